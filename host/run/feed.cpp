// SPDX-License-Identifier: MIT
#include "run/feed.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "card/frame.h"

namespace cpstep::run {

namespace {

double number(std::string_view s, std::string_view event, std::string_view what) {
  double v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v))
    throw std::invalid_argument(fmt::format("--feed: \"{}\": {} \"{}\" is not a number", event, what, s));
  return v;
}

}  // namespace

uint32_t override_q14(double pct) {
  if (!(pct >= 0 && pct <= 200))
    throw std::invalid_argument(fmt::format("an override of {} % is outside 0..200 %", pct));
  return uint32_t(std::lround(pct / 100.0 * card::urgent::kOverrideOne));
}

std::vector<FeedEvent> parse_feed_events(std::string_view text) {
  std::vector<FeedEvent> out;
  while (!text.empty()) {
    const size_t comma = text.find(',');
    const std::string_view ev = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    const size_t colon = ev.find(':');
    if (colon == std::string_view::npos)
      throw std::invalid_argument(fmt::format("--feed: \"{}\": expected TIME:hold, TIME:resume or TIME:override=PCT", ev));
    FeedEvent e;
    e.at_s = number(ev.substr(0, colon), ev, "the time");
    if (e.at_s < 0) throw std::invalid_argument(fmt::format("--feed: \"{}\": a time before START", ev));
    if (!out.empty() && e.at_s < out.back().at_s)
      throw std::invalid_argument(fmt::format("--feed: \"{}\": the events must be in time order", ev));
    const std::string_view what = ev.substr(colon + 1);
    if (what == "hold") {
      e.kind = FeedEvent::Kind::hold;
    } else if (what == "resume") {
      e.kind = FeedEvent::Kind::resume;
    } else if (what.starts_with("override=")) {
      e.kind = FeedEvent::Kind::override_pct;
      e.pct = number(what.substr(9), ev, "the override");
      try {
        (void)override_q14(e.pct);
      } catch (const std::invalid_argument& x) {
        throw std::invalid_argument(fmt::format("--feed: \"{}\": {}", ev, x.what()));
      }
    } else {
      throw std::invalid_argument(fmt::format("--feed: \"{}\": \"{}\" is not hold, resume or override=PCT", ev, what));
    }
    out.push_back(e);
  }
  return out;
}

uint32_t feed_word(const FeedEvent& e, bool held) {
  switch (e.kind) {
    case FeedEvent::Kind::hold: return card::urgent::hold;
    case FeedEvent::Kind::resume: return card::urgent::resume;
    case FeedEvent::Kind::override_pct: return card::urgent::override_to(override_q14(e.pct));
    case FeedEvent::Kind::toggle: return held ? card::urgent::resume : card::urgent::hold;
  }
  return 0;
}

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
#include "run/feed_driver.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "card/frame.h"

namespace cpstep::run {

card::ClientOptions feed_waits(card::ClientOptions client, bool events, bool toggle) {
  const double wait = events ? 0.005 : toggle ? 0.05 : 0.0;
  if (wait > 0) client.keepalive_s = client.keepalive_s > 0 ? std::min(client.keepalive_s, wait) : wait;
  return client;
}

void send_with_feed(card::CardClient& client, WordSource& words, const FeedPlan& plan,
                    const card::CardClient::KeepWaiting& keep_waiting,
                    const std::function<std::optional<double>()>& since_start_s, FeedOutcome& out) {
  out = {};
  bool held = false, gave_up = false;
  size_t next = 0;
  int toggles = 0;
  const auto send = [&](const FeedEvent& e, std::string what) {
    const uint32_t word = feed_word(e, held);
    if (!client.urgent(word, keep_waiting)) return;
    if (word & card::urgent::hold) held = true;
    if (word & card::urgent::resume) held = false;
    if (e.kind == FeedEvent::Kind::toggle) what = held ? "hold" : "resume";
    out.applied.push_back({e, since_start_s().value_or(0.0), std::move(what)});
  };
  if (plan.override_pct != 100)
    send({0, FeedEvent::Kind::override_pct, plan.override_pct}, fmt::format("override {} %", plan.override_pct));
  const auto due = [&] {
    if (plan.toggle && plan.toggle()) ++toggles;
    if (toggles > 0) return true;
    if (next >= plan.events.size()) return false;
    const std::optional<double> t = since_start_s();
    return t && *t >= plan.events[next].at_s;
  };
  const auto apply = [&] {
    if (toggles > 0) {
      --toggles;
      send({0, FeedEvent::Kind::toggle, 100}, "toggle");
      return;
    }
    const FeedEvent& e = plan.events[next++];
    send(e, e.kind == FeedEvent::Kind::hold     ? std::string("hold")
            : e.kind == FeedEvent::Kind::resume ? std::string("resume")
                                                : fmt::format("override {} %", e.pct));
  };
  // A wait also gives up when a feed event falls due: it is sent, and the words and
  // the wait go on. (keep_waiting giving up ends it all.)
  const bool feeding = plan.any();
  const auto keep = [&](const card::Reply& r) {
    if (!keep_waiting(r)) {
      gave_up = true;
      return false;
    }
    return !(feeding && due());
  };
  // Words a window at a time (whole commands; the client batches within it).
  constexpr size_t kWindow = size_t{1} << 16;
  for (;;) {
    while (!words.exhausted()) {
      const std::span<const uint32_t> w = words.window(kWindow);
      const size_t n = client.send(w, keep);
      words.consume(n);
      out.sent += n;
      if (n < w.size()) break;
    }
    if (gave_up) break;
    if (feeding && due()) {
      apply();
      continue;
    }
    if (!words.exhausted()) break;
    if (client.wait_until_stopped(keep)) {
      out.stopped = true;
      break;
    }
    if (gave_up || !(feeding && due())) break;
    apply();
  }
}

std::string stop_short(card::CardClient& client, bool feed, const card::CardClient::KeepWaiting& keep_waiting,
                       const std::function<std::optional<double>()>& since_start_s,
                       std::vector<FeedApplied>& applied) {
  if (!feed) return "the card, which has no feed hold, runs what it holds";
  if (!client.urgent(card::urgent::hold, keep_waiting)) return "the host gave up before the card took HOLD";
  const double at = since_start_s().value_or(0.0);
  applied.push_back({{at, FeedEvent::Kind::hold, 100}, at, "hold (the job stopped short)"});
  // Until the motion stands (held, its ramp done) or the run is off.
  for (;;) {
    const card::Status st = card::decode_status(client.last().status);
    if (!st.running || (st.held && !st.feed_ramping)) break;
    if (keep_waiting && !keep_waiting(client.last())) return "the card, held, did not stand before the host gave up";
    client.link().wait(client.options().poll_interval_s);
    client.poll();
  }
  if (!client.urgent(card::urgent::flush, keep_waiting) || !client.urgent(card::urgent::resume, keep_waiting))
    return "the card held to a stand; the host gave up before FLUSH and RESUME";
  return "the card held to a stand on its feed ramp, then FLUSH and RESUME";
}

}  // namespace cpstep::run

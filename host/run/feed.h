// SPDX-License-Identifier: MIT
// Feed hold, resume and override during a run (docs/CORE.md "Feed hold and
// override", docs/HOST.md): the events `cpstep run --feed` schedules, the URGENT
// words that carry them, and what a run did with them.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace cpstep::run {

struct FeedEvent {
  enum class Kind { hold, resume, override_pct, toggle };
  double at_s = 0;  // seconds from START (the card's clock)
  Kind kind = Kind::hold;
  double pct = 100;  // override_pct: 0..200
};

// "T:hold", "T:resume", "T:override=P" separated by commas, T seconds from START in
// increasing order, P a percentage 0..200 (e.g. "2.5:hold,4:resume,6:override=50").
// Empty text: no events. Throws std::invalid_argument naming the event at fault.
std::vector<FeedEvent> parse_feed_events(std::string_view text);

// The override as the card takes it: Q2.14, 0x4000 = 100 %. Throws
// std::invalid_argument outside 0..200 %.
uint32_t override_q14(double pct);

// The URGENT word of an event (a toggle: HOLD when not held, else RESUME).
uint32_t feed_word(const FeedEvent& e, bool held);

// An event a run sent, and when the card took it.
struct FeedApplied {
  FeedEvent event;
  double taken_s = 0;  // seconds from START on the card's clock when the URGENT frame was accepted
  std::string what;    // "hold", "resume", "override 50 %"
};

}  // namespace cpstep::run

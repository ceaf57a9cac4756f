// SPDX-License-Identifier: MIT
// Feed hold, resume and override on the card (issue 12, docs/CORE.md "Feed hold and
// override"): the move timer runs on scaled time, so every move keeps its place on
// the path and only time stretches. The small card (2 axes) behind its pins, the
// Verilated RTL and the fast engine in lockstep every cycle (sim::TwinCardDut),
// driven by the host's client: HOLD at random cycles mid-job, the motion slowing
// to a stand (the intervals between move events only growing), standing with the
// counters equal to the pins' steps, RESUME back to the planned intervals, the
// job's end exact and no runt pulse; OVERRIDE stretching or shrinking every
// interval by its factor. Expected values come from the job's own segments and
// the ramp's configuration, measured on the pins.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "card/card_client.h"
#include "card/frame.h"
#include "card/protocol.h"
#include "small_card_job.h"

namespace cpstep::tb {
namespace {

using namespace small_card;

// (Replies are copied: CardClient::poll() returns a reference to its latest reply.)

// A ramp tick every 4 clocks: a time constant of 4,096 clocks, a hold from 1 to its
// stand in 16.9 of them (about 69,000 clocks, some 58 moves of 1,200).
constexpr uint32_t kTick = 4;

std::vector<uint32_t> feed_setup(const Job& j) {
  std::vector<uint32_t> w = j.setup;
  card::encode_config(0, card::ConfigField::feed_tick, kTick, w);
  return w;
}

// Idles until the reply's status says the feed settled (held: standing; resumed: on
// the override), at most `cycles`, sending the job's segments from `w` on as they fit.
card::Reply wait_settled(card::CardClient& c, Card& card, const Job& j, size_t& w, uint64_t cycles) {
  for (uint64_t waited = 0; waited < cycles; waited += 2000) {
    w = send_what_fits(c, j, w);
    const card::Reply r = c.poll();
    if (!card::decode_status(r.status).feed_ramping) return r;
    card.spi.idle(2000);
  }
  return c.poll();
}

TEST(Feed, HoldAndResumeAtRandomCyclesKeepThePathAndItsTimes) {
  std::mt19937_64 rng(21);
  const uint32_t delay = 1200;
  for (int trial = 0; trial < 4; ++trial) {
    SCOPED_TRACE(trial);
    const Job j = make_job(80, delay);
    Card card;
    card::CardClient c(card.link, card.options());
    const std::vector<uint32_t> setup = feed_setup(j);
    ASSERT_EQ(c.send(setup), setup.size());
    ASSERT_TRUE(c.urgent(card::urgent::start));
    size_t w = 0;
    unsigned holds = 0;
    // The move events' cycles where a hold began, stood and was resumed.
    std::vector<std::array<size_t, 2>> spans;  // [first move after HOLD, first move after RESUME]
    while (w < j.segments.size() || card::decode_status(c.poll().status).running) {
      w = send_what_fits(c, j, w);
      card.spi.idle(std::uniform_int_distribution<uint64_t>(100, 15000)(rng));
      const card::Reply now = c.poll();
      if (holds < 3 && card::decode_status(now.status).running && now.moves + 40 < j.moves) {
        const size_t before = card.move_cycles.size();
        ASSERT_TRUE(c.urgent(card::urgent::hold));
        ++holds;
        const card::Reply held = wait_settled(c, card, j, w, 400000);
        const card::Status st = card::decode_status(held.status);
        ASSERT_TRUE(st.held && !st.feed_ramping) << "the hold comes to a stand";
        EXPECT_TRUE(st.running) << "held, the run stays on";
        card.spi.idle(30000);
        const card::Reply still = c.poll();
        EXPECT_EQ(still.moves, held.moves) << "no move while held";
        EXPECT_EQ(still.positions, (std::vector<int32_t>{int32_t(card.pins[0]), int32_t(card.pins[1])}))
            << "the pins' steps are the counters";
        EXPECT_LT(card.last_step, card.cs_rose) << "no STEP edge while standing";
        const size_t stood = card.move_cycles.size();
        ASSERT_TRUE(c.urgent(card::urgent::resume));
        const card::Reply back = wait_settled(c, card, j, w, 400000);
        EXPECT_FALSE(card::decode_status(back.status).feed_ramping);
        EXPECT_FALSE(card::decode_status(back.status).held);
        spans.push_back({before, stood});
      }
    }
    EXPECT_GE(holds, 1u);
    expect_job_done(c, card, j);
    EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
    // Every move event fired on the path in order (the counters say so); in time,
    // a hold only stretches intervals: from the HOLD on, each interval is at least
    // the one before (the scale falls; one clock of the fraction's rounding), and
    // none is shorter than planned; the intervals after the ramp back are the plan's.
    const std::vector<uint64_t>& m = card.move_cycles;
    ASSERT_EQ(m.size(), j.moves);
    for (const auto& [from, stood] : spans) {
      for (size_t k = from + 1; k < stood && k < m.size(); ++k) {
        EXPECT_GE(m[k] - m[k - 1] + 1, m[k - 1] - (k >= 2 ? m[k - 2] : m[k - 1] - delay))
            << "move " << k << ": the intervals only grow while the hold ramps down";
        EXPECT_GE(m[k] - m[k - 1], delay) << "move " << k;
      }
    }
    for (size_t k = 1; k < m.size(); ++k) EXPECT_GE(m[k] - m[k - 1], delay) << "never faster than planned";
    EXPECT_EQ(m.back() - m[m.size() - 2], delay) << "back on the plan's intervals at the end";
  }
}

// OVERRIDE 50 %: every interval doubles; 200 %: halves (exactly, the fraction being
// a power of two); back to 100 %: the plan's. The ramp between them keeps every
// interval between the two.
TEST(Feed, OverrideScalesEveryInterval) {
  // (At 200 % a segment of 8 moves takes 8,000 clocks: the client keeps up.)
  const uint32_t delay = 2000;
  const Job j = make_job(60, delay);
  Card card;
  card::CardClient c(card.link, card.options());
  const std::vector<uint32_t> setup = feed_setup(j);
  ASSERT_EQ(c.send(setup), setup.size());
  // 50 % before START: the scale ramps there (the ramp runs whether the run is on or not).
  ASSERT_TRUE(c.urgent(card::urgent::override_to(card::urgent::kOverrideOne / 2)));
  size_t w = 0;
  ASSERT_FALSE(card::decode_status(wait_settled(c, card, j, w, 400000).status).feed_ramping);
  ASSERT_TRUE(c.urgent(card::urgent::start));
  int phase = 0;  // 0: 50 %, 1: 200 %, 2: 100 %
  std::array<size_t, 3> settled_at{};
  while (w < j.segments.size() || card::decode_status(c.poll().status).running) {
    w = send_what_fits(c, j, w);
    card.spi.idle(5000);
    const card::Reply now = c.poll();
    if (phase < 2 && now.moves > (phase + 1) * j.moves / 3) {
      ++phase;
      ASSERT_TRUE(c.urgent(card::urgent::override_to(phase == 1 ? 2 * card::urgent::kOverrideOne
                                                                 : card::urgent::kOverrideOne)));
      ASSERT_FALSE(card::decode_status(wait_settled(c, card, j, w, 400000).status).feed_ramping);
      settled_at[size_t(phase)] = card.move_cycles.size() + 1;
    }
  }
  expect_job_done(c, card, j);
  const std::vector<uint64_t>& m = card.move_cycles;
  ASSERT_EQ(m.size(), j.moves);
  // The first third at 50 % (set before START): every interval 2·delay.
  for (size_t k = 1; k < j.moves / 3 - 2; ++k) EXPECT_EQ(m[k] - m[k - 1], 2 * delay) << k;
  ASSERT_GT(settled_at[2], settled_at[1]);
  for (size_t k = settled_at[1] + 1; k + 1 < std::min<size_t>(m.size(), 2 * j.moves / 3); ++k)
    EXPECT_EQ(m[k] - m[k - 1], delay / 2) << k;
  for (size_t k = settled_at[2] + 1; k < m.size(); ++k) EXPECT_EQ(m[k] - m[k - 1], delay) << k;
  EXPECT_GE(card.shortest_high, kStepHigh);
}

}  // namespace
}  // namespace cpstep::tb

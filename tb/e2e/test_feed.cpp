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

// A ramp tick every 4 clocks: a time constant τ of 4,096 clocks, a hold from 1 to its
// stand in 16.9 of them (about 69,000 clocks, 58 planned intervals of 1,200; the
// scaled time meanwhile is 2·τ, some 7 moves).
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
        EXPECT_EQ(still.positions, card.steps())
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

// Faults while held (docs/CORE.md "Validation: whole segments or nothing" and
// "Feed hold and override"): the hold is not a fault and a fault does not end it.
// make_job's geometry: where the job stands after its first `s` segments.
std::vector<int32_t> after_segments(unsigned s) {
  int32_t x = 0, y = 0;
  for (unsigned i = 0; i < s; ++i) {
    x += 8;
    y += (i / 3) % 2 == 0 ? int32_t(2 + i % 5) : -int32_t(2 + i % 5);
  }
  return {x, y};
}

// A segment the card refuses (v_y = 9 > U = 8: SEG_V_GT_U, code 2).
std::vector<uint32_t> bad_segment() {
  card::WireSegment w;
  w.u = 8;
  w.v = {8, 9};
  w.dir_positive = {true, true};
  w.chunks = {{1200, 8, 0, 0}};
  std::vector<uint32_t> out;
  card::encode_segment(w, out);
  return out;
}

// The run off where the hold stood it (`held`): nothing queued, no move since, the
// counters the pins'.
void expect_off_at_the_stand(const card::Reply& r, const card::Reply& held, const Card& card) {
  EXPECT_FALSE(card::decode_status(r.status).running);
  EXPECT_EQ(r.status >> 16, 0u) << "no segment and no chunk queued: flushed";
  EXPECT_EQ(r.moves, held.moves);
  EXPECT_EQ(r.positions, held.positions);
  EXPECT_EQ(r.positions, card.steps());
}

std::vector<uint32_t> clear_word() {
  std::vector<uint32_t> w;
  card::encode_control(false, false, true, w);
  return w;
}

// The job (all its words sent: they fit the buffer and queues) started; once 12
// moves are made, HOLD, nothing more sent: the reply at the stand. (The hold from
// 100 % makes some 2·τ = 8,192 clocks of scaled time, a handful of moves; the queues
// keep room, so a word sent now reaches the parser.)
card::Reply run_then_hold(card::CardClient& c, Card& card, const Job& j) {
  const std::vector<uint32_t> setup = feed_setup(j);
  EXPECT_EQ(c.send(setup), setup.size());
  EXPECT_TRUE(c.urgent(card::urgent::start));
  EXPECT_EQ(c.send(j.segments), j.segments.size());
  for (int i = 0; i < 100 && c.poll().moves < 12; ++i) card.spi.idle(2000);
  EXPECT_TRUE(c.urgent(card::urgent::hold));
  size_t all_sent = j.segments.size();
  const card::Reply held = wait_settled(c, card, j, all_sent, 400000);
  const card::Status st = card::decode_status(held.status);
  EXPECT_TRUE(st.held && !st.feed_ramping && st.running) << "held to a stand, the run on";
  EXPECT_GE(held.moves, 12u);
  EXPECT_LT(held.moves + 16, j.moves) << "the job is far from its end";
  return held;
}

// Each test: the card held to a stand mid-job (`held`), `next` the job after.
class FeedHeld : public ::testing::Test {
 protected:
  void SetUp() override {
    held = run_then_hold(c, card, j);
    ASSERT_FALSE(HasFailure()) << "no stand to start from";
  }
  const Job j = make_job(6, 1200), next = make_job(3, 500);
  Card card;
  card::CardClient c{card.link, card.options()};
  card::Reply held;
};

// A segment refused while held: the fault latches at once, but its flush waits for
// the segment under way, which stands: the run stays on and held, nothing moves, the
// queues keep their segments, and neither CLEAR nor ACK clears the fault. RESUME: that
// segment completes on the path (and no other), then the queues are flushed; CLEAR
// clears; the next job runs from there exactly.
TEST_F(FeedHeld, AFaultWhileHeldWaitsForTheSegmentUnderWayToComplete) {
  const std::vector<uint32_t> bad = bad_segment();
  ASSERT_EQ(c.send(bad), bad.size());
  card.spi.idle(2000);
  const card::Reply refused = c.poll();
  card::Status st = card::decode_status(refused.status);
  EXPECT_TRUE(st.fault);
  EXPECT_EQ(st.err_code, 2u) << "SEG_V_GT_U";
  EXPECT_TRUE(st.running && st.held) << "the segment under way has not ended: no flush yet";
  EXPECT_GE(st.segments_queued, 1u) << "the queued segments wait for the flush";
  EXPECT_EQ(refused.moves, held.moves);

  ASSERT_EQ(c.send(clear_word()), 1u);
  ASSERT_TRUE(c.urgent(card::urgent::ack));
  const uint64_t stood_from = card.twin.cycle();
  card.spi.idle(30000);
  const card::Reply still = c.poll();
  st = card::decode_status(still.status);
  EXPECT_TRUE(st.fault && st.err_code == 2u) << "CLEAR and ACK wait for the flush: " << st.err_code;
  EXPECT_TRUE(st.running && st.held);
  EXPECT_EQ(still.moves, held.moves) << "no move while held";
  EXPECT_LT(card.last_step, stood_from) << "no STEP edge while standing";
  EXPECT_EQ(still.positions, card.steps());

  ASSERT_TRUE(c.urgent(card::urgent::resume));
  ASSERT_TRUE(c.wait_until_stopped());
  const card::Reply ended = c.poll();
  st = card::decode_status(ended.status);
  EXPECT_TRUE(st.fault && st.err_code == 2u) << st.err_code;
  EXPECT_FALSE(st.running);
  EXPECT_FALSE(st.held);
  EXPECT_EQ(ended.status >> 16, 0u) << "no segment and no chunk queued: flushed";
  // The segment under way at the stand, completed: the first segment boundary after
  // the held count (the next segment is loaded at a boundary, so one exactly there
  // runs it whole).
  EXPECT_EQ(ended.moves, (held.moves / 8 + 1) * 8);
  EXPECT_EQ(ended.positions, after_segments(ended.moves / 8)) << "the segment completed on the path";
  EXPECT_EQ(ended.positions, card.steps());

  ASSERT_EQ(c.send(clear_word()), 1u);
  card.spi.idle(2000);
  const card::Reply cleared = c.poll();
  EXPECT_FALSE(card::decode_status(cleared.status).fault) << "CLEAR after the flush clears";
  expect_next_job_runs_exactly(c, card, next, cleared);
  EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
}

// STOP while held, a fault latched: the run is off, so the flush happens at once
// (the segment under way dropped where it stood) and CLEAR clears. The hold outlives
// STOP, the fault and CLEAR: a new job STARTed while still held does not move until
// RESUME, then runs from where the card stood, exactly.
TEST_F(FeedHeld, StopWhileHeldFlushesAtOnceAndTheHoldStays) {
  const std::vector<uint32_t> bad = bad_segment();
  ASSERT_EQ(c.send(bad), bad.size());
  ASSERT_TRUE(c.urgent(card::urgent::stop));
  card.spi.idle(2000);
  const card::Reply stopped = c.poll();
  card::Status st = card::decode_status(stopped.status);
  EXPECT_TRUE(st.fault && st.err_code == 2u) << st.err_code;
  EXPECT_TRUE(st.held);
  expect_off_at_the_stand(stopped, held, card);  // flushed at once: no segment under way

  ASSERT_EQ(c.send(clear_word()), 1u);
  card.spi.idle(2000);
  EXPECT_FALSE(card::decode_status(c.poll().status).fault) << "CLEAR clears";
  ASSERT_EQ(c.send(next.segments), next.segments.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  const uint64_t started = card.twin.cycle();
  card.spi.idle(30000);
  const card::Reply waiting = c.poll();
  st = card::decode_status(waiting.status);
  EXPECT_TRUE(st.running && st.held) << "started, still held";
  EXPECT_EQ(waiting.moves, held.moves) << "no move while held";
  EXPECT_LT(card.last_step, started);

  ASSERT_TRUE(c.urgent(card::urgent::resume));
  ASSERT_TRUE(c.wait_until_stopped());
  const card::Reply r = c.poll();
  EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault";
  EXPECT_EQ(r.moves, held.moves + next.moves);
  const std::vector<int32_t> end{held.positions[0] + next.x, held.positions[1] + next.y};
  EXPECT_EQ(r.positions, end);
  EXPECT_EQ(card.steps(), end);
  EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
}

// E-stop while held: the run stops at once, drivers off, the queues flushed, ESTOP
// latched; ACK does nothing while the input is on, clears once it is released. The
// hold stays; RESUME and the next job runs from the stand exactly.
TEST_F(FeedHeld, EstopWhileHeldLatchesAndAckClearsOnceReleased) {
  const uint64_t pressed = card.twin.cycle();
  card.spi.set_estop(true);
  card.spi.idle(2000);
  const card::Reply stopped = c.poll();
  card::Status st = card::decode_status(stopped.status);
  EXPECT_TRUE(st.fault && st.err_code == 10u) << st.err_code;
  EXPECT_FALSE(st.drivers_enabled);
  EXPECT_GE(card.enable_fell, pressed) << "the ENABLE pin fell";
  expect_off_at_the_stand(stopped, held, card);

  ASSERT_TRUE(c.urgent(card::urgent::ack));
  card.spi.idle(2000);
  EXPECT_EQ(card::decode_status(c.poll().status).err_code, 10u) << "ACK under E-stop does nothing";
  card.spi.set_estop(false);
  card.spi.idle(2000);
  ASSERT_EQ(c.send(clear_word()), 1u);
  card.spi.idle(2000);
  EXPECT_EQ(card::decode_status(c.poll().status).err_code, 10u) << "CLEAR does not clear an E-stop";
  ASSERT_TRUE(c.urgent(card::urgent::ack));
  card.spi.idle(2000);
  const card::Reply acked = c.poll();
  st = card::decode_status(acked.status);
  EXPECT_FALSE(st.fault) << st.err_code;
  EXPECT_TRUE(st.held) << "the hold outlives the E-stop";
  ASSERT_TRUE(c.urgent(card::urgent::resume));
  card.spi.idle(2000);
  std::vector<uint32_t> drivers;
  card::encode_drivers(true, drivers);
  ASSERT_EQ(c.send(drivers), drivers.size());
  const card::Reply resumed = c.poll();
  EXPECT_EQ(resumed.moves, held.moves);
  EXPECT_EQ(resumed.positions, held.positions) << "E-stop, ACK and RESUME moved nothing";
  expect_next_job_runs_exactly(c, card, next, resumed);
  EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
}

}  // namespace
}  // namespace cpstep::tb

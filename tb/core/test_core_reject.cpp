// SPDX-License-Identifier: MIT
// cp_core bad input (docs/CORE.md "Validation", codes 1–8 and 12–15): the bad
// command makes no move, its code latches, nothing after it runs until CLEAR, and
// what came before it behaves as the doc says — a segment already running completes,
// queued ones are flushed. RTL vs model in lockstep, the pin checker on.
#include <gtest/gtest.h>

#include <functional>
#include <numeric>
#include <string>

#include "core/core_bench.h"
#include "core/core_reject_cases.h"
#include "core/core_small.h"
#include "core/core_validated.h"

namespace cpstep::tb {
namespace {

using Core = ValidatedCore;
using Harness = CoreHarness<Core>;

void expect_runs_after_clear(Harness& h, const std::string& where) {
  h.expecting = true;
  h.control(false, false, true);
  ASSERT_FALSE(h.status().fault) << where << ": CLEAR did not clear";
  JobShape shape;
  shape.max_moves = 200;
  h.play(h.gen.job(2, shape));
  h.expect_consistent(where + ", the job after CLEAR");
}

// One segment of 400 moves, 25 clocks apart (400, -130, 0, 57), STARTed: true once it
// runs — its patterns are built (one axis after the other) and it has moved.
bool start_running(Harness& h) {
  card::WireSegment a;
  if (!h.gen.from_deltas({400, -130, 0, 57}, a)) return false;
  a.chunks = {{25, 400, 0}};
  h.segment(a);
  h.control(true, false, false);
  return h.wait_for([](const model::CpCoreOut& o) { return o.position[0] > 8; }, 5000);
}

// Before START: a good segment, the bad input, a good segment, START. The fault flushes
// the queue at once; START is refused; no STEP pulse at all.
TEST(CoreReject, BeforeStartNothingRuns) {
  for (const BadInput& bad : bad_inputs(Core::model_params())) {
    if (bad.only_while_running) continue;
    Harness h(std::string("reject_queued_") + bad.name, 1);
    const std::string where = std::string(bad.name) + " (queued)";
    JobShape shape;
    shape.max_moves = 100;
    h.segment(h.gen.segment(shape, false), false);
    h.send(bad.words());
    h.segment(h.gen.segment(shape, true), false);
    ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.fault; }, 5000))
        << where << ": no fault latched";
    h.control(true, false, false);
    h.idle(300);
    EXPECT_EQ(h.chk.moves(), 0u) << where;
    expect_stopped_with(h, bad.code, where);
    expect_runs_after_clear(h, where);
    if (HasFailure()) return;
  }
}

// While a segment runs: it completes exactly; the bad input, a good segment after it
// and a second error make no move; the first code stays.
TEST(CoreReject, WhileRunningTheRunningSegmentCompletes) {
  for (const BadInput& bad : bad_inputs(Core::model_params())) {
    Harness h(std::string("reject_running_") + bad.name, 2);
    const std::string where = std::string(bad.name) + " (running)";
    ASSERT_TRUE(start_running(h)) << where << ": the segment did not start";
    h.expecting = false;
    h.send(bad.words());
    // (a pattern is refused during its build, W cycles later)
    ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.fault; }, 5000))
        << where << ": no fault latched";
    JobShape shape;
    shape.max_moves = 100;
    h.segment(h.gen.segment(shape, true), false);
    h.send({0xE0000000u});  // another error: the first code stays
    h.finish();
    h.idle(300);
    EXPECT_EQ(h.chk.segments_done(), 1u) << where << ": the running segment did not complete";
    EXPECT_EQ(h.chk.position(0), 400) << where;
    EXPECT_EQ(h.chk.position(1), -130) << where;
    expect_stopped_with(h, bad.code_while_running(), where);
    expect_runs_after_clear(h, where);
    if (HasFailure()) return;
  }
}

// A pattern longer than W as the first segment of a run: it is loaded for running
// before its build refuses it; the run stops without a move (and does not hang).
TEST(CoreReject, PatternAboveWAsTheRunningSegmentStopsTheRun) {
  Harness h("reject_pattern_first", 3);
  const auto p = Core::model_params();
  h.control(true, false, false);
  h.send(words_of(p.w + 1, 0, {p.w + 1, 1, 0, 0}, {{5, uint16_t(p.w + 1), 0}}));
  ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.fault; }, 5000)) << "no fault";
  h.idle(50);
  EXPECT_EQ(h.chk.moves(), 0u);
  h.stretch_slack = 1;  // its first move was due, and counted late, while it built
  expect_stopped_with(h, 8, "pattern above W, first segment");
  expect_runs_after_clear(h, "pattern above W, first segment");
}

// A fault raised while a segment is being built (a pattern above W: the build stops at
// that axis, leaving the later axes' words queued) while another segment runs: its flush
// waits for the running segment to end, and until then CLEAR and ACK leave the fault
// (docs/CORE.md "Validation"). A CLEAR that dropped it would let the builder take the
// abandoned segment's next word as a header (finding 20, docs/RELIABILITY.md). The wait
// ends with the segment's last move, or with ABORT, or the out-of-band STOP or FLUSH.
TEST(CoreReject, ClearWaitsForTheFlushOfAFaultRaisedMidBuild) {
  enum class End { segment, abort, stop, flush };
  const std::pair<End, const char*> ends[] = {
      {End::segment, "segment"}, {End::abort, "abort"}, {End::stop, "stop"}, {End::flush, "flush"}};
  for (const auto& [end, name] : ends) {
    const std::string where = std::string("ended by ") + name;
    Harness h(std::string("reject_clear_pending_") + name, 6);
    const auto p = Core::model_params();
    ASSERT_TRUE(start_running(h)) << where << ": the segment did not start";
    h.expecting = false;
    h.send(words_of(p.w + 1, 0, {p.w + 1, 1, 7, 3}, {{5, uint16_t(p.w + 1), 0}}));
    ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.fault; }, 5000))
        << where << ": no fault latched";
    h.control(false, false, true);
    card::Status st = h.status();
    EXPECT_TRUE(st.fault) << where << ": CLEAR dropped a fault whose flush was pending";
    EXPECT_EQ(st.err_code, 8u) << where;
    EXPECT_TRUE(st.running) << where << ": the segment under way should still run";
    h.ack();
    st = h.status();
    EXPECT_TRUE(st.fault) << where << ": ACK dropped a fault whose flush was pending";
    EXPECT_EQ(st.err_code, 8u) << where;
    if (end == End::segment) {
      h.finish();
      h.idle(300);
      EXPECT_EQ(h.chk.segments_done(), 1u) << where << ": the running segment did not complete";
      EXPECT_EQ(h.chk.position(0), 400) << where;
      EXPECT_EQ(h.chk.position(1), -130) << where;
      EXPECT_EQ(h.chk.position(3), 57) << where;
    } else {
      // Each flushes at once (ABORT's own code is not latched: the first fault's stays).
      if (end == End::abort) {
        h.control(false, true, false);
      } else {
        model::CpCoreIn in;
        (end == End::stop ? in.ctl_stop : in.ctl_flush) = true;
        h.drv.step(in);
      }
      h.chk.abandon();
      h.idle(300);
      h.stretch_slack = 1;  // a move counted late may have been cut
      EXPECT_LT(h.chk.position(0), 400) << where << ": the segment was not cut";
    }
    expect_stopped_with(h, 8, where);
    // Flushed: CLEAR clears, and a job after it runs exactly (its segments built from
    // their own words).
    expect_runs_after_clear(h, where);
    if (HasFailure()) return;
  }
}

// The limits themselves are accepted: U/gcd = W, k = KMAX, 2^CAW chunks (these run),
// U = UMAX and a last delay of 2^32-1 (queued, then aborted).
TEST(CoreReject, LimitsAreAccepted) {
  Harness h("reject_limits", 4);
  const auto p = Core::model_params();
  card::WireSegment s;
  ASSERT_TRUE(h.gen.from_deltas({int64_t(p.w), -1, int64_t(p.w), 0}, s));
  ASSERT_EQ(s.u / std::gcd(s.u, s.v[1]), p.w);
  s.chunks = {{1, uint16_t(p.w), 0}};
  h.segment(s);
  ASSERT_TRUE(h.gen.from_deltas({int64_t(1) << p.kmax, -(int64_t(1) << p.kmax), 0, 0}, s));
  ASSERT_EQ(s.k, p.kmax);
  s.chunks = {{3, uint16_t(1u << p.kmax), 0}};
  h.segment(s);
  const unsigned queue = 1u << p.caw;  // 2^CAW chunks: one move each
  ASSERT_TRUE(h.gen.from_deltas({int64_t(queue), 0, 0, 13}, s));
  s.chunks.assign(queue, card::WireChunk{2, 1, 0});
  s.end = true;
  h.segment(s);
  h.control(true, false, false);
  h.finish();
  h.expect_consistent("limits");
  // Not run: U = UMAX, and a chunk whose last delay is 2^32 - 1.
  h.expecting = false;
  std::vector<card::WireChunk> umax_chunks(p.umax / 65535, card::WireChunk{1, 65535, 0});
  if (p.umax % 65535) umax_chunks.push_back({1, uint16_t(p.umax % 65535), 0});
  h.send(words_of(p.umax, 0, {p.umax, 0, p.umax / 5, 0}, umax_chunks));  // U/g = 5
  h.send(words_of(2, 0, {2, 1, 0, 0}, {{0xFFFFFFFEu, 2, 1}}));
  h.idle(100);
  const card::Status st = h.status();
  EXPECT_FALSE(st.fault) << "code " << st.err_code;
  EXPECT_EQ(st.segments_queued, 2u);
  h.control(false, true, false);
  h.control(false, false, true);
  EXPECT_EQ(h.status().segments_queued, 0u);
}

}  // namespace
}  // namespace cpstep::tb

namespace cpstep::tb {
namespace {

// add2 at its limits, accepted (queued, not run): a last delay of exactly 2^32 - 1;
// 1 + 2·65534·65533/2 = 4,294,639,623 and 2^32 - 1 - 2·65534·65533/2 = 327,673 over
// 65535 moves; increments 4, 2, 0 (ending at 0, no change of sign); add2 on a
// chunk of one and of two moves (no delay depends on it).
TEST(CoreReject, Add2LimitsAreAccepted) {
  Harness h("reject_add2_limits", 5);
  h.expecting = false;
  h.send(words_of(3, 0, {3, 1, 0, 0}, {{0xFFFFFFFCu, 3, 1, 1}}));
  h.send(words_of(65535, 0, {65535, 0, 0, 0}, {{1, 65535, 0, 2}}));
  h.send(words_of(65535, 0, {65535, 0, 65535, 0}, {{0xFFFFFFFFu, 65535, 0, -2}}));
  h.send(words_of(7, 0, {7, 0, 3, 0}, {{20, 4, 4, -2}, {5, 1, -9, 32767}, {6, 2, 3, -32768}}));
  h.idle(100);
  const card::Status st = h.status();
  EXPECT_FALSE(st.fault) << "code " << st.err_code;
  EXPECT_EQ(st.segments_queued, 4u);
  EXPECT_EQ(st.chunks_queued, 6u - 1u) << "(the timer holds the first chunk)";
  h.control(false, true, false);
  h.control(false, false, true);
  EXPECT_EQ(h.status().segments_queued, 0u);
}

// A pulse timing value must fit the TW-bit field; it is refused, not truncated.
TEST(CoreReject, TimingValueWiderThanTheFieldOnASmallCore) {
  ASSERT_EQ(sim::CoreSmall::model_params().tw, 8u);
  Lockstep<sim::CoreSmall> ls("reject_tw");
  sim::CoreDriver<Lockstep<sim::CoreSmall>> drv(ls);
  drv.reset();
  drv.send(config_word(0, 0, 255));  // 255 fits 8 bits
  drv.idle(2);
  EXPECT_FALSE(drv.last().fault);
  for (const unsigned field : {0u, 1u, 2u, 3u}) {
    drv.send(config_word(1, field, 256));
    drv.idle(2);
    EXPECT_TRUE(drv.last().fault) << "field " << field;
    EXPECT_EQ(drv.last().err_code, uint32_t(model::CoreError::config_value)) << "field " << field;
    std::vector<uint32_t> clear;
    card::encode_control(false, false, true, clear);
    drv.send(clear);
    drv.idle(2);
    EXPECT_FALSE(drv.last().fault);
  }
}

}  // namespace
}  // namespace cpstep::tb

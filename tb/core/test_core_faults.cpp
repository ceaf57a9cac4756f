// SPDX-License-Identifier: MIT
// cp_core faults and bad input (docs/CORE.md "Faults", "Validation", SPEC §4), RTL vs
// model in lockstep with the pin checker on; each test also states what must hold
// from the pins and the registers alone.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/core_bench.h"
#include "core/core_small.h"
#include "core/core_validated.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

using Core = ValidatedCore;
using Harness = CoreHarness<Core>;

constexpr uint32_t kEstop = 10, kAbort = 11, kUnderrun = 9;

card::WireSegment seg_of(const std::vector<int64_t>& d, std::vector<card::WireChunk> chunks, bool end,
                         const model::CpCoreParams& p = Core::model_params()) {
  card::WireSegment s;
  JobGen g(p, 0);
  if (!g.from_deltas(d, s)) throw std::runtime_error("bench error: segment does not fit");
  s.chunks = std::move(chunks);
  s.end = end;
  return s;
}

// The run after a fault: released and cleared, a new job runs exactly. An E-stop
// is not cleared by CLEAR, only by the out-of-band ACK (docs/CORE.md "Faults").
template <class H>
void expect_recovers(H& h, const std::string& where) {
  h.expecting = true;
  h.control(false, false, true);
  if (const card::Status kept = h.status(); kept.fault && kept.err_code == 10) {
    h.ack();
  } else {
    ASSERT_FALSE(kept.fault) << where << ": CLEAR did not clear (code " << kept.err_code << ")";
  }
  const card::Status st = h.status();
  ASSERT_FALSE(st.fault) << where << ": CLEAR did not clear (code " << st.err_code << ")";
  JobShape shape;
  shape.max_moves = 300;
  h.play(h.gen.job(3, shape));
  EXPECT_TRUE(h.chk.errors().empty()) << where << ", the job after CLEAR:\n" << h.chk.report();
  EXPECT_FALSE(h.status().fault) << where << ": the job after CLEAR faulted";
  for (unsigned a = 0; a < h.params.n; ++a)
    EXPECT_EQ(int32_t(h.read(card::Register::position0, a)), int32_t(h.chk.position(a)))
        << where << ": position of axis " << a << " after recovery";
}

// After an E-stop or ABORT seen in cycle `at`: no STEP leading edge after `at` (one at
// `at` comes from a move fired before it), the pulses that were high complete (the pin
// checker), queues flushed, the code latched, counters and positions exact.
template <class H>
void expect_stopped_at_once(H& h, uint64_t at, uint32_t code, const std::string& where) {
  EXPECT_TRUE(h.chk.errors().empty()) << where << ":\n" << h.chk.report();
  EXPECT_LE(h.chk.last_edge_cycle(), at) << where << ": a STEP leading edge after the stop";
  const card::Status st = h.status();
  EXPECT_TRUE(st.fault) << where;
  EXPECT_EQ(st.err_code, code) << where;
  EXPECT_FALSE(st.running) << where;
  EXPECT_EQ(st.segments_queued, 0u) << where << ": queue not flushed";
  EXPECT_EQ(st.chunks_queued, 0u) << where << ": chunks not flushed";
  h.stretch_slack = 1;  // a move counted late may have been cut
  h.expect_counters(where);
}

// One randomized run of a fault test: a fresh harness, random pulse timing, a job.
struct FaultRun {
  FaultRun(const char* name, uint64_t seed, unsigned segments)
      : h(name, seed), where(std::string(name) + " seed " + std::to_string(seed)) {
    h.configure_random(20);
    JobShape shape;
    shape.max_moves = 400;
    job = h.gen.job(segments, shape);
  }
  Harness h;
  std::string where;
  std::vector<card::WireSegment> job;
};

// E-stop at a random cycle of a streamed job (before START, during builds, between
// and during pulses): no STEP leading edge after the cycle it is seen except the
// completion of a pulse already high, queue flushed, code 10, positions exact, CLEAR
// refused while it is held, and everything works again after release and CLEAR.
TEST(CoreFaults, Estop) {
  const uint64_t seed = core_seed(3000);
  for (unsigned run = 0; run < 16; ++run) {
    FaultRun r("estop", seed + run, 6);
    Harness& h = r.h;
    const std::string& where = r.where;
    const auto& job = r.job;
    uint64_t total = 0;
    for (const auto& s : job) total += JobGen::programmed_cycles(s);
    const uint64_t at = h.ls.cycle() + 2 + h.gen.uniform(0, uint32_t(std::min<uint64_t>(total, 20000)));
    uint64_t seen = 0;
    h.hook = [&](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut&) {
      if (c + 1 == at) h.drv.set_estop(true);
      if (in.estop && !seen) {
        seen = c;
        h.chk.abandon();  // edges up to this cycle come from moves fired before it
        h.expecting = false;
      }
    };
    h.play(job);
    h.idle(200);
    ASSERT_NE(seen, 0u) << where;
    h.hook = nullptr;
    expect_stopped_at_once(h, seen, kEstop, where + " (held)");
    EXPECT_TRUE(h.status().estop) << where;
    h.control(false, false, true);  // refused while held
    const card::Status st = h.status();
    EXPECT_TRUE(st.fault) << where << ": CLEAR accepted while E-stop is held";
    EXPECT_EQ(st.err_code, kEstop) << where;
    h.drv.set_estop(false);
    h.idle(2);
    h.control(false, false, true);  // released: CLEAR still does not clear an E-stop
    const card::Status kept = h.status();
    EXPECT_TRUE(kept.fault) << where << ": CLEAR cleared an E-stop (only the out-of-band ACK may)";
    EXPECT_EQ(kept.err_code, kEstop) << where;
    expect_recovers(h, where);
    if (HasFailure()) return;
  }
}

// ABORT at a random point of a streamed job: the same rules as the E-stop from the
// cycle the word is taken, code 11, and CLEAR works at once.
TEST(CoreFaults, Abort) {
  const uint64_t seed = core_seed(4000);
  for (unsigned run = 0; run < 16; ++run) {
    FaultRun r("abort", seed + run, 6);
    Harness& h = r.h;
    const std::string& where = r.where;
    auto& job = r.job;
    const unsigned after = h.gen.uniform(0, 5);  // segments sent before the abort
    if (after > 0) job[after - 1].end = true;     // no underrun while the abort waits
    size_t i = 0;
    for (; i < 2 && i < after; ++i) h.segment(job[i]);
    h.control(true, false, false);
    for (; i < after; ++i) h.segment(job[i]);
    h.idle(h.gen.uniform(0, 3000));
    const uint64_t taken = h.control(false, true, false);
    h.chk.abandon();
    h.expecting = false;
    for (; i < job.size(); ++i) h.segment(job[i]);  // dropped: the fault is latched
    h.idle(200);
    expect_stopped_at_once(h, taken, kAbort, where);
    expect_recovers(h, where);
    if (HasFailure()) return;
  }
}

// Reset in the middle of a run at a random cycle: pins at their idle levels during
// reset, no pulse after it, every counter and position zero, and the core runs again.
TEST(CoreFaults, Reset) {
  const uint64_t seed = core_seed(5000);
  for (unsigned run = 0; run < 16; ++run) {
    FaultRun r("reset", seed + run, 5);
    Harness& h = r.h;
    const std::string& where = r.where;
    const auto& job = r.job;
    h.segment(job[0]);
    h.segment(job[1]);
    h.control(true, false, false);
    h.segment(job[2]);
    h.idle(h.gen.uniform(0, 2000));
    h.drv.reset(h.gen.uniform(1, 3));  // the checker restarts: nothing is expected after it
    const uint64_t after = h.ls.cycle();
    h.idle(300);
    EXPECT_TRUE(h.chk.errors().empty()) << where << ":\n" << h.chk.report();
    EXPECT_LT(h.chk.last_edge_cycle(), after) << where << ": a STEP pulse after reset";
    const card::Status st = h.status();
    EXPECT_FALSE(st.fault || st.running || st.stretched) << where;
    EXPECT_EQ(st.segments_queued, 0u) << where;
    EXPECT_EQ(st.chunks_queued, 0u) << where;
    EXPECT_EQ(h.read(card::Register::moves_done), 0u) << where;
    EXPECT_EQ(h.read(card::Register::segments_done), 0u) << where;
    EXPECT_EQ(h.read(card::Register::stretch_count), 0u) << where;
    for (unsigned a = 0; a < h.params.n; ++a) {
      EXPECT_EQ(h.read(card::Register::position0, a), 0u) << where << ": axis " << a;
      EXPECT_EQ(h.drv.last().position[a], 0) << where << ": position_o of axis " << a;
    }
    // The pins idle at the reset polarities, and the job after it runs exactly.
    EXPECT_EQ(h.drv.last().step, Core::model_params().step_pol_reset ? 0u : 0xFu) << where;
    expect_recovers(h, where);
    if (HasFailure()) return;
  }
}

// A segment without the end flag and nothing after it: motion stops at its last move
// (the fault is up from the cycle of that move's leading edge), code 9, positions on
// the deltas; a segment sent late is dropped until CLEAR.
TEST(CoreFaults, Underrun) {
  const uint64_t seed = core_seed(6000);
  for (unsigned run = 0; run < 8; ++run) {
    Harness h("underrun", seed + run);
    const std::string where = "underrun run " + std::to_string(run);
    h.configure_random(10);
    JobShape shape;
    shape.max_moves = 300;
    auto job = h.gen.job(3, shape);
    job.back().end = false;
    uint64_t fault_at = 0, stop_at = 0;
    h.hook = [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
      if (o.fault && !fault_at) fault_at = c;
      if (!o.running && !stop_at && h.chk.queue_empty() && h.chk.moves()) stop_at = c;
    };
    h.play(job);
    h.idle(100);
    EXPECT_TRUE(h.chk.errors().empty()) << where << ":\n" << h.chk.report();
    EXPECT_EQ(h.chk.segments_done(), 3u) << where << ": every segment completes";
    EXPECT_EQ(fault_at, h.chk.last_edge_cycle()) << where << ": fault not raised at the last move";
    EXPECT_EQ(stop_at, h.chk.last_edge_cycle()) << where << ": running not dropped at the last move";
    card::Status st = h.status();
    EXPECT_EQ(st.err_code, kUnderrun) << where;
    EXPECT_FALSE(st.running) << where;
    // Too late: dropped, no move.
    h.segment(h.gen.segment(shape, true), false);
    h.control(true, false, false);
    h.idle(500);
    EXPECT_TRUE(h.chk.errors().empty()) << where << ", the late segment moved:\n" << h.chk.report();
    st = h.status();
    EXPECT_EQ(st.err_code, kUnderrun) << where;
    EXPECT_EQ(st.segments_queued, 0u) << where;
    h.hook = nullptr;
    h.expect_counters(where + " (faulted)");
    expect_recovers(h, where);
    if (HasFailure()) return;
  }
}

// The underrun race, cycle by cycle: the next segment arrives just before or just
// after the last move of one without the end flag. docs/CORE.md: it is an underrun
// exactly when the next segment is committed in the cycle of that last move or later
// (a segment's commit is the chunk check's 51 cycles after its last word),
// whether or not it has been built yet.
TEST(CoreFaults, UnderrunDecidedByTheCommitCycle) {
  for (int offset = -8; offset <= 3; ++offset) {
    Harness h("underrun_race", 1);
    h.word_gap = 0;
    const std::string where = "commit " + std::to_string(offset) + " cycles from the last move";
    h.segment(seg_of({20, 7, 0, 0}, {{10, 19, 0}, {300, 1, 0}}, false));
    h.idle(100);  // built before START, so its moves are on time
    const uint64_t start = h.control(true, false, false);
    const uint64_t last_fire = start + 19 * 10 + 300;  // leading edge one cycle later
    const card::WireSegment next = seg_of({5, 0, -2, 0}, {{10, 5, 0}}, true);
    const uint64_t commit = last_fire + offset;
    const uint64_t words = 2 + 4 + 2, check = JobGen::kCheckCycles;
    h.idle(commit - check - (words - 1) - h.ls.cycle());
    const bool underrun = commit >= last_fire;
    uint64_t first_end = 0;
    h.hook = [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut&) {
      if (!first_end && h.chk.segments_done() == 1) first_end = c;
    };
    const uint64_t last_word = h.segment(next, !underrun);
    ASSERT_EQ(last_word + check, commit) << where << ": bench timing";
    h.finish(20000);
    h.idle(20);
    EXPECT_TRUE(h.chk.errors().empty()) << where << ":\n" << h.chk.report();
    const card::Status st = h.status();
    EXPECT_EQ(st.fault, underrun) << where << ": code " << st.err_code;
    EXPECT_EQ(h.chk.segments_done(), underrun ? 1u : 2u) << where;
    EXPECT_EQ(first_end, last_fire + 1) << where << ": the first segment's last move not on time";
    if (underrun) {
      EXPECT_EQ(st.err_code, 9u) << where;
    }
    if (HasFailure()) return;
  }
}

// Moves due faster than the pulse timing allows are delayed, never dropped: at the
// maximum rate one axis steps every step_high + step_low cycles (docs/PULSE.md), and
// every late move is counted.
TEST(CoreFaults, StretchAtTheMaximumStepRate) {
  Harness h("stretch_rate", 1);
  AxisTiming t;
  t.high = 3;
  t.low = 4;
  t.setup = 2;
  t.hold = 5;
  h.configure_all(t);
  std::vector<uint64_t> edges;
  uint32_t prev = 0;
  h.hook = [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
    if ((o.step & ~prev) & 1) edges.push_back(c);
    prev = o.step;
  };
  // +200 then -200 on x, every delay 1.
  h.segment(seg_of({200, 0, 0, 0}, {{1, 200, 0}}, false));
  h.segment(seg_of({-200, 0, 0, 0}, {{1, 200, 0}}, true));
  const uint64_t start = h.control(true, false, false);
  h.finish();
  h.hook = nullptr;
  ASSERT_EQ(edges.size(), 400u);
  EXPECT_EQ(edges[0], start + 2) << "the first move is on time (START + delay 1, then the pin)";
  for (size_t i = 1; i < edges.size(); ++i) {
    // Across the reversal: trailing edge, dir_hold, dir_setup (docs/PULSE.md).
    const uint64_t gap = i == 200 ? t.high + t.hold + t.setup : t.high + t.low;
    ASSERT_EQ(edges[i] - edges[i - 1], gap) << "move " << i;
  }
  EXPECT_EQ(h.chk.late_moves(), 399u);
  EXPECT_EQ(h.read(card::Register::stretch_count), 399u);
  EXPECT_TRUE(h.status().stretched);
  EXPECT_EQ(h.drv.last().position[0], 0);
  h.expect_consistent("stretch at the maximum rate");
  // CLEAR drops the flag, not the counter.
  h.control(false, false, true);
  EXPECT_FALSE(h.status().stretched);
  EXPECT_EQ(h.read(card::Register::stretch_count), 399u);
}

// Random pulse timings against delays of 1..4 on every axis: all moves happen, each no
// earlier than programmed, the late ones counted.
TEST(CoreFaults, StretchRandom) {
  const uint64_t seed = core_seed(7000);
  for (unsigned run = 0; run < 6; ++run) {
    Harness h("stretch_random", seed + run);
    h.configure_random(50);
    JobShape shape;
    shape.max_moves = 300;
    shape.max_delay = 4;
    h.play(h.gen.job(8, shape));
    EXPECT_GT(h.chk.late_moves(), 0u);
    h.expect_consistent("stretch random run " + std::to_string(run));
    if (HasFailure()) return;
  }
}

// A move whose chunk reaches the timer after its time (START sent before the segment):
// it is late, and counted, though it never waited due.
TEST(CoreFaults, StretchWhenTheSegmentComesAfterItsTime) {
  Harness h("stretch_late_segment", 1);
  const uint64_t start = h.control(true, false, false);
  h.idle(200);
  h.segment(seg_of({5, 3, 0, -1}, {{5, 1, 0}, {50, 4, 0}}, true));
  h.finish();
  EXPECT_GT(h.chk.last_edge_cycle(), start + 200);
  EXPECT_EQ(h.chk.late_moves(), 1u);
  EXPECT_EQ(h.read(card::Register::stretch_count), 1u) << "a late move went uncounted";
  h.expect_consistent("late segment");
}

}  // namespace
}  // namespace cpstep::tb

namespace cpstep::tb {
namespace {

// Drivers' enable (docs/CORE.md "Drivers"): off after reset, CONTROL bit 3 on, bit 4
// off (off wins), E-stop forces off and holds it off; other faults leave it on. The
// live outputs and status bit 4 agree with READ. Also the capability registers.
TEST(CoreFaults, DriversEnableAndCapabilities) {
  Harness h("core_drivers", 7);
  auto enabled = [&] { return h.drv.last().enable; };
  auto drivers = [&](bool on) {
    std::vector<uint32_t> w;
    card::encode_drivers(on, w);
    h.send(w);
    h.idle(1);
  };
  EXPECT_FALSE(enabled()) << "enable after reset";
  EXPECT_FALSE(h.status().drivers_enabled);
  drivers(true);
  EXPECT_TRUE(enabled());
  EXPECT_TRUE(h.status().drivers_enabled);
  h.send({0x3u << 28 | 1u << 3 | 1u << 4});  // both bits: off wins
  h.idle(1);
  EXPECT_FALSE(enabled()) << "on and off together";
  drivers(true);
  h.control(false, true, false);  // ABORT: a fault, the drivers stay on
  h.idle(1);
  EXPECT_TRUE(h.status().fault);
  EXPECT_TRUE(enabled()) << "ABORT must not drop the drivers";
  h.drv.set_estop(true);
  h.idle(2);  // seen in t, off from t+1
  EXPECT_FALSE(enabled()) << "E-stop";
  drivers(true);  // ignored while E-stop is held
  EXPECT_FALSE(enabled()) << "drivers on while E-stop is held";
  h.drv.set_estop(false);
  h.idle(1);
  EXPECT_FALSE(enabled()) << "E-stop released: the drivers stay off until asked";
  drivers(true);
  EXPECT_TRUE(enabled());
  // The live status outputs equal the registers READ returns.
  const model::CpCoreOut o = h.drv.last();
  EXPECT_EQ(o.status & 0xFFFF'FFF7u, h.read(card::Register::status) & 0xFFFF'FFF7u);
  EXPECT_EQ(o.moves_done, h.read(card::Register::moves_done));
  EXPECT_EQ(o.segments_done, h.read(card::Register::segments_done));
  EXPECT_EQ(o.stretch_count, h.read(card::Register::stretch_count));
  // Capabilities: what this build is, from the parameters the bench knows.
  const model::CpCoreParams& p = h.params;
  const uint32_t caps = h.read(card::Register::caps);
  EXPECT_EQ(caps & 0xFF, p.n);
  EXPECT_EQ(caps >> 8 & 0xFF, p.kmax);
  EXPECT_EQ(caps >> 16 & 0xF, p.caw);
  EXPECT_EQ(caps >> 20 & 0xF, p.saw);
  EXPECT_EQ(caps >> 24 & 0x1F, p.tw);
  EXPECT_EQ(h.read(card::Register::pattern_capacity), p.w);
  EXPECT_EQ(h.read(card::Register::umax), p.umax);
}

}  // namespace
}  // namespace cpstep::tb

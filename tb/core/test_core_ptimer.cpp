// SPDX-License-Identifier: MIT
// The phase timer's build of the motion core (PTIMER = 1; docs/PROTOCOL.md "Toward a
// compact wire"): the HX8K's core with its moves timed by rtl/cp_ptimer.v from PHASE
// commands, each segment carrying its length per move. RTL and model in lockstep
// every cycle, fed a real job as the host would send it: tab.ngc planned for the
// HX8K (arcs as chords) by card::plan_phase_timer_job — the feed plan's phases fitted
// by plan::PhaseFitter in the timer's half clocks, the segments without chunks. Every move fires at the clock
// the fitter computed (twice its half clocks after the first), nothing is late, the
// run ends with its last segment, and every axis ends where the job's steps put it.
// The model skips the quiet clocks (sim::Skipping: the phase timer advancing with no
// move due, CpPtimer::quiet_advs) and is compared with the RTL on every cycle.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "Vcp_core_hx8k_pt.h"
#include "card/caps.h"
#include "card/job.h"
#include "card/ptimer_job.h"
#include "card/protocol.h"
#include "common/lockstep.h"
#include "cpstep/builds.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "plan/phases.h"
#include "plan/pipeline.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"

namespace cpstep::tb {
namespace {

struct CorePtimer : sim::CorePortBase<Vcp_core_hx8k_pt, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() {
    return model::core_params(builds::hx8k_pt);
  }
};

// tab.ngc planned for the HX8K with its arcs as chords, for a phase-timer card
// (card::plan_phase_timer_job); each command one of the card's (command_words, on a
// phase-timer card, counts it whole).
// seed002.toml bound to the HX8K's card, arcs as chords; and that card's limits.
plan::Machine hx8k_machine(plan::ArcMode arcs = plan::ArcMode::chords) {
  auto loaded = plan::load_machine(std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/seed002.toml");
  EXPECT_TRUE(loaded.ok()) << plan::join(loaded.errors);
  plan::Machine m = *loaded;
  m.planner.arcs = arcs;
  const builds::Build& b = builds::hx8k_pt;
  // (The card's conic walker: 40 bits, cp_core's CIW, READ 0x26.)
  EXPECT_TRUE(plan::bind_card(m, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw, b.umax,
                                  b.conic ? 40u : 0u})
                  .empty());
  return m;
}
const card::CardLimits kHx8kLimits{builds::hx8k_pt.umax, builds::hx8k_pt.kmax, builds::hx8k_pt.w,
                                   1u << builds::hx8k_pt.caw, 1u << builds::hx8k_pt.saw};

card::PhaseTimerJob plan_tab(plan::ArcMode arcs = plan::ArcMode::chords) {
  const plan::Machine m = hx8k_machine(arcs);
  const std::string file = std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc";
  auto job = plan::load_gcode(file);
  EXPECT_TRUE(job.ok());
  auto planned = card::plan_phase_timer_job(*job, m, kHx8kLimits, file);
  EXPECT_TRUE(planned.ok()) << plan::join(planned.errors);
  if (!planned.ok()) return {};
  for (const auto& w : planned->commands)
    EXPECT_EQ(card::command_words(w[0], 4, true), w.size()) << "command_words of " << std::hex << w[0];
  return *planned;
}

// Sends a planned job to a core stepper (the preamble, the commands in their order,
// START after the first segment) and runs it to its end: the cycle of each move's
// fire (moves_done counts each move in the cycle after it fires) and the last outputs.
template <class Stepper>
std::vector<uint64_t> run_job(Stepper& dut, const card::PhaseTimerJob& job, model::CpCoreOut& last) {
  std::vector<uint64_t> fires;
  uint32_t moves_seen = 0;
  sim::CoreDriver<Stepper> drv(dut, [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
    for (; moves_seen < o.moves_done; ++moves_seen) fires.push_back(c);
  });
  drv.reset();
  drv.send(job.preamble);
  for (size_t i = 0; i < job.commands.size(); ++i) {
    drv.send(job.commands[i]);
    if (i + 1 == job.start_after) {
      std::vector<uint32_t> start;
      card::encode_control(true, false, false, start);
      drv.send(start);
    }
  }
  drv.run_until_stopped(uint64_t(4 * job.fire_half_clocks.back()) + 100000);
  drv.idle(100);
  last = drv.last();
  return fires;
}

// The run's verdict: no error, stopped, nothing late, every move at twice the
// fitter's half clocks from the first, every axis where the job's steps put it.
void expect_fitters_clocks(const card::PhaseTimerJob& job, const std::vector<uint64_t>& fires,
                           const model::CpCoreOut& last) {
  EXPECT_EQ(last.err_code, 0u);
  EXPECT_FALSE(last.running);
  EXPECT_EQ(last.stretch_count, 0u) << "no move late";
  ASSERT_EQ(fires.size(), job.fire_half_clocks.size());
  for (size_t n = 0; n < fires.size(); ++n)
    ASSERT_EQ(int64_t(fires[n] - fires[0]), 2 * (job.fire_half_clocks[n] - job.fire_half_clocks[0])) << "move " << n;
  for (unsigned a = 0; a < 4; ++a) EXPECT_EQ(last.position[a], job.end[a]) << "axis " << a;
}

TEST(CorePtimer, AJobsMovesFireWhereTheFitterSays) {
  const card::PhaseTimerJob job = plan_tab();
  ASSERT_FALSE(job.commands.empty());
  using Port = sim::Skipping<CorePtimer>;
  Lockstep<Port> ls("core_ptimer_tab");
  model::CpCoreOut last;
  const std::vector<uint64_t> fires = run_job(ls, job, last);
  const uint64_t skipped = ls.model_stepper().skipped(), cycles = ls.model_stepper().cycle();
  std::printf("tab.ngc: %llu segments, %llu phases, %llu bytes of segments (compact axis form) and phases "
              "(every axis's v sent: %llu; segments with chunks: %llu); %zu moves; the model skipped %llu of "
              "%llu clocks\n",
              (unsigned long long)job.segments, (unsigned long long)job.phases, (unsigned long long)job.bytes,
              (unsigned long long)(job.bytes - job.segment_bytes + job.every_axis_bytes),
              (unsigned long long)job.chunked_bytes, fires.size(), (unsigned long long)skipped,
              (unsigned long long)cycles);
  EXPECT_GT(skipped, cycles / 2) << "the model skipped too little to prove its skipping";
  EXPECT_LT(job.segment_bytes, job.every_axis_bytes) << "the compact form is shorter";
  expect_fitters_clocks(job, fires, last);
}

// The same job with its arcs as CONIC segments (one per arc): each conic move's length
// comes from the walker's length rule (K 2^S / m, rtl/cp_conic_serial.v LEN, the
// divider rtl/cp_div.v), which the host applied exactly to fit the phases; every move
// fires at the fitter's clock, in lockstep, and each conic's L word is its arc's {S, K}.
TEST(CorePtimer, AnArcsMovesFireWhereTheLengthRuleAndTheFitterSay) {
  const card::PhaseTimerJob job = plan_tab(plan::ArcMode::conic);
  ASSERT_FALSE(job.commands.empty());
  size_t conics = 0;
  for (size_t i = 0; i < job.wire.segments.size(); ++i) {
    const card::WireSegment& s = job.wire.segments[i];
    if (!s.conic) continue;
    ++conics;
    const plan::PlannedCardSegment& c = job.planned.card[job.wire.source[i]];
    ASSERT_TRUE(c.conic);
    ASSERT_TRUE(s.length);
    EXPECT_EQ(*s.length, c.rule_word) << "wire segment " << i;
    EXPECT_GE(*s.length & ((1u << 27) - 1), 1u << 26) << "K keeps 27 significant bits";
  }
  ASSERT_EQ(conics, 1u) << "tab.ngc's arc (G3), one CONIC";
  using Port = sim::Skipping<CorePtimer>;
  Lockstep<Port> ls("core_ptimer_tab_conics");
  model::CpCoreOut last;
  const std::vector<uint64_t> fires = run_job(ls, job, last);
  std::printf("tab.ngc, arcs as conics: %llu segments (%zu conics), %llu phases, %llu bytes of segments and "
              "phases; %zu moves\n",
              (unsigned long long)job.segments, conics, (unsigned long long)job.phases,
              (unsigned long long)job.bytes, fires.size());
  expect_fitters_clocks(job, fires, last);
}

// A dwell shorter than a pause (2^32 - 1 clocks) is no segment of its own: the phases
// hold the timer still through it. On the model core (skipping; the RTL is too slow
// for the dwell's 8 M clocks), every move fires at the fitter's clock, the second line's
// first the dwell after the first line's last.
TEST(CorePtimer, AShortDwellIsTimedByThePhases) {
  const plan::Machine m = hx8k_machine();
  const card::CardLimits& limits = kHx8kLimits;
  const builds::Build& b = builds::hx8k_pt;
  auto gcode = plan::parse_gcode("G21 G90\nG1 X1 Y0.5 F1800\nG4 P0.2\nG1 X2\nM2\n", "dwell.ngc");
  ASSERT_TRUE(gcode.ok()) << plan::join(gcode.errors);
  auto job = card::plan_phase_timer_job(*gcode, m, limits, "dwell.ngc");
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  sim::SkippingModelDut<sim::Skipping<CorePtimer>> dut;
  model::CpCoreOut last;
  const std::vector<uint64_t> fires = run_job(dut, *job, last);
  // The longest gap between moves: the dwell (0.2 s at 40 MHz), and a little more.
  uint64_t gap = 0;
  for (size_t n = 1; n < fires.size(); ++n) gap = std::max(gap, fires[n] - fires[n - 1]);
  std::printf("dwell.ngc: %zu moves, the longest gap %llu clocks; the model skipped %llu of %llu clocks\n",
              fires.size(), (unsigned long long)gap, (unsigned long long)dut.skipped(),
              (unsigned long long)dut.cycle());
  EXPECT_GE(gap, uint64_t(0.2 * b.clock_hz));
  EXPECT_LT(gap, uint64_t(0.3 * b.clock_hz));
  EXPECT_GT(dut.skipped(), dut.cycle() * 9 / 10);
  expect_fitters_clocks(*job, fires, last);
}

// The phase-timer job: an arc goes as a CONIC or as chords, as the machine file
// says; a pause (a dwell longer than 2^32 - 1 clocks, which the planner times as
// pause moves) as a segment of pause moves fired by timed phases.
TEST(CorePtimer, ThePhaseTimerJobPlansArcsEitherWayAndPausesAsTimedMoves) {
  plan::Machine m = hx8k_machine();
  const card::CardLimits& limits = kHx8kLimits;
  auto arcs = plan::parse_gcode("G21 G90 G17\nG1 X5 F600\nG2 X10 Y5 I0 J5\nM2\n", "arc.ngc");
  ASSERT_TRUE(arcs.ok()) << plan::join(arcs.errors);
  m.planner.arcs = plan::ArcMode::conic;
  auto conic = card::plan_phase_timer_job(*arcs, m, limits, "arc.ngc");
  ASSERT_TRUE(conic.ok()) << plan::join(conic.errors);
  EXPECT_EQ(conic->segments, 2u) << "the line and the arc, one CONIC";
  m.planner.arcs = plan::ArcMode::chords;
  auto chords = card::plan_phase_timer_job(*arcs, m, limits, "arc.ngc");
  ASSERT_TRUE(chords.ok()) << plan::join(chords.errors);
  EXPECT_GT(chords->segments, 4u) << "the same arc as chords";
  auto dwell = plan::parse_gcode("G21 G90\nG1 X5 F600\nG4 P200\nG1 X10\nM2\n", "dwell.ngc");
  ASSERT_TRUE(dwell.ok()) << plan::join(dwell.errors);
  // A dwell over 2^32 - 1 clocks: a segment of pause moves (every v 0, L never
  // reached), each fired by a timed phase at its clock (docs/PLANNING.md "Dwells").
  auto paused = card::plan_phase_timer_job(*dwell, m, limits, "dwell.ngc");
  ASSERT_TRUE(paused.ok()) << plan::join(paused.errors);
  const uint64_t pause_moves = paused->planned.stats.pause_moves;
  ASSERT_GT(pause_moves, 0u);
  size_t still = 0;
  for (const card::WireSegment& s : paused->wire.segments) {
    bool none = true;
    for (uint32_t v : s.v) none = none && v == 0;
    if (!none) continue;
    ++still;
    EXPECT_EQ(uint64_t(s.u) << s.k, pause_moves);
    EXPECT_EQ(s.length, std::optional<uint32_t>(0xFFFFFFFFu));
  }
  EXPECT_EQ(still, 1u);
  size_t timed = 0;
  for (const auto& c : paused->commands) timed += (c[0] >> 28) == 0x6 && (c[0] >> 25 & 1);
  EXPECT_GE(timed, pause_moves) << "each pause move a timed phase";
  EXPECT_EQ(paused->fire_half_clocks.size(), paused->planned.stats.moves + pause_moves);
}

// The card says what it is (READ 0x23 [26], through the core's read port, RTL and
// model in lockstep), and the host, which plans a phase-timer card's jobs with its
// phases (run::plan_card_job), takes it; the same core's build without the phase
// timer says it has none.
TEST(CorePtimer, TheHostSeesAPhaseTimerCard) {
  Lockstep<CorePtimer> ls("core_ptimer_caps");
  ls.reset();
  std::array<uint32_t, card::kCapsRegisters.size()> values{};
  for (size_t r = 0; r < values.size(); ++r) {
    model::CpCoreIn in;
    in.rd_addr = uint32_t(card::kCapsRegisters[r]);
    values[r] = ls.step(in).rd_data;
  }
  const card::CardCaps caps = card::decode_caps(values);
  EXPECT_TRUE(caps.ptimer);
  EXPECT_EQ(caps.n, 4u);
  EXPECT_EQ(card::unusable(caps, 4), "");
  EXPECT_NE(card::describe(caps).find("phase timer"), std::string::npos);
  model::CpCore chunked(model::core_params(builds::hx8k));
  for (size_t r = 0; r < values.size(); ++r) {
    chunked.in.rd_addr = uint32_t(card::kCapsRegisters[r]);
    values[r] = chunked.outputs().rd_data;
  }
  EXPECT_FALSE(card::decode_caps(values).ptimer);
  EXPECT_EQ(card::describe(card::decode_caps(values)).find("phase timer"), std::string::npos);
}

}  // namespace
}  // namespace cpstep::tb

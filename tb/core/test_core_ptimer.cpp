// SPDX-License-Identifier: MIT
// The phase timer's build of the motion core (PTIMER = 1; docs/PROTOCOL.md "Toward a
// compact wire"): the HX8K's core with its moves timed by rtl/cp_ptimer.v from PHASE
// commands, each segment carrying its length per move. RTL and model in lockstep
// every cycle, fed a real job as the host would send it: tab.ngc planned for the
// HX8K (arcs as chords), the feed plan's phases fitted by plan::PhaseFitter in the
// timer's half clocks, the segments without chunks. Every move fires at the clock
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

#include "Vcp_core_ptimer.h"
#include "card/caps.h"
#include "card/job.h"
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

struct CorePtimer : sim::CorePortBase<Vcp_core_ptimer, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() {
    model::CpCoreParams p = model::core_params(builds::hx8k);
    p.ptimer = true;
    return p;
  }
};

// A phase's length in the timer's half clocks (2^6 of them a tick; a timed move's in clocks).
int64_t phase_clocks(const plan::TimerPhase& ph) {
  const int64_t t = ph.ticks == 0 ? 1 : int64_t(ph.ticks);
  return ph.timed ? t : t << 6;
}

struct PtimerJob {
  std::vector<uint32_t> preamble;
  // The segments' and the phases' words in the order the card needs them (by the
  // time each begins: a phase at its start, a segment at its first move); START
  // goes after the first segment.
  std::vector<std::vector<uint32_t>> items;
  size_t start_after = 0;           // items before START
  std::vector<int64_t> fire_clocks; // the fitter's, half clocks from the first phase's start
  std::array<int64_t, 4> end{};     // every axis's position at the end, steps
  uint64_t phases = 0, segments = 0, bytes = 0;
  uint64_t chunked_bytes = 0;       // the same segments with their chunks, as a chunk card takes them
  uint64_t segment_bytes = 0;       // of `bytes`, the segments'
  uint64_t every_axis_bytes = 0;    // ... with every axis's v sent (H0[15:0] = 0), not the compact form
};

PtimerJob plan_ptimer_job(const std::string& gcode) {
  PtimerJob out;
  auto loaded = plan::load_machine(std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/seed002.toml");
  EXPECT_TRUE(loaded.ok());
  plan::Machine m = *loaded;
  m.planner.arcs = plan::ArcMode::chords;
  const builds::Build& b = builds::hx8k;
  EXPECT_TRUE(plan::bind_card(m, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw}).empty());
  auto job = plan::load_gcode(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/" + gcode);
  EXPECT_TRUE(job.ok());

  // The timer counts half clocks (rtl/cp_run.v, PTIMER): every time in them.
  plan::PhaseFormat fmt{6, 60, true, false, 0.0125};
  fmt.clock_hz = m.card.clock_hz / 2;
  fmt.length_bits = 30;   // the segment word L: Q2.30 of the path unit
  plan::PhaseFitter fitter(fmt, m.chunk_tolerance_cycles() / 2);
  std::vector<uint32_t> lengths;   // per timed batch (a card segment): its L
  std::vector<size_t> batch_moves;
  const card::CardLimits limits{b.umax, b.kmax, b.w, 1u << b.caw, 1u << b.saw};
  plan::PlanOptions o;
  o.chunk_limits = card::chunk_limits(limits);   // (the chunks are not sent; to_wire checks them)
  o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                        std::span<const plan::PlanJerk> changes) {
    std::vector<double> half(ideal.begin(), ideal.end());
    for (double& t : half) t /= 2;
    std::vector<plan::PlanJerk> ch(changes.begin(), changes.end());
    for (plan::PlanJerk& c : ch) c.at /= 2;
    const plan::i128 l = plan::move_length(lengths_mm.front(), fmt) >> 30;
    EXPECT_TRUE(l > 0 && l < (plan::i128(1) << 32)) << "L fits its word";
    for (double x : lengths_mm) EXPECT_EQ(plan::move_length(x, fmt) >> 30, l) << "a line's moves are one length";
    lengths.push_back(uint32_t(l));
    batch_moves.push_back(ideal.size());
    EXPECT_TRUE(fitter.push(half, lengths_mm, rest_at < 0 ? rest_at : rest_at / 2, ch)) << fitter.error();
  };
  auto planned = plan::plan_job(*job, m, o);
  EXPECT_TRUE(planned.ok());
  EXPECT_TRUE(fitter.finish()) << fitter.error();
  out.fire_clocks = fitter.fire_clocks();

  auto wired = card::to_wire(*planned, gcode, limits);
  EXPECT_TRUE(wired.ok()) << plan::join(wired.errors);
  card::WireJob wire_job = *wired;
  card::WireJob* wire = &wire_job;
  // Each wire segment's length per move is its planned card segment's (a batch each).
  std::vector<uint64_t> first_move;   // per wire segment: its first move's index
  uint64_t moves = 0;
  for (size_t i = 0; i < wire->segments.size(); ++i) {
    card::WireSegment& s = wire->segments[i];
    const size_t c = wire->source[i];
    EXPECT_FALSE(planned->card[c].segment.pause) << "no pause segments in this job";
    EXPECT_LT(c, lengths.size());
    s.length = lengths[std::min(c, lengths.size() - 1)];
    first_move.push_back(moves);
    moves += uint64_t(s.u) << s.k;
    for (size_t a = 0; a < 4 && a < s.v.size(); ++a)
      out.end[a] += (s.dir_positive[a] ? 1 : -1) * int64_t(uint64_t(s.v[a]) << s.k);
  }
  EXPECT_EQ(moves, out.fire_clocks.size()) << "every move timed";
  EXPECT_EQ(std::accumulate(batch_moves.begin(), batch_moves.end(), uint64_t(0)), moves);
  wire->segments.back().end = true;

  card::encode_preamble(m, 0, out.preamble);
  // Phases and segments by the time each begins (a phase first at a tie).
  std::vector<std::pair<int64_t, std::vector<uint32_t>>> timed;
  int64_t t = 0;
  for (const plan::TimerPhase& ph : fitter.phases()) {
    std::vector<uint32_t> w;
    card::encode_phase(card::wire_phase(ph), w);
    timed.push_back({2 * t, std::move(w)});
    t += phase_clocks(ph);
    ++out.phases;
  }
  for (size_t i = 0; i < wire->segments.size(); ++i) {
    std::vector<uint32_t> w;
    card::WireSegment chunked = wire->segments[i];
    chunked.length.reset();
    std::vector<uint32_t> cw;
    card::encode_segment(chunked, cw);
    out.chunked_bytes += 4 * cw.size();
    std::vector<uint32_t> ew;
    card::encode_segment(wire->segments[i], ew, true);
    out.every_axis_bytes += 4 * ew.size();
    card::encode_segment(wire->segments[i], w);
    timed.push_back({2 * out.fire_clocks[first_move[i]] + 1, std::move(w)});
    ++out.segments;
  }
  std::stable_sort(timed.begin(), timed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [when, w] : timed) {
    out.bytes += 4 * w.size();
    if ((w[0] >> 28) != 6) out.segment_bytes += 4 * w.size();
    // The host's count of a command's words, a phase-timer card's: each item is one command.
    EXPECT_EQ(card::command_words(w[0], 4, true), w.size()) << "command_words of " << std::hex << w[0];
    if (out.start_after == 0 && (w[0] >> 28) != 6) out.start_after = out.items.size() + 1;
    out.items.push_back(std::move(w));
  }
  return out;
}

TEST(CorePtimer, AJobsMovesFireWhereTheFitterSays) {
  const PtimerJob job = plan_ptimer_job("tab.ngc");
  ASSERT_FALSE(job.items.empty());
  using Port = sim::Skipping<CorePtimer>;
  Lockstep<Port> ls("core_ptimer_tab");
  std::vector<uint64_t> fires;
  uint32_t moves_seen = 0;
  sim::CoreDriver<Lockstep<Port>> drv(ls, [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
    // moves_done counts each move in the cycle after it fires.
    for (; moves_seen < o.moves_done; ++moves_seen) fires.push_back(c);
  });
  drv.reset();
  drv.send(job.preamble);
  for (size_t i = 0; i < job.items.size(); ++i) {
    drv.send(job.items[i]);
    if (i + 1 == job.start_after) {
      std::vector<uint32_t> start;
      card::encode_control(true, false, false, start);
      drv.send(start);
    }
  }
  drv.run_until_stopped(uint64_t(4 * job.fire_clocks.back()) + 100000);
  drv.idle(100);
  const model::CpCoreOut& last = drv.last();
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
  EXPECT_EQ(last.err_code, 0u);
  EXPECT_FALSE(last.running);
  EXPECT_EQ(last.stretch_count, 0u) << "no move late";
  ASSERT_EQ(fires.size(), job.fire_clocks.size());
  for (size_t n = 0; n < fires.size(); ++n)
    ASSERT_EQ(int64_t(fires[n] - fires[0]), 2 * (job.fire_clocks[n] - job.fire_clocks[0])) << "move " << n;
  for (unsigned a = 0; a < 4; ++a) EXPECT_EQ(last.position[a], job.end[a]) << "axis " << a;
}

// The card says what it is (READ 0x23 [26], through the core's read port, RTL and
// model in lockstep) and the host, which plans chunks, refuses to drive it.
TEST(CorePtimer, TheHostSeesAPhaseTimerCardAndRefusesIt) {
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
  const std::string why = card::unusable(caps, 4);
  EXPECT_NE(why.find("phase timer"), std::string::npos) << why;
  EXPECT_NE(card::describe(caps).find("phase timer"), std::string::npos);
  // The same core's build without the phase timer: usable, and it says so.
  model::CpCore chunked(model::core_params(builds::hx8k));
  for (size_t r = 0; r < values.size(); ++r) {
    chunked.in.rd_addr = uint32_t(card::kCapsRegisters[r]);
    values[r] = chunked.outputs().rd_data;
  }
  EXPECT_FALSE(card::decode_caps(values).ptimer);
  EXPECT_EQ(card::unusable(card::decode_caps(values), 4), "");
}

}  // namespace
}  // namespace cpstep::tb

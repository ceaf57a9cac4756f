// SPDX-License-Identifier: MIT
// `cpstep run` on the phase-timer card (rtl/builds.json's hx8k_pt; docs/CORE.md
// "Phase-timer builds"): the host reads that the card times its moves by the phase
// timer, plans the job with its phases (run::plan_card_job -> card::plan_phase_timer_job)
// and streams the PHASE and SEGMENT commands through the card's SPI pins; every move
// must fire at the cycle the host computed for it (MoveClock's chunk time: twice the
// fitter's half clocks after the timer's start), every card segment end where the
// plan says, and the wire must carry fewer bytes than the chunk card's job.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <fmt/format.h>

#include "card/caps.h"
#include "card/protocol.h"
#include "card/ptimer_job.h"
#include "plan/common.h"
#include "plan/queue_step.h"
#include "run/card_job.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

const std::string kMachine = std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/seed002.toml";
const std::string kTab = std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc";

// A file of this suite's scratch folder (made when needed) holding `text`.
fs::path scratch_file(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "ptimer_job";
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

bool has_warning(const std::vector<plan::Diagnostic>& w, const std::string& text) {
  for (const plan::Diagnostic& d : w)
    if (d.message.find(text) != std::string::npos) return true;
  return false;
}

// tab.ngc on the simulated phase-timer card (the fast engine; the Boards suite runs the
// same job on the Verilated card in lockstep with it): the card's own report of what
// it is, the job planned from it, every move at its computed cycle.
TEST(PhaseTimerRun, EveryMoveFiresAtTheCycleTheHostComputed) {
  const card::CardCaps caps = run::connect_sim("hx8k_pt");
  ASSERT_TRUE(caps.ptimer) << "the card reports its phase timer (READ 0x23 [26])";
  auto prepared = run::prepare_job(kTab, kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  EXPECT_FALSE(has_warning(job.warnings, "arcs planned as chords")) << "seed002.toml asks for conics";
  size_t conics = 0;
  for (const card::WireSegment& s : job.wire.segments) conics += s.conic.has_value();
  EXPECT_EQ(conics, 1u) << "tab.ngc's arc (G3), one CONIC segment";
  ASSERT_EQ(job.fire_cycles.size(), job.moves());
  ASSERT_GT(job.phases, 0u);
  EXPECT_EQ(job.phase_end_word.size(), job.phases);
  EXPECT_EQ(job.segment_end_word.size(), job.wire.segments.size());
  // Every command whole by the card's lengths, START once, after the first segment.
  size_t starts = 0, segments = 0, phases = 0;
  for (size_t i = 0; i < job.words.size(); i += card::command_words(job.words[i], 4, true)) {
    const uint32_t op = job.words[i] >> 28;
    if (op == 0x3 && (job.words[i] & 1)) {
      EXPECT_EQ(segments, 1u) << "START after the first segment";
      ++starts;
    }
    segments += op == 0x1 || op == 0x5;
    phases += op == 0x6;
  }
  EXPECT_EQ(starts, 1u);
  EXPECT_EQ(segments, job.wire.segments.size());
  EXPECT_EQ(phases, job.phases);

  run::SimRunOptions o;
  o.board = "hx8k_pt";
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.moves_done, job.moves());
  EXPECT_EQ(r.checked_segments, job.checkpoints.size());
  EXPECT_EQ(r.position_mismatches, 0u);
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  EXPECT_EQ(r.stretch_count, 0u);
  ASSERT_EQ(r.move_cycles.size(), job.moves());
  // Each move's fire against the host's cycle for it, START counted from.
  for (size_t n = 0; n < r.move_cycles.size(); ++n)
    ASSERT_EQ(int64_t(r.move_cycles[n] - r.start_cycle), job.fire_cycles[n]) << "move " << n + 1;
  const run::RunMeasure m = run::measure_run(job, r);
  EXPECT_EQ(m.max_chunk_error_cycles, 0);
  EXPECT_EQ(m.moves_off_chunk_time, 0u);
  EXPECT_LE(m.max_timing_error_cycles, job.machine.chunk_tolerance_cycles() + 2);

  // The same job for the chunk card (the hx8k build, arcs as conics too): more bytes.
  plan::Machine chords = job.machine;
  auto gcode = run::read_card_gcode(kTab, chords, {});
  ASSERT_TRUE(gcode.ok());
  auto chunked = run::plan_card_job(*gcode, chords, *card::board_caps("hx8k"));
  ASSERT_TRUE(chunked.ok()) << plan::join(chunked.errors);
  std::printf("tab.ngc, arcs as conics: %zu command words on the phase-timer card (%llu phases, %zu segments), "
              "%zu on the chunk card; %llu bytes on the link (frames, polls and replies)\n",
              job.words.size(), (unsigned long long)job.phases, job.wire.segments.size(),
              chunked->words.size(), (unsigned long long)r.link.stats.bytes);
  EXPECT_LT(job.words.size() * 10, chunked->words.size() * 6) << "the phase-timer card's wire is shorter";
  // A move off its cycle (here, the pins' record of one moved by 3 clocks) is a LATE
  // fault: a phase-timer card counts no move as stretched.
  run::CardRun off = r;
  EXPECT_TRUE(off.ok());
  run::add_phase_timer_fault(job, m, off);
  EXPECT_TRUE(off.ok()) << "every move at its cycle";
  off.move_cycles[600] += 3;
  const run::RunMeasure moved = run::measure_run(job, off);
  EXPECT_EQ(moved.moves_off_chunk_time, 1u);
  run::add_phase_timer_fault(job, moved, off);
  ASSERT_EQ(off.faults.size(), 1u);
  EXPECT_EQ(off.faults[0].name, "LATE");
  EXPECT_NE(off.faults[0].message.find("1 move(s) fired off"), std::string::npos) << off.faults[0].message;
  // The card took the job's words and the READs of its capability registers, nothing else.
  EXPECT_EQ(r.link.stats.words, job.words.size() + card::kCapsRegisters.size());
}

// plasma.ngc, 238,280 moves of 60 pierced contours with their stops, on the same card
// (the fast engine): every move at its cycle, the torch as planned. This job found the
// timer's lost move (Ptimer.AMoveDueInTheLastClockBeforeATimedMoveFiresThere): one move
// due in the last clock before a stop's timed move, then the card a move behind and an
// underrun at the end.
TEST(PhaseTimerRun, ThePlasmaJobsMovesAllFireAtTheirCycles) {
  const card::CardCaps caps = *card::board_caps("hx8k_pt");
  auto prepared = run::prepare_job(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/plasma.ngc", kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  run::SimRunOptions o;
  o.board = "hx8k_pt";
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  ASSERT_EQ(r.move_cycles.size(), job.fire_cycles.size());
  size_t off = 0;
  for (size_t n = 0; n < r.move_cycles.size(); ++n)
    if (int64_t(r.move_cycles[n] - r.start_cycle) != job.fire_cycles[n] && off++ == 0)
      ADD_FAILURE() << "move " << n + 1 << " fired at " << r.move_cycles[n] - r.start_cycle << ", the host says "
                    << job.fire_cycles[n];
  EXPECT_EQ(off, 0u) << "moves off their cycles";
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  EXPECT_EQ(r.torch_verdict.errors.size(), 0u);
  EXPECT_GT(job.phases, 500u);
}

// The motion the card holds, as the client's batching sees it: never more than both
// the segments and the phases handed time.
TEST(PhaseTimerRun, TheHeldMotionEndsWhereTheHandedPhasesEnd) {
  const card::CardCaps caps = *card::board_caps("hx8k_pt");
  auto prepared = run::prepare_job(kTab, kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  const double hz = job.clock_hz();
  for (size_t p = 0; p < job.phase_end_word.size(); ++p) {
    const uint64_t handed = job.phase_end_word[p];
    // The segments whose words are all handed by then.
    size_t sent = 0;
    while (sent < job.segment_end_word.size() && job.segment_end_word[sent] <= handed) ++sent;
    if (sent == 0) continue;
    const double held = run::buffered_seconds(job, 0, 0, handed);
    const double by_segments = double(job.segment_end_cycle[sent - 1]) - double(job.fire_cycles[0]);
    const double by_phases = double(job.phase_end_cycle[p]) - double(job.fire_cycles[0]);
    EXPECT_NEAR(held * hz, std::max(0.0, std::min(by_segments, by_phases)), 1e-6 * hz) << "phase " << p;
  }
  EXPECT_EQ(run::buffered_seconds(job, 0, 0, 0), 0.0);
}

// naca0025.ngc (seed 002's airfoil, one G5.2 NURBS) as written, seed002.toml as it
// is: on a card that walks arcs the curve goes as arcs within arc_tolerance_mm (the
// tolerance its chords would have), each one CONIC the card walks and measures, every
// move at its cycle, and the wire carries at most half the bytes Klipper's queue_step
// takes for the job's steps at 25 us (issue 13's goal; the steps of the G-code as
// written). With planner.arcs = "chords" the curve is its chords, and over the goal.
TEST(PhaseTimerRun, TheAirfoilsNurbsGoesAsArcsWithinTheWireGoal) {
  const card::CardCaps caps = run::connect_sim("hx8k_pt");
  std::ifstream in(kMachine);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("[planner]\n");
  ASSERT_NE(at, std::string::npos);
  const fs::path chords_machine =
      scratch_file("seed002_chords.toml", text.substr(0, at + 10) + "arcs = \"chords\"\n" + text.substr(at + 10));
  const std::string naca = std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/naca0025.ngc";
  auto prepared = run::prepare_job(naca, kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  EXPECT_EQ(job.planned.stats.fit.curves, 1u);
  EXPECT_LE(job.planned.stats.fit.curve_max_deviation_mm, job.machine.planner.arc_tolerance_mm);
  size_t conics = 0;
  for (const card::WireSegment& s : job.wire.segments) conics += s.conic.has_value();
  EXPECT_EQ(conics, job.planned.stats.fit.curve_arcs) << "each arc of the curve one CONIC";
  EXPECT_GT(conics, 5u);

  run::SimRunOptions o;
  o.board = "hx8k_pt";
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.moves_done, job.moves());
  EXPECT_EQ(r.position_mismatches, 0u);
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  ASSERT_EQ(r.move_cycles.size(), job.moves());
  for (size_t n = 0; n < r.move_cycles.size(); ++n)
    ASSERT_EQ(int64_t(r.move_cycles[n] - r.start_cycle), job.fire_cycles[n]) << "move " << n + 1;

  const plan::QueueStepCost klipper = plan::queue_step_cost(run::klipper_path_steps(job), 25e-6 * caps.clock_hz);
  ASSERT_TRUE(klipper.error.empty()) << klipper.error;
  auto chords = run::prepare_job(naca, chords_machine, caps);
  ASSERT_TRUE(chords.ok()) << plan::join(chords.errors);
  EXPECT_EQ(chords->planned.stats.fit.curves, 0u);
  std::printf("naca0025 on hx8k_pt: %zu bytes with its NURBS as %zu arcs (%zu with it as chords); "
              "Klipper's queue_step at 25 us %llu bytes, the goal %llu\n",
              4 * job.words.size(), conics, 4 * chords->words.size(), (unsigned long long)klipper.bytes,
              (unsigned long long)klipper.bytes / 2);
  EXPECT_LE(4 * job.words.size(), klipper.bytes / 2);
  EXPECT_GT(4 * chords->words.size(), klipper.bytes / 2) << "the chords alone do not meet it";
}

// A dwell longer than one phase holds (2^24 - 1 ticks of 64 half clocks: 53.7 s at
// 40 MHz) waits in several rest phases, each within the PHASE word's 24-bit field; one
// of exactly 2^24 ticks was sent as 0 (1 tick on the card), and every move after the
// dwell fired 53.7 s early. Every move at its cycle, the dwell's 100 s between them.
TEST(PhaseTimerRun, ADwellLongerThanOnePhaseWaitsInRestPhasesThatFitTheirField) {
  const card::CardCaps caps = run::connect_sim("hx8k_pt");
  const fs::path dwell = scratch_file("long_dwell.ngc", "G21 G90\nG1 X5 F600\nG4 P100\nG1 X10\nM2\n");
  auto prepared = run::prepare_job(dwell, kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  // Every PHASE word's ticks field as the card reads it (0: 1), the rest phases' sum.
  uint64_t rest_half_clocks = 0, rests = 0;
  for (size_t i = 0; i < job.words.size(); i += card::command_words(job.words[i], 4, true)) {
    const uint32_t w = job.words[i];
    if (w >> 28 != 0x6 || !(w >> 26 & 1) || (w >> 25 & 1)) continue;   // a rest, not a timed move
    const uint64_t ticks = (w & 0xFFFFFF) == 0 ? 1 : (w & 0xFFFFFF);
    rest_half_clocks += ticks << 6;
    ++rests;
  }
  EXPECT_GE(rests, 2u) << "100 s is more than one phase holds";
  EXPECT_GE(double(rest_half_clocks) / (caps.clock_hz / 2.0), 99.0) << "the rests hold the dwell";

  run::SimRunOptions o;
  o.board = "hx8k_pt";
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  ASSERT_EQ(r.move_cycles.size(), job.moves());
  size_t gap_at = 0;
  for (size_t n = 0; n < r.move_cycles.size(); ++n) {
    ASSERT_EQ(int64_t(r.move_cycles[n] - r.start_cycle), job.fire_cycles[n]) << "move " << n + 1;
    if (n > 0 && r.move_cycles[n] - r.move_cycles[n - 1] > r.move_cycles[gap_at] - r.move_cycles[gap_at ? gap_at - 1 : 0])
      gap_at = n;
  }
  ASSERT_GT(gap_at, 0u);
  EXPECT_GE(double(r.move_cycles[gap_at] - r.move_cycles[gap_at - 1]) / caps.clock_hz, 100.0) << "the dwell";
}

// Pauses (docs/PLANNING.md "Dwells"): a dwell longer than a move interval holds
// (2^32 - 1 clocks, 107 s at 40 MHz) and a dwell after the last move are a segment of
// pause moves (every v 0, L 0xFFFFFFFF), each fired by a timed move at its clock after
// flat rests; the card counts them, the pins show none. 200 s between two lines on the
// fast engine; a trailing dwell with the torch on, on the Verilated card in lockstep
// with the model: the card runs on, the torch held, until the dwell's end.
TEST(PhaseTimerRun, PausesAreTimedMovesOfASegmentThatStepsNothing) {
  const card::CardCaps caps = run::connect_sim("hx8k_pt");
  struct Case {
    const char* name;
    const char* gcode;
    run::Engine engine;
    double dwell_s;
  };
  int64_t end_after_pin_move = -1;
  for (const Case& c : {Case{"pause.ngc", "G21 G90\nG1 X5 F600\nG4 P200\nG1 X10\nM2\n", run::Engine::model, 200},
                        Case{"trailing.ngc", "G21 G90\nM3\nG1 X0.5 F600\nG4 P0.05\nM5\nM2\n",
                             run::Engine::lockstep, 0.05}}) {
    SCOPED_TRACE(c.name);
    const fs::path path = scratch_file(c.name, c.gcode);
    auto prepared = run::prepare_job(path, kMachine, caps);
    ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
    const run::CardJob& job = *prepared.value;
    ASSERT_GT(job.planned.stats.pause_moves, 0u);
    size_t pauses = 0;
    for (const card::WireSegment& s : job.wire.segments) {
      bool still = true;
      for (uint32_t v : s.v) still = still && v == 0;
      if (!still) continue;
      ++pauses;
      EXPECT_EQ(s.length, std::optional<uint32_t>(0xFFFFFFFFu)) << "a pause's L: never reached";
    }
    EXPECT_EQ(pauses, 1u);
    EXPECT_EQ(job.fire_cycles.size(), job.card_moves()) << "pause moves timed too";

    run::SimRunOptions o;
    o.board = "hx8k_pt";
    o.engine = c.engine;
    const run::CardRun r = run::run_on_sim(job, o);
    ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
    EXPECT_EQ(r.moves_done, job.card_moves()) << "the card counts the pause moves";
    EXPECT_EQ(r.position, job.checkpoints.back().position);
    EXPECT_EQ(r.position_mismatches, 0u);
    ASSERT_EQ(r.move_cycles.size(), job.moves()) << "the pins show no pause move";
    const run::RunMeasure m = run::measure_run(job, r);
    EXPECT_EQ(m.moves_off_chunk_time, 0u);
    EXPECT_EQ(m.max_chunk_error_cycles, 0);
    // The dwell on the pins: the longest gap between moves, or the run past the last.
    uint64_t gap = r.cycles - r.move_cycles.back();
    for (size_t n = 1; n < r.move_cycles.size(); ++n) gap = std::max(gap, r.move_cycles[n] - r.move_cycles[n - 1]);
    // The run ends as long after its last move when that is a pause move (its time
    // the host's) as when it is a move on the pins (the first case).
    const int64_t end_after = int64_t(r.cycles - r.start_cycle) - job.fire_cycles.back();
    if (c.engine == run::Engine::model) {
      EXPECT_EQ(int64_t(r.move_cycles.back() - r.start_cycle), job.fire_cycles.back()) << "the last move on the pins";
      end_after_pin_move = end_after;
    } else {
      EXPECT_EQ(end_after, end_after_pin_move) << "the run ends where the last pause move is due";
    }
    EXPECT_GE(double(gap) / caps.clock_hz, c.dwell_s);
    EXPECT_LT(double(gap) / caps.clock_hz, c.dwell_s + 1.0);
    EXPECT_TRUE(r.torch_verdict.ok()) << (r.torch_verdict.errors.empty() ? "" : r.torch_verdict.errors.front());
    if (c.engine == run::Engine::lockstep) {  // M3 ... G4 P0.05 M5: on through the dwell
      EXPECT_GE(r.torch_verdict.on_cycles / caps.clock_hz, c.dwell_s);
    }
  }
}

// Arcs go as conics, with nothing to say; an arc whose moves come faster than the
// walker gives them goes as chords, with a warning that says why. (Homing and probing
// run on the card too: Home.EveryAxisHomesAtItsSwitchOnTheFastEngine,
// ProbeBoards.*/hx8k_pt; pauses above.)
TEST(PhaseTimerRun, ArcsTheWalkerCannotPaceGoAsChordsWithAWarning) {
  const card::CardCaps caps = *card::board_caps("hx8k_pt");
  const fs::path arcs = scratch_file("arcs.ngc", "G21 G90 G17\nG1 X5 F600\nG2 X10 Y5 I0 J5\nG2 X15 Y0 I5 J0\nM2\n");
  auto a = run::prepare_job(arcs, kMachine, caps);
  ASSERT_TRUE(a.ok()) << plan::join(a.errors);
  EXPECT_FALSE(has_warning(a->warnings, "arcs planned as chords"));
  EXPECT_EQ(a->wire.segments.size(), 3u) << "a line and two CONIC segments";
  // The walker's fastest: 8,000 steps/mm at 60 mm/s (moves some 100 clocks apart,
  // drivers that take 100 ns pulses) makes the arcs' moves come sooner than a pass
  // and a division apart.
  std::string axes;
  for (const char* axis : {"x", "y", "z"})
    axes += fmt::format("[axes.{}]\nsteps_per_mm = 8000\ntravel_min_mm = -50\ntravel_max_mm = 50\n"
                        "max_velocity_mm_s = 60\nmax_accel_mm_s2 = 5000\nmax_jerk_mm_s3 = 200000\n"
                        "step_high_ns = 100\nstep_low_ns = 100\ndir_setup_ns = 100\ndir_hold_ns = 100\n",
                        axis);
  const fs::path fast = scratch_file("fast.toml", "[planner]\narc_tolerance_mm = 0.002\nchunk_tolerance_us = 1.0\n" + axes);
  const fs::path fast_arcs =
      scratch_file("fast_arcs.ngc", "G21 G90 G17\nG1 X5 F3600\nG2 X7 Y2 I0 J2\nG2 X9 Y0 I2 J0\nM2\n");
  auto f = run::prepare_job(fast_arcs, fast, caps);
  ASSERT_TRUE(f.ok()) << plan::join(f.errors);
  size_t said = 0;
  for (const plan::Diagnostic& d : f->warnings)
    if (d.message.find("as chords") != std::string::npos) {
      ++said;
      EXPECT_NE(d.message.find("walker"), std::string::npos) << d.message;
    }
  EXPECT_GE(said, 1u) << "why the arcs went as chords";
  for (const card::WireSegment& s : f->wire.segments) EXPECT_FALSE(s.conic.has_value()) << "chords only";
}

}  // namespace
}  // namespace cpstep::tb

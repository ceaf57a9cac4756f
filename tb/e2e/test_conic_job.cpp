// SPDX-License-Identifier: MIT
// G2/G3 arcs through the whole pipeline as CONIC segments (docs/PLANNING.md "Arcs as
// conics"): planned for the HX8K card (CONIC = 1), sent over SPI to the simulated
// card, stepped by its walker. The Verilated card and the golden model give the same
// pins edge for edge; every move comes on its planned time; the trace conforms to the
// plan by `cpstep check`'s checker (the walk's moves and directions, nodes within
// the walk's bound of its circle); the card ends where the G-code does; the same job
// with arcs as chords ends at the same steps.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "card/caps.h"
#include "check/check.h"
#include "check/vcd.h"
#include "run/card_job.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

const std::string kSource = CPSTEP_SOURCE_DIR;

// Arcs of radius 0.5 and 1 mm, a half circle between lines, a helix turn in G17, an
// arc in G18 and one in G19, on the router (320 steps/mm on X, Y, Z): about 1 s of
// motion, 40 M card cycles.
constexpr const char* kJob =
    "G21 G90 G17\n"
    "G0 X10 Y10 Z0\n"
    "G1 X11 F3000\n"
    "G3 X11.5 Y10.5 I0 J0.5\n"
    "G2 X13.5 Y10.5 I1 J0\n"
    "G1 Y11\n"
    "G3 X13.5 Y11 Z-0.3 I-0.5 J0\n"
    "G18 G2 X14 Z-0.8 I0 K-0.5\n"
    "G19 G3 Y11.5 Z-0.3 J0 K0.5\n"
    "G17 G1 X10 Y10 Z0\n"
    "M2\n";

fs::path write_job(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "conic_job";
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

// `cpstep check`'s verdict on a run's VCD against the job's plan (every read
// must work: a failure throws the test's assertion).
check::Verdict check_vcd(const run::CardJob& job, const fs::path& vcd) {
  const auto text = check::read_text(vcd);
  EXPECT_TRUE(text.has_value()) << vcd;
  if (!text) return {};
  const auto trace = check::parse_vcd(*text, vcd.string());
  EXPECT_TRUE(trace.ok()) << plan::join(trace.errors);
  if (!trace.ok()) return {};
  const auto pins = check::read_pins(*trace, check::default_pin_map(), job);
  EXPECT_TRUE(pins.ok()) << plan::join(pins.errors);
  if (!pins.ok()) return {};
  return check::check_trace(job, *pins);
}

// The job on the simulated HX8K card (the fast engine), its pins into `vcd`.
run::CardRun run_hx8k(const run::CardJob& job, const fs::path& vcd) {
  run::SimRunOptions o;
  o.board = "hx8k";
  o.vcd = vcd.string();
  return run::run_on_sim(job, o);
}

plan::Result<run::CardJob> prepare(const std::string& board, bool chords) {
  std::string machine;
  {
    std::ifstream in(kSource + "/examples/machines/router.toml");
    machine.assign(std::istreambuf_iterator<char>(in), {});
  }
  if (chords) machine.replace(machine.find("[planner]\n"), 10, "[planner]\narcs = \"chords\"\n");
  const fs::path m = write_job(chords ? "router_chords.toml" : "router.toml", machine);
  return run::prepare_job(write_job("arcs.ngc", kJob).string(), m.string(), *card::board_caps(board));
}

TEST(ConicJob, ArcsRunAsConicsOnTheHx8kCardOnBothEnginesAndConformToThePlan) {
  auto prepared = prepare("hx8k", false);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  EXPECT_TRUE(job.warnings.empty()) << plan::join(job.warnings);
  const plan::PlanStats& st = job.planned.stats;
  EXPECT_EQ(st.conic_arcs, 5u);
  EXPECT_EQ(st.chord_arcs, 0u);
  size_t conic_words = 0;
  for (size_t w = 0; w < job.words.size(); w += card::command_words(job.words[w], plan::kAxes))
    conic_words += job.words[w] >> 28 == 0x5;
  EXPECT_GE(conic_words, 5u) << "CONIC commands in the stream";

  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "conic_job";
  run::CardRun runs[2];
  const run::Engine engines[2] = {run::Engine::rtl, run::Engine::model};
  fs::path vcds[2];
  for (int e = 0; e < 2; ++e) {
    run::SimRunOptions o;
    o.engine = engines[e];
    o.board = "hx8k";
    vcds[e] = dir / fmt::format("arcs.{}.vcd", run::engine_name(engines[e]));
    o.vcd = vcds[e].string();
    runs[e] = run::run_on_sim(job, o);
    ASSERT_TRUE(runs[e].ok()) << runs[e].faults.front().name << ": " << runs[e].faults.front().message;
  }
  const run::CardRun &rtl = runs[0], &model = runs[1];
  // The card ends where the G-code does: X10 Y10 Z0 in steps.
  EXPECT_EQ(rtl.position[0], 3200);
  EXPECT_EQ(rtl.position[1], 3200);
  EXPECT_EQ(rtl.position[2], 0);
  EXPECT_EQ(model.position, rtl.position);
  EXPECT_EQ(model.move_cycles, rtl.move_cycles);
  EXPECT_EQ(rtl.stretch_count, 0u) << "a move waited for the walker";
  EXPECT_EQ(rtl.moves_done, job.card_moves());
  ASSERT_EQ(rtl.move_cycles.size(), job.moves());
  const std::vector<int64_t> chunk_cycles = run::chunk_cycles(job);
  ASSERT_EQ(chunk_cycles.size(), job.moves());
  for (size_t i = 0; i < job.moves(); ++i)
    ASSERT_EQ(rtl.move_cycles[i] - rtl.start_cycle, uint64_t(chunk_cycles[i])) << "move " << i;
  {
    std::ifstream a(vcds[0]), b(vcds[1]);
    const std::string ta((std::istreambuf_iterator<char>(a)), {}), tb((std::istreambuf_iterator<char>(b)), {});
    EXPECT_EQ(ta, tb) << "the engines' pins differ";
  }

  // The trace against the plan: the checker a validation engineer runs.
  const auto text = check::read_text(vcds[0].string());
  ASSERT_TRUE(text.has_value()) << vcds[0];
  const auto vcd = check::parse_vcd(*text, vcds[0].string());
  ASSERT_TRUE(vcd.ok()) << plan::join(vcd.errors);
  const auto pins = check::read_pins(*vcd, check::default_pin_map(), job);
  ASSERT_TRUE(pins.ok()) << plan::join(pins.errors);
  const check::Verdict v = check::check_trace(job, *pins);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  EXPECT_LE(v.axes[0].max_deviation, 0.5 + 0.05);
  EXPECT_LE(v.axes[1].max_deviation, 0.5 + 0.05);
  EXPECT_LE(v.axes[2].max_deviation, 0.5 + 0.05);
  // The same trace against the job planned with chords: the checker tells them apart
  // (the walk's combined moves are not the chords' strings).
  auto chords = prepare("hx8k", true);
  ASSERT_TRUE(chords.ok()) << plan::join(chords.errors);
  const auto chord_pins = check::read_pins(*vcd, check::default_pin_map(), *chords);
  ASSERT_TRUE(chord_pins.ok()) << plan::join(chord_pins.errors);
  const check::Verdict cv = check::check_trace(*chords, *chord_pins);
  EXPECT_FALSE(cv.conforms());
}

TEST(ConicJob, TheSameJobAsChordsEndsAtTheSameSteps) {
  auto conic = prepare("hx8k", false);
  auto chords = prepare("hx8k", true);
  ASSERT_TRUE(conic.ok() && chords.ok()) << plan::join(conic.errors) << plan::join(chords.errors);
  EXPECT_EQ(chords->planned.stats.conic_arcs, 0u);
  EXPECT_LT(conic->wire.segments.size(), chords->wire.segments.size());
  const run::CardRun a = run::run_on_sim(*conic, {});
  const run::CardRun b = run::run_on_sim(*chords, {});
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a.position, b.position);
  // The iCEBreaker has no walker: the same job is chords there, without a warning.
  auto ice = prepare("icebreaker", false);
  ASSERT_TRUE(ice.ok()) << plan::join(ice.errors);
  EXPECT_EQ(ice->planned.stats.conic_arcs, 0u);
  EXPECT_EQ(ice->planned.stats.chord_arcs, 5u);
  EXPECT_TRUE(ice->warnings.empty()) << plan::join(ice->warnings);
}

// A chain of G1 chords (a half circle of 120 lines and a quarter the other way, as
// CAM output gives) with planner.fit_arcs_mm set: the planner fits arcs to them
// (docs/PLANNING.md "Arcs fitted to line chains"), the HX8K card walks them as
// conics, the trace conforms to the plan, the card ends on the last G1's steps.
TEST(ConicJob, FittedLineChainsRunAsConics) {
  std::string g = "G21 G90 G17\nG0 X20 Y10 Z0\nF900\n";
  for (int i = 1; i <= 120; ++i) {
    const double a = 3.14159265358979 * i / 120;
    g += fmt::format("G1 X{:.4f} Y{:.4f}\n", 15 + 5 * std::cos(a), 10 + 5 * std::sin(a));
  }
  for (int i = 1; i <= 60; ++i) {
    const double a = 3.14159265358979 * (1 + 0.5 * i / 60);
    g += fmt::format("G1 X{:.4f} Y{:.4f}\n", 5 - 5 * std::cos(a), 10 - 5 * std::sin(a));
  }
  g += "M2\n";
  std::string machine;
  {
    std::ifstream in(kSource + "/examples/machines/seed002.toml");
    machine.assign(std::istreambuf_iterator<char>(in), {});
  }
  machine.replace(machine.find("[planner]\n"), 10, "[planner]\nfit_arcs_mm = 0.002\n");
  const fs::path m = write_job("seed002_fit.toml", machine);
  auto job = run::prepare_job(write_job("chain.ngc", g).string(), m.string(), *card::board_caps("hx8k"));
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  const plan::PlanStats& st = job->planned.stats;
  EXPECT_EQ(st.fit.arcs, 2u);
  EXPECT_EQ(st.fit.lines_in_arcs, 180u);
  EXPECT_LE(st.fit.max_deviation_mm, 0.002);
  EXPECT_EQ(st.conic_arcs, 2u);
  const fs::path vcd = fs::path(CPSTEP_TEST_DIR) / "conic_job" / "chain.vcd";
  const run::CardRun r = run_hx8k(*job, vcd);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  // The last G1: X = 5 - 5 cos(1.5 pi) = 5, Y = 10 - 5 sin(1.5 pi) = 15 mm at 80 steps/mm.
  EXPECT_EQ(r.position[0], 5 * 80);
  EXPECT_EQ(r.position[1], 15 * 80);
  EXPECT_EQ(r.stretch_count, 0u);
  const check::Verdict v = check_vcd(*job, vcd);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
}

// An arc whose plane's axes have different steps/mm (seed002.toml: X 80, Z 400) is an
// ellipse in steps; the card walks it as one (docs/PLANNING.md "Arcs as conics"): the
// fast engine runs it, the trace conforms to the plan, the card ends where the G-code
// does.
TEST(ConicJob, AnArcInXZOnUnequalStepsPerMmIsAnEllipseOnTheCard) {
  const fs::path g = write_job("xz.ngc", "G21 G90\nG0 X20 Y10 Z0\nG18 G2 X30 Z0 I5 K0 F600\nG3 X20 Z0 I-5 K0\nM2\n");
  auto job = run::prepare_job(g.string(), kSource + "/examples/machines/seed002.toml", *card::board_caps("hx8k"));
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  EXPECT_EQ(job->planned.stats.conic_arcs, 2u) << plan::join(job->warnings);
  const fs::path vcd = fs::path(CPSTEP_TEST_DIR) / "conic_job" / "xz.vcd";
  const run::CardRun r = run_hx8k(*job, vcd);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.position[0], 20 * 80);
  EXPECT_EQ(r.position[2], 0);
  EXPECT_EQ(r.stretch_count, 0u);
  const check::Verdict v = check_vcd(*job, vcd);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  EXPECT_LE(v.axes[0].max_deviation, 0.55);
  EXPECT_LE(v.axes[2].max_deviation, 0.55);
}

// Seed 001's figure on the card's pins: a G-code quarter circle of radius 1,000 steps
// (3.125 mm at 320 steps/mm) about a node, planned for the HX8K card and stepped by its
// walker, every move event read off STEP/DIR: 1,414 moves of which 586 are combined
// (both axes on one clock edge), against 2,000 one axis at a time, and every node
// within half a step of the circle. The same G-code as chords (arc_tolerance_mm 0.005,
// 1.6 steps) strays further. (docs/CONIC.md §9 prints both.)
TEST(ConicJob, SeedFigureAQuarterCircleOfRadius1000StepsOnThePins) {
  const std::string g = "G21 G90 G17\nG0 X13.125 Y10\nG3 X10 Y13.125 I-3.125 J0 F600\nM2\n";
  for (bool chords : {false, true}) {
    std::string machine;
    {
      std::ifstream in(kSource + "/examples/machines/router.toml");
      machine.assign(std::istreambuf_iterator<char>(in), {});
    }
    if (chords) machine.replace(machine.find("[planner]\n"), 10, "[planner]\narcs = \"chords\"\n");
    const fs::path m = write_job(chords ? "router_chords.toml" : "router.toml", machine);
    auto job = run::prepare_job(write_job("quarter.ngc", g).string(), m.string(), *card::board_caps("hx8k"));
    ASSERT_TRUE(job.ok()) << plan::join(job.errors);
    struct Move {
      int dx, dy;
    };
    std::vector<Move> moves;
    uint32_t last_step = 0;
    run::SimRunOptions o;
    o.board = "hx8k";
    o.pins = [&](uint64_t, uint32_t step, uint32_t dir) {
      const uint32_t rise = step & ~last_step;  // STEP active high on the router
      last_step = step;
      if (rise & 3) moves.push_back({(rise & 1) ? ((dir & 1) ? 1 : -1) : 0, (rise & 2) ? ((dir & 2) ? 1 : -1) : 0});
    };
    const run::CardRun r = run::run_on_sim(*job, o);
    ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
    // The rapid to the start comes first: the quarter's moves are the last ones.
    int64_t x = 4200, y = 3200;
    size_t first = moves.size();
    {
      int64_t px = r.position[0], py = r.position[1];
      ASSERT_EQ(px, 3200);
      ASSERT_EQ(py, 4200);
      while (first > 0 && !(px == 4200 && py == 3200)) {
        --first;
        px -= moves[first].dx;
        py -= moves[first].dy;
      }
    }
    size_t diagonal = 0;
    double worst = 0;
    for (size_t k = first; k < moves.size(); ++k) {
      x += moves[k].dx;
      y += moves[k].dy;
      diagonal += moves[k].dx != 0 && moves[k].dy != 0;
      worst = std::max(worst, std::abs(std::hypot(double(x - 3200), double(y - 3200)) - 1000.0));
    }
    const size_t quarter = moves.size() - first;
    RecordProperty(chords ? "chords_moves" : "conic_moves", int(quarter));
    RecordProperty(chords ? "chords_max_deviation_e6" : "conic_max_deviation_e6", int(worst * 1e6));
    std::printf("%s: %zu moves (%zu combined), largest node distance %.5f steps\n", chords ? "chords" : "conic",
                quarter, diagonal, worst);
    if (!chords) {
      EXPECT_EQ(job->planned.stats.conic_arcs, 1u);
      EXPECT_EQ(quarter, 1414u);
      EXPECT_EQ(diagonal, 586u);
      EXPECT_LE(worst, 0.5);
    } else {
      EXPECT_GT(worst, 0.5) << "chords within 1.6 steps of the arc, then rounded to steps";
    }
  }
}

}  // namespace
}  // namespace cpstep::tb

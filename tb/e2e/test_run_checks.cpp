// SPDX-License-Identifier: MIT
// The checks of host/run against a plan that the card does not follow: a
// planned position changed by one step must become a POSITION fault at that
// card segment, and nothing else may change.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "card/caps.h"
#include "card/protocol.h"
#include "run/card_job.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

TEST(RunChecks, APositionOffThePlanIsAFaultAtItsSegment) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "run_checks";
  fs::create_directories(dir);
  const fs::path job_file = dir / "square.ngc";
  // Two lines: x to 0.5 mm, then y to 0.5 mm (40 steps each on the plotter).
  std::ofstream(job_file) << "G21 G90\nG1 X0.5 F600\nG1 Y0.5\nM2\n";
  auto prepared = run::prepare_job(job_file, std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/plotter.toml");
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  run::CardJob job = *prepared.value;
  ASSERT_EQ(job.checkpoints.size(), 2u);
  ASSERT_EQ(job.checkpoints[0].position[0], 40);

  // The card follows the real plan; the checker is told x ends the first
  // segment one step further.
  job.checkpoints[0].position[0] += 1;
  const run::CardRun r = run::run_on_sim(job, {});
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.checked_segments, 2u);
  EXPECT_EQ(r.position_mismatches, 1u);
  ASSERT_EQ(r.faults.size(), 1u);
  EXPECT_EQ(r.faults[0].code, 101u);
  EXPECT_EQ(r.faults[0].name, "POSITION");
  EXPECT_EQ(r.faults[0].message.rfind("card segment 1 (" + job_file.string() + ":2), move 40: position_o x=40 y=0 "
                                      "z=0 but the plan says x=41 y=0 z=0",
                                      0),
            0u)
      << r.faults[0].message;
  // Everything else is as planned.
  EXPECT_EQ(r.move_cycles.size(), 80u);
  EXPECT_EQ(r.position[0], 40);
  EXPECT_EQ(r.position[1], 40);
  EXPECT_EQ(r.stretch_count, 0u);
  const run::RunMeasure m = run::measure_run(job, r);
  EXPECT_EQ(m.max_chunk_error_cycles, 0);
  EXPECT_LE(m.max_timing_error_cycles, job.machine.chunk_tolerance_cycles() + 1);
}

TEST(RunChecks, StretchedMovesAreALateFault) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "run_checks";
  fs::create_directories(dir);
  const fs::path job_file = dir / "line.ngc";
  // 40 x steps at 10 mm/s: 800 steps/s, 50,000 cycles apart on the HX8K card
  // (40 MHz; its TW = 16 takes pulse times up to 65,535 cycles).
  std::ofstream(job_file) << "G21 G90\nG1 X0.5 F600\nM2\n";
  const auto hx8k = card::board_caps("hx8k");
  ASSERT_TRUE(hx8k.has_value());
  auto prepared =
      run::prepare_job(job_file, std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/plotter.toml", *hx8k);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  run::CardJob job = *prepared.value;
  // Before the first SEGMENT word (opcode 1), after the job's own CONFIG words,
  // x's STEP high time set to 60,000 cycles: every x pulse then outlasts the gap
  // to the next move, which the card stretches.
  std::size_t at = 0;
  while (at < job.words.size() && (job.words[at] >> 28) != 0x1) ++at;
  ASSERT_LT(at, job.words.size());
  ASSERT_EQ(job.words[at - 1] >> 28, 0x2u) << "the CONFIG words come right before the first segment";
  std::vector<uint32_t> slow;
  card::encode_config(0, card::ConfigField::step_high, 60000, slow);
  job.words.insert(job.words.begin() + std::ptrdiff_t(at), slow.begin(), slow.end());

  const run::CardRun r = run::run_on_sim(job, {});
  EXPECT_FALSE(r.ok());
  std::string faults;
  for (const run::Fault& f : r.faults) faults += f.name + ": " + f.message + "\n";
  EXPECT_GT(r.stretch_count, 0u) << faults;
  ASSERT_FALSE(r.faults.empty());
  bool late = false;
  for (const run::Fault& f : r.faults) {
    if (f.name != "LATE") continue;
    late = true;
    EXPECT_EQ(f.code, 107u);
    EXPECT_EQ(f.message.rfind(std::to_string(r.stretch_count) + " move(s) fired late", 0), 0u) << f.message;
  }
  EXPECT_TRUE(late) << "no LATE fault";
  // Late, not lost: the card still ends where the plan says.
  EXPECT_EQ(r.position[0], 40);
  EXPECT_EQ(r.position_mismatches, 0u);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The G-code corpus (examples/gcode/, README there) run on the simulated card:
// `cpstep run` as a user runs it, one program per ctest test (tb/e2e/CMakeLists.txt
// names the program and its machine in CPSTEP_CORPUS_FILE / CPSTEP_CORPUS_MACHINE,
// and the engine, --engine, in CPSTEP_CORPUS_ENGINE).
// The card must end every program where the G-code ends (the last block's end
// rounded to whole steps, computed here from the parsed program, not from the
// plan), with no fault, no stretched (late) move, every card segment's position
// as planned, and the realized peaks measured from the pins within the machine's
// limits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "common/process.h"
#include "plan/gcode.h"
#include "plan/machine.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

TEST(CorpusRun, LandsWhereTheProgramEndsNeverLateWithinLimits) {
  const std::string file = env("CPSTEP_CORPUS_FILE"), machine = env("CPSTEP_CORPUS_MACHINE");
  ASSERT_FALSE(file.empty()) << "CPSTEP_CORPUS_FILE is not set (tb/e2e/CMakeLists.txt sets it per test)";
  ASSERT_FALSE(machine.empty()) << "CPSTEP_CORPUS_MACHINE is not set";
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "corpus_run";
  fs::create_directories(dir);
  const std::string stem = fs::path(file).stem().string();
  const fs::path report = dir / (stem + ".json");
  const std::string engine = env("CPSTEP_CORPUS_ENGINE").empty() ? "model" : env("CPSTEP_CORPUS_ENGINE");
  // Only this engine's report: the same program's run on the other engine may be
  // running beside this one (ctest -j), and removing its report made it read none.
  fs::remove(report.string() + "." + engine);
  const cpstep::tb::Outcome run =
      cpstep::tb::run_program(CPSTEP_BIN,
                              {"run", file, "--machine", machine, "--engine", engine, "--report",
                               report.string() + "." + engine, "--no-progress"},
                              dir, stem + "." + engine);
  ASSERT_EQ(run.rc, 0) << file << "\n" << run.out << run.err;

  // Where the program ends, from the reader (the planner is not asked).
  auto m = cpstep::plan::load_machine(machine);
  ASSERT_TRUE(m.ok()) << cpstep::plan::join(m.errors);
  auto job = cpstep::plan::load_gcode(file, cpstep::plan::gcode_options(*m));
  ASSERT_TRUE(job.ok()) << cpstep::plan::join(job.errors);
  ASSERT_FALSE(job->blocks.empty());
  const auto& end_mm = job->blocks.back().end;

  const json rep = json::parse(cpstep::tb::slurp(report.string() + "." + engine));
  EXPECT_EQ(rep.at("engine"), engine);
  EXPECT_EQ(rep.at("faults"), json::array()) << rep.at("faults").dump();
  EXPECT_EQ(rep.at("stretches").get<int>(), 0) << "a move fired late";
  EXPECT_EQ(rep.at("position_mismatches").get<int>(), 0);
  EXPECT_EQ(rep.at("checked_segments").get<uint64_t>(), rep.at("planned_card_segments").get<uint64_t>());
  const double clk = rep.at("clock_hz").get<double>();
  // Never late; early by at most the chunk tolerance plus an ideal time's rounding.
  EXPECT_LE(rep.at("max_timing_error_cycles").get<double>(),
            rep.at("chunk_tolerance_cycles").get<double>() + 1) << "clock " << clk;
  const json& axes = rep.at("axes");
  ASSERT_FALSE(axes.empty());
  for (std::size_t a = 0; a < cpstep::plan::kAxes; ++a) {
    const auto& ax = m->axes[a];
    const std::string name(1, cpstep::plan::kAxisLetters[a]);
    if (!ax.present) {
      EXPECT_FALSE(axes.contains(name)) << name;
      continue;
    }
    SCOPED_TRACE("axis " + name);
    ASSERT_TRUE(axes.contains(name));
    const json& r = axes.at(name);
    const auto expected = static_cast<int64_t>(std::floor(end_mm[a] * ax.steps_per_mm + 0.5));
    EXPECT_EQ(r.at("final_steps").get<int64_t>(), expected);
    EXPECT_EQ(r.at("planned_final_steps").get<int64_t>(), expected);
    EXPECT_TRUE(r.at("within_limits").get<bool>())
        << "peak v " << r.at("peak_velocity") << " a " << r.at("peak_accel") << " j " << r.at("peak_jerk");
  }
}

}  // namespace

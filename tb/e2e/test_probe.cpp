// SPDX-License-Identifier: MIT
// Probing (issue 12, docs/HOST.md "Probing"): G38.2..G38.5 in a G-code job, run on the
// simulated HX8K card with a touch plate across Z (inputs.sim_probe_mm) that closes
// the probe input when the pins reach it. Checked against the program's own
// arithmetic: the trip lies at the plate (or past it by no more than the steps made
// while its closing reaches the card), the program goes on from the trip with #5063
// and #5070 as LinuxCNC sets them, the pins equal the card's counters; G38.2 without
// contact stops the program there, a probe already in contact moves nothing, a
// program refused for its text sends nothing; `cpstep run` on the example job; a
// short probing job with the Verilated card in lockstep with the fast engine.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "common/process.h"
#include "run/home.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;
const fs::path kDir = fs::path(CPSTEP_TEST_DIR) / "probe";
const std::string kSrc = CPSTEP_SOURCE_DIR;
const std::string kMill = kSrc + "/examples/machines/mill.toml";

std::string slurp_text(const std::string& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path write(const std::string& name, const std::string& text) {
  fs::create_directories(kDir);
  const fs::path p = kDir / name;
  std::ofstream(p) << text;
  return p;
}

// The mill with its plate at `z_mm` from the start.
fs::path mill_with_plate(const std::string& name, double z_mm) {
  return write(name, std::regex_replace(slurp_text(kMill), std::regex(R"(sim_probe_mm = \{ z = [-0-9.]+ \})"),
                                        "sim_probe_mm = { z = " + std::to_string(z_mm) + " }"));
}

// Steps Z makes at `mm_s` while the plate's contact reaches the card: a frame (under
// 8,000 clocks), the world's wait chunk, the synchronizer, the filter's three samples
// and the level, the fire decision; plus the step under way.
int64_t overshoot_bound(const plan::Machine& m, double mm_s) {
  const double latency = 8000 + 2 + 3.0 * m.inputs.filter_cycles + 1 + 1;
  return int64_t(std::ceil(mm_s * m.axes[2].steps_per_mm * latency / m.card.clock_hz)) + 1;
}

// On the HX8K's chunk card and on its phase-timer card (hx8k_pt).
class ProbeBoards : public ::testing::TestWithParam<const char*> {};
TEST_P(ProbeBoards, TheExampleJobTouchesOffAndCutsAtTheHeightFound) {
  const run::SimProbeRun r = run::probe_job_on_sim(kSrc + "/examples/jobs/probe.ngc", kMill, GetParam(), "model");
  ASSERT_TRUE(r.ok()) << r.error << (r.errors.empty() ? "" : r.errors.front().str());
  ASSERT_EQ(r.probes.size(), 2u);
  const plan::Machine& m = r.machine;
  const double spm = m.axes[2].steps_per_mm;
  const run::ProbeEvent& touch = r.probes[0];
  EXPECT_EQ(touch.code, "G38.2");
  EXPECT_TRUE(touch.tripped);
  EXPECT_EQ(r.probe_at, std::llround(-12.5 * spm)) << "the plate of the machine file";
  const int64_t past = r.probe_at - touch.counts[2];  // Z moves down onto it
  EXPECT_GE(past, 0) << "stopped before the plate";
  EXPECT_LE(past, overshoot_bound(m, 1.0)) << "F60: 1 mm/s";
  EXPECT_EQ(touch.counts[0], std::llround(20 * spm));
  // The probe touches at the G38.2, and the simulated plane again when the cut goes
  // 1 mm below it (the cutter, not the probe, in a real machine).
  ASSERT_EQ(r.contacts.size(), 2u);
  EXPECT_EQ(r.contacts[0].pins, r.probe_at);
  // G38.3 along X finds no edge: no error, it ends at its target, 5 mm above the
  // touch (G0 Z[#100 + 5], #100 = #5063).
  const run::ProbeEvent& edge = r.probes[1];
  EXPECT_FALSE(edge.tripped);
  EXPECT_EQ(edge.counts[0], std::llround(60 * spm));
  EXPECT_EQ(edge.counts[2], touch.counts[2] + std::llround(5 * spm)) << "#5063 + 5";
  EXPECT_EQ(r.counts[0], 0);
  EXPECT_EQ(r.counts[1], 0);
  EXPECT_EQ(r.counts[2], touch.counts[2] + std::llround(5 * spm));
  EXPECT_EQ(r.pins, r.counts) << "the STEP edges on the pins equal the card's counters";
}

INSTANTIATE_TEST_SUITE_P(Hx8k, ProbeBoards, ::testing::Values("hx8k", "hx8k_pt"),
                         [](const auto& p) { return std::string(p.param); });

// #5070 after a probe that trips and one that does not, used by the program.
TEST(Probe, TheProgramReadsTheTripFlagAndPosition) {
  const fs::path job = write("flag.ngc",
                             "G21 G90\nG38.2 Z-20 F120\nG0 Z[#5063 + 2]\nG1 X[#5070 * 4] F600\n"
                             "G38.3 Y3 F300\nG1 X[#5070 * 4 + 1] F600\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), mill_with_plate("mill_flag.toml", -6.0).string(),
                                                   "hx8k", "model");
  ASSERT_TRUE(r.ok()) << r.error << (r.errors.empty() ? "" : r.errors.front().str());
  ASSERT_EQ(r.probes.size(), 2u);
  const double spm = r.machine.axes[0].steps_per_mm;
  EXPECT_TRUE(r.probes[0].tripped);
  EXPECT_EQ(r.probes[1].counts[0], std::llround(4 * spm)) << "#5070 = 1 after the first";
  EXPECT_FALSE(r.probes[1].tripped);
  EXPECT_EQ(r.counts[0], std::llround(1 * spm)) << "#5070 = 0 after the second";
  EXPECT_EQ(r.counts[2], r.probes[0].counts[2] + std::llround(2 * spm));
  EXPECT_EQ(r.pins, r.counts);
}

// G38.2 that makes no contact: an error at its line, and nothing after it runs.
TEST(Probe, AG38Point2WithoutContactStopsTheProgram) {
  const fs::path job = write("miss.ngc", "G21 G90\nG1 Y2 F600\nG38.2 Z-4 F120\nG1 X5 F600\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), kMill, "hx8k", "model");
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_FALSE(r.errors.empty());
  EXPECT_EQ(r.errors.front().loc.line, 3);
  EXPECT_NE(r.errors.front().message.find("made no contact"), std::string::npos) << r.errors.front().message;
  const double spm = r.machine.axes[0].steps_per_mm;
  EXPECT_EQ(r.counts[0], 0) << "the G1 X5 after it did not run";
  EXPECT_EQ(r.counts[1], std::llround(2 * spm)) << "the block before it did";
  EXPECT_EQ(r.counts[2], std::llround(-4 * spm)) << "it ran to its end";
}

// The machine starts on the plate: G38.2 moves nothing and says so.
TEST(Probe, AProbeAlreadyInContactMovesNothing) {
  const fs::path job = write("on.ngc", "G21 G90\nG38.2 Z-4 F120\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), mill_with_plate("mill_on.toml", 0.0).string(), "hx8k",
                                                   "model");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_NE(r.errors.front().message.find("already in contact"), std::string::npos) << r.errors.front().message;
  EXPECT_EQ(r.moves, 0u);
  EXPECT_EQ(r.counts, (plan::PerAxis<int64_t>{}));
}

// An error anywhere in the text, or a probe move past the travel, refuses the program
// before anything is sent.
TEST(Probe, AProbeOutsideTheTravelIsRefusedBeforeAnythingRuns) {
  const fs::path job = write("far.ngc", "G21 G90\nG1 X3 F600\nG38.2 Z-95 F120\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), kMill, "hx8k", "model");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_EQ(r.errors.front().loc.line, 3);
  EXPECT_NE(r.errors.front().message.find("outside the travel"), std::string::npos) << r.errors.front().message;
  EXPECT_EQ(r.moves, 0u);
  EXPECT_EQ(r.counts, (plan::PerAxis<int64_t>{}));
}

TEST(Probe, AProgramWithAnErrorAfterItsProbeRunsNothing) {
  const fs::path job = write("bad.ngc", "G21 G90\nG1 X3 F600\nG38.2 Z-20 F120\nG1 X[1/0] F600\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), kMill, "hx8k", "model");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_EQ(r.errors.front().loc.line, 4);
  EXPECT_TRUE(r.probes.empty());
  EXPECT_EQ(r.moves, 0u);
  EXPECT_EQ(r.counts, (plan::PerAxis<int64_t>{}));
}

TEST(Probe, CpstepRunRunsAProbingJob) {
  const Outcome o = run_program(CPSTEP_BIN, {"run", kSrc + "/examples/jobs/probe.ngc", "--machine", kMill}, kDir,
                                "run_probe");
  ASSERT_EQ(o.rc, 0) << o.err;
  EXPECT_NE(o.out.find("G38.2: tripped at x=20.0000 y=20.0000 z=-12.5"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("faults     none"), std::string::npos) << o.out;
  const Outcome refused = run_program(
      CPSTEP_BIN, {"run", kSrc + "/examples/jobs/probe.ngc", "--machine", kMill, "--vcd", (kDir / "p.vcd").string()},
      kDir, "run_probe_vcd");
  EXPECT_EQ(refused.rc, 2);
  EXPECT_NE(refused.err.find("a job that probes"), std::string::npos) << refused.err;
}

TEST(Probe, TheVerilatedCardProbesInLockstepWithTheFastEngine) {
  const fs::path job = write("short.ngc", "G21 G90\nG38.2 Z-1 F240\nG0 Z[#5063 + 0.1]\nG1 X0.2 F600\nM2\n");
  const run::SimProbeRun r = run::probe_job_on_sim(job.string(), mill_with_plate("mill_short.toml", -0.3).string(),
                                                   "hx8k", "lockstep");
  ASSERT_TRUE(r.ok()) << r.error << (r.errors.empty() ? "" : r.errors.front().str());
  ASSERT_EQ(r.probes.size(), 1u);
  EXPECT_TRUE(r.probes[0].tripped);
  EXPECT_LE(r.probe_at - r.probes[0].counts[2], overshoot_bound(r.machine, 4.0));
  EXPECT_EQ(r.pins, r.counts);
}

}  // namespace
}  // namespace cpstep::tb

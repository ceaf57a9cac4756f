// SPDX-License-Identifier: MIT
// Homing (issue 12, docs/HOST.md "Homing"): the host's cycle on the card's seek, on
// the simulated HX8K card with switches that close where the machine file puts them,
// driven by the positions counted on the STEP/DIR pins (run/home_sim.cpp). Checked
// against the machine file alone: each latch trip lies at the switch's place, or
// past it by no more than the steps the axis makes at its latch speed while the
// switch's closing reaches the card (the simulated world's granularity, a frame, the
// synchronizer and the filter); every back-off is exact; the offset makes the trip
// position_mm; the pins equal the card's counters; Z first (its sequence). A switch
// out of reach, and one the machine starts on, and `cpstep home --json` as a process.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <string>

#include "common/process.h"
#include "run/home.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;
const fs::path kDir = fs::path(CPSTEP_TEST_DIR) / "home";
const std::string kMill = std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/mill.toml";

// The mill's machine file with each axis's sim_switch_mm replaced (x, y, z);
// `short_cycle`: back-offs of 0.2 mm and the latch at 4 mm/s (a cycle the Verilated
// card runs in seconds).
fs::path mill_with_switches(const std::string& name, double x, double y, double z, bool short_cycle = false) {
  std::ifstream in(kMill);
  std::stringstream s;
  s << in.rdbuf();
  std::string text = s.str();
  if (short_cycle) {
    text = std::regex_replace(text, std::regex(R"(backoff_mm = [0-9.]+)"), "backoff_mm = 0.2");
    text = std::regex_replace(text, std::regex(R"(latch_mm_s = [0-9.]+)"), "latch_mm_s = 4");
  }
  const double at[3] = {x, y, z};
  std::string out;
  std::regex re(R"(sim_switch_mm = [-0-9.]+)");
  auto it = std::sregex_iterator(text.begin(), text.end(), re);
  size_t last = 0, k = 0;
  for (; it != std::sregex_iterator(); ++it, ++k) {
    out += text.substr(last, size_t(it->position()) - last);
    out += "sim_switch_mm = " + std::to_string(at[k]);
    last = size_t(it->position() + it->length());
  }
  out += text.substr(last);
  EXPECT_EQ(k, 3u) << "the mill homes x, y and z";
  fs::create_directories(kDir);
  const fs::path p = kDir / name;
  std::ofstream(p) << out;
  return p;
}

// The most steps an axis makes at `mm_s` while a switch's closing reaches the card
// and stops it: the world's wait chunk (1,024 clocks) or a whole frame (a POLL or
// READ: under 8,000 clocks at SCK = clk/8), the synchronizer (2), three filter
// samples and the level (3 P + 1), the fire decision (1); plus the step under way.
int64_t overshoot_bound(const plan::Machine& m, int a, double mm_s) {
  const double latency = 8000 + 2 + 3.0 * m.inputs.filter_cycles + 1 + 1;
  return int64_t(std::ceil(mm_s * m.axes[a].steps_per_mm * latency / m.card.clock_hz)) + 1;
}

void expect_homed(const run::SimHomeRun& r) {
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_TRUE(r.result.ok()) << r.result.error;
  const plan::Machine& m = r.machine;
  ASSERT_EQ(r.result.axes.size(), 3u);
  EXPECT_EQ(r.result.axes[0].axis, 2) << "Z first: its sequence is 0";
  for (const run::HomedAxis& h : r.result.axes) {
    SCOPED_TRACE(plan::kAxisLetters[h.axis]);
    const plan::AxisConfig& ax = m.axes[h.axis];
    const int64_t toward = ax.home.at_max ? 1 : -1;
    const int64_t place = r.switch_at[h.axis];
    // The latch trip at the switch, or a little past it toward it.
    const int64_t past = (h.latch_trip - place) * toward;
    EXPECT_GE(past, 0) << "tripped before the switch";
    EXPECT_LE(past, overshoot_bound(m, h.axis, ax.home.latch_mm_s));
    const int64_t search_past = (h.search_trip - place) * toward;
    EXPECT_GE(search_past, 0);
    EXPECT_LE(search_past, overshoot_bound(m, h.axis, ax.home.search_mm_s));
    // Back-offs exact; the final position is position_mm backed off.
    const int64_t backoff = std::llround(ax.home.backoff_mm * ax.steps_per_mm);
    EXPECT_EQ(h.final_count, h.latch_trip - toward * backoff);
    EXPECT_EQ(h.offset, h.latch_trip - std::llround(ax.home.position_mm * ax.steps_per_mm));
    EXPECT_NEAR(h.final_mm, ax.home.position_mm - double(toward) * ax.home.backoff_mm, 1e-9);
    ASSERT_GE(h.moves.size(), 4u);
    EXPECT_EQ(h.moves.back().to, h.final_count);
    for (const run::HomeMove& mv : h.moves)
      EXPECT_EQ(mv.tripped, mv.what == "search" || mv.what == "latch") << mv.what << ": only the approaches trip";
  }
  // The world saw each switch close where it is placed.
  for (const run::SimHomeSwitchTrip& t : r.trips) EXPECT_EQ(t.pins, r.switch_at[t.axis]);
  EXPECT_EQ(r.pins, r.counts) << "the STEP edges on the pins equal the card's counters";
}

// On the HX8K's chunk card and on its phase-timer card (hx8k_pt: the seek's moves
// planned with phases, the seek armed after the preamble).
TEST(Home, EveryAxisHomesAtItsSwitchOnTheFastEngine) {
  std::mt19937_64 rng(5061);
  for (int trial = 0; trial < 3; ++trial) {
    std::uniform_real_distribution<double> xy(-40.0, -3.0), z(3.0, 15.0);
    const fs::path m = mill_with_switches("mill_" + std::to_string(trial) + ".toml", xy(rng), xy(rng), z(rng));
    for (const char* board : {"hx8k", "hx8k_pt"}) {
      SCOPED_TRACE(std::to_string(trial) + " on " + board);
      expect_homed(run::home_on_sim(m.string(), board, "model"));
    }
  }
}

// The machine starts on X's switch: off it first, then the cycle.
TEST(Home, AnAxisStartingOnItsSwitchBacksOffFirst) {
  const fs::path m = mill_with_switches("mill_on.toml", 0.5, -3.0, 2.0);
  const run::SimHomeRun r = run::home_on_sim(m.string(), "hx8k", "model");
  expect_homed(r);
  const run::HomedAxis& x = r.result.axes.at(1);
  ASSERT_EQ(x.axis, 0);
  EXPECT_EQ(x.moves.front().what, "clear");
}

// A switch farther than 1.5 travels: the search ends untripped, the cycle stops with
// the reason and the card stands where the search ended.
TEST(Home, ASwitchOutOfReachIsReported) {
  const fs::path m = mill_with_switches("mill_far.toml", -3.0, -3.0, 200.0);
  const run::SimHomeRun r = run::home_on_sim(m.string(), "hx8k", "model");
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_NE(r.result.error.find("homing Z: no switch within"), std::string::npos) << r.result.error;
  EXPECT_EQ(r.pins, r.counts);
}

// `cpstep home --json` as a user runs it; and the Verilated card in lockstep with the
// fast engine through a short cycle (switches close by).
TEST(Home, TheCommandPrintsTheCycleAsJson) {
  const Outcome o = run_program(CPSTEP_BIN, {"home", "--machine", kMill, "--json"}, kDir, "home_json");
  ASSERT_EQ(o.rc, 0) << o.err;
  const nlohmann::json j = nlohmann::json::parse(o.out);
  EXPECT_TRUE(j["ok"].get<bool>());
  ASSERT_EQ(j["axes"].size(), 3u);
  EXPECT_EQ(j["axes"][0]["axis"], "z");
  for (const auto& a : j["axes"]) {
    const double spm = a["steps_per_mm"].get<double>();
    EXPECT_NEAR(double(a["latch_trip"].get<int64_t>()), double(a["sim_switch_steps"].get<int64_t>()), 2.0);
    const int64_t offset = a["offset"].get<int64_t>();
    EXPECT_EQ(a["latch_trip"].get<int64_t>() - offset, std::llround(a["position_mm"].get<double>() * spm))
        << "the latch trip is position_mm";
    EXPECT_NEAR(a["final_mm"].get<double>(), double(a["final_count"].get<int64_t>() - offset) / spm, 1e-9);
  }
  EXPECT_EQ(j["counts"], j["pins"]);
}

TEST(Home, TheVerilatedCardHomesInLockstepWithTheFastEngine) {
  const fs::path m = mill_with_switches("mill_lockstep.toml", -0.3, -0.2, 0.25, true);
  const run::SimHomeRun r = run::home_on_sim(m.string(), "hx8k", "lockstep");
  expect_homed(r);
}

}  // namespace
}  // namespace cpstep::tb

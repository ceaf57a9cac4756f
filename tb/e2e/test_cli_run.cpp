// SPDX-License-Identifier: MIT
// `cpstep run` and `cpstep plan` as a user runs them: the program runs as a
// process and its outputs are read back here with independent readers: the
// JSON report, the VCD through tb/cli/vcd_count, PNG signatures, and the
// command words decoded from docs/CORE.md's layout. Every expected value is
// derived in this file from the test's own G-code and the example machine.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "common/process.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kDir = fs::path(CPSTEP_TEST_DIR) / "cli_run";
const std::string kMachine = std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/plotter.toml";

// Runs `program args...` with stdout and stderr captured in files of kDir.
Outcome run(const std::string& program, const std::vector<std::string>& args, const std::string& tag) {
  return run_program(program, args, kDir, tag);
}
Outcome cpstep(const std::vector<std::string>& args, const std::string& tag) {
  return run(CPSTEP_BIN, args, tag);
}

fs::path write_job(const std::string& name, const std::string& text) {
  fs::create_directories(kDir);
  const fs::path p = kDir / name;
  std::ofstream(p) << text;
  return p;
}

// floor(mm * spm + 0.5): the rounding docs/PLANNING.md gives for segment ends.
int64_t steps(double mm, double spm) { return int64_t(std::floor(mm * spm + 0.5)); }

// The test job: x, y and z each move one way only (the arc is the quarter
// from the bottom to the right of its circle), so each axis's STEP edges
// number |final steps| and each DIR pin changes at most once.
const char* kJob =
    "G21 G90\n"
    "G1 X1 Y0.2 Z-0.1 F900\n"
    "G3 X2 Y1.2 I0 J1\n"
    "G1 X2.2 Y1.8\n"
    "M2\n";
// examples/machines/plotter.toml: 80 steps/mm on x and y, 400 on z.
const double kSpm[3] = {80, 80, 400};
const double kFinalMm[3] = {2.2, 1.8, -0.1};

// The command stream decoded by docs/CORE.md's word layout (4 axes).
struct Decoded {
  size_t configs = 0, starts = 0, segments = 0, chunks = 0, ends = 0;
  uint64_t moves = 0;
  int64_t delta[4] = {0, 0, 0, 0};
  bool counts_add_up = true;
  std::string error;
};
Decoded decode(const std::string& bytes) {
  Decoded d;
  if (bytes.size() % 4 != 0) {
    d.error = "size is not a multiple of 4";
    return d;
  }
  std::vector<uint32_t> w(bytes.size() / 4);
  for (size_t i = 0; i < w.size(); ++i)
    for (int b = 0; b < 4; ++b) w[i] |= uint32_t(uint8_t(bytes[4 * i + b])) << (8 * b);
  for (size_t i = 0; i < w.size();) {
    const uint32_t op = w[i] >> 28;
    if (op == 0x2) {
      ++d.configs, ++i;
    } else if (op == 0x3) {
      d.starts += (w[i] & 1), ++i;
    } else if (op == 0x1) {
      const uint32_t h0 = w[i], h1 = w[i + 1];
      const unsigned k = h0 >> 23 & 0xF, nchunks = h0 & 0xFFFF;
      const uint64_t u = h1 & 0xFFFFFF;
      d.ends += h0 >> 27 & 1;
      for (int a = 0; a < 4; ++a) {
        const int64_t v = int64_t(w[i + 2 + a] & 0xFFFFFF) << k;
        d.delta[a] += (h1 >> (24 + a) & 1) ? v : -v;
      }
      const unsigned words = (h0 >> 22 & 1) ? 3 : 2;  // chunks with add2: three words
      uint64_t count = 0;
      for (unsigned c = 0; c < nchunks; ++c) count += w[i + 6 + words * c + 1] & 0xFFFF;
      d.counts_add_up = d.counts_add_up && count == u << k;
      d.moves += u << k;
      ++d.segments;
      d.chunks += nchunks;
      i += 6 + words * nchunks;
    } else {
      d.error = "unexpected opcode at word " + std::to_string(i);
      return d;
    }
  }
  return d;
}

// "label   <number> ..." on a line of the plan summary.
uint64_t summary_number(const std::string& text, const std::string& label) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex("(^|\n)" + label + " +([0-9]+)"))) return UINT64_MAX;
  return std::stoull(m[2]);
}

bool is_png(const fs::path& p) {
  const std::string head = slurp(p).substr(0, 8);
  return head == std::string("\x89PNG\r\n\x1a\n", 8);
}

TEST(CliRun, SmallJobOnTheSimulatedCard) {
  const fs::path job = write_job("small.ngc", kJob);
  const fs::path report = kDir / "small.json", vcd = kDir / "small.vcd", plots = kDir / "plots",
                 bin = kDir / "small.bin";
  fs::remove_all(plots);
  fs::remove(report);
  fs::remove(vcd);
  const Outcome r = cpstep({"run", job.string(), "--machine", kMachine, "--report", report.string(),
                            "--vcd", vcd.string(), "--plots", plots.string(), "--klipper"},
                           "small_run");
  ASSERT_EQ(r.rc, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "") << "progress must be off when stderr is not a terminal";

  // The plan of the same job, and its command stream decoded here.
  const Outcome p = cpstep({"plan", job.string(), "--machine", kMachine, "-o", bin.string()}, "small_plan");
  ASSERT_EQ(p.rc, 0) << p.err;
  const Decoded d = decode(slurp(bin));
  ASSERT_EQ(d.error, "");
  EXPECT_EQ(d.configs, 3u * 5u) << "five CONFIG words per present axis";
  EXPECT_EQ(d.starts, 1u);
  EXPECT_EQ(d.ends, 1u);
  EXPECT_TRUE(d.counts_add_up);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(d.delta[a], steps(kFinalMm[a], kSpm[a])) << "axis " << a;
  EXPECT_EQ(d.delta[3], 0);

  const json rep = json::parse(slurp(report));
  for (const char* key : {"clock_hz", "segments", "chunks", "moves", "max_timing_error_cycles", "faults",
                          "stretches", "job_time_s", "axes"})
    EXPECT_TRUE(rep.contains(key)) << key;
  // The default board's card (the iCEBreaker's, 16.5 MHz), as the card reported it.
  EXPECT_EQ(rep["clock_hz"].get<double>(), 16.5e6);
  EXPECT_EQ(rep["card"]["name"], "icebreaker");
  EXPECT_EQ(rep["card"]["w"].get<int>(), 256);
  EXPECT_EQ(rep["faults"], json::array());
  EXPECT_EQ(rep["warnings"], json::array());
  EXPECT_EQ(rep["stretches"].get<int>(), 0);
  EXPECT_EQ(rep["segments"].get<uint64_t>(), d.segments);
  EXPECT_EQ(rep["chunks"].get<uint64_t>(), d.chunks);
  EXPECT_EQ(rep["moves"].get<uint64_t>(), d.moves);
  EXPECT_EQ(summary_number(p.out, "segments"), d.segments);
  EXPECT_EQ(summary_number(p.out, "chunks"), d.chunks);
  EXPECT_EQ(summary_number(r.out, "segments"), d.segments);
  EXPECT_EQ(summary_number(r.out, "chunks"), d.chunks);
  // Never late, at most the chunk tolerance (1 us = 18 cycles) early, plus the
  // rounding of an ideal time to a whole cycle.
  EXPECT_LE(rep["max_timing_error_cycles"].get<double>(), rep["clock_hz"].get<double>() * 1e-6 + 1);
  EXPECT_GT(rep["job_time_s"].get<double>(), 0.1);
  // The wire against Klipper's: the command file's bytes; Klipper's steps as
  // many as the pins' (every stepper that moves) and a tighter error costs more.
  EXPECT_EQ(rep["wire"]["command_bytes"].get<uint64_t>(), fs::file_size(bin));
  for (const char* k : {"klipper_25us", "klipper_1us", "klipper_pins_25us"}) {
    const json& w = rep["wire"][k];
    EXPECT_FALSE(w.contains("error")) << k;
    EXPECT_EQ(w["reset_step_clock"].get<uint64_t>(), 3u) << k;
    EXPECT_GE(w["queue_step"].get<uint64_t>(), 3u) << k;
    EXPECT_GT(w["bytes"].get<uint64_t>(), w["message_bytes"].get<uint64_t>()) << k;
  }
  EXPECT_GT(rep["wire"]["klipper_1us"]["bytes"].get<uint64_t>(), rep["wire"]["klipper_25us"]["bytes"].get<uint64_t>());

  // Per axis: positions, pulse timing from the driver presets (docs/PLANNING.md,
  // TMC2209 100/100/20/20 ns on x and y, A4988 1000/1000/200/200 ns on z, ns
  // rounded up to 16.5 MHz cycles) and the realized peaks against the limits.
  const json& axes = rep["axes"];
  ASSERT_EQ(axes.size(), 3u);
  const char* names[3] = {"x", "y", "z"};
  const double clk = rep["clock_hz"].get<double>();
  auto cycles_of = [clk](double ns) { return int(std::ceil(ns * clk / 1e9 - 1e-9)); };
  const int high[3] = {cycles_of(100), cycles_of(100), cycles_of(1000)},
            hold[3] = {cycles_of(20), cycles_of(20), cycles_of(200)};
  const double vmax[3] = {100, 100, 20}, amax[3] = {2000, 2000, 500}, jmax[3] = {50000, 50000, 10000};
  for (int a = 0; a < 3; ++a) {
    SCOPED_TRACE(names[a]);
    const json& ax = axes.at(names[a]);
    const int64_t expected = steps(kFinalMm[a], kSpm[a]);
    EXPECT_EQ(ax.at("steps_per_mm").get<double>(), kSpm[a]);
    EXPECT_EQ(ax.at("final_steps").get<int64_t>(), expected);
    EXPECT_DOUBLE_EQ(ax.at("final_mm").get<double>(), double(expected) / kSpm[a]);
    EXPECT_EQ(ax.at("pulses").get<int64_t>(), std::abs(expected));
    EXPECT_EQ(ax.at("step_high_cycles").get<int>(), high[a]);
    EXPECT_EQ(ax.at("step_low_cycles").get<int>(), high[a]);
    EXPECT_EQ(ax.at("dir_setup_cycles").get<int>(), hold[a]);
    EXPECT_EQ(ax.at("dir_hold_cycles").get<int>(), hold[a]);
    EXPECT_TRUE(ax.at("step_active_high").get<bool>());
    EXPECT_TRUE(ax.at("dir_positive_high").get<bool>());
    EXPECT_EQ(ax.at("max_velocity").get<double>(), vmax[a]);
    EXPECT_EQ(ax.at("max_accel").get<double>(), amax[a]);
    EXPECT_EQ(ax.at("max_jerk").get<double>(), jmax[a]);
    // realized_peaks' quantization bounds for the windows the report used.
    const double hv = ax.at("velocity_window_s").get<double>(), ha = ax.at("accel_window_s").get<double>(),
                 hj = ax.at("jerk_window_s").get<double>();
    EXPECT_NEAR(ax.at("velocity_tolerance").get<double>(), 1 / (hv * kSpm[a]), 1e-9);
    EXPECT_NEAR(ax.at("accel_tolerance").get<double>(), 4 / (ha * ha * kSpm[a]), 1e-6);
    EXPECT_NEAR(ax.at("jerk_tolerance").get<double>(), 6 / (hj * hj * hj * kSpm[a]), 1e-3);
    EXPECT_GT(ax.at("peak_velocity").get<double>(), 0);
    EXPECT_LE(ax.at("peak_velocity").get<double>(), vmax[a] + 1 / (hv * kSpm[a]));
    EXPECT_LE(ax.at("peak_accel").get<double>(), amax[a] + 4 / (ha * ha * kSpm[a]));
    EXPECT_LE(ax.at("peak_jerk").get<double>(), jmax[a] + 6 / (hj * hj * hj * kSpm[a]));
    EXPECT_TRUE(ax.at("within_limits").get<bool>());
  }

  // The pins: 8 signals, one leading STEP edge per step; DIR rises once on x
  // and y (reset leaves DIR low, the negative side, and both move +), z moves
  // - so its DIR stays low; a is not on this machine.
  const Outcome v = run(VCD_COUNT_BIN, {vcd.string()}, "small_vcd");
  ASSERT_EQ(v.rc, 0) << v.err;
  EXPECT_NE(v.out.find("signals step_x step_y step_z step_a dir_x dir_y dir_z dir_a torch\n"), std::string::npos)
      << v.out;
  for (int a = 0; a < 3; ++a) {
    const int64_t n = std::abs(steps(kFinalMm[a], kSpm[a]));
    const std::string line = "step_" + std::string(names[a]) + " width=1 rises=" + std::to_string(n) +
                             " falls=" + std::to_string(n) + " final=0\n";
    EXPECT_NE(v.out.find(line), std::string::npos) << line << v.out;
  }
  for (const char* line : {"step_a width=1 rises=0 falls=0 final=0\n", "dir_x width=1 rises=1 falls=0 final=1\n",
                           "dir_y width=1 rises=1 falls=0 final=1\n", "dir_z width=1 rises=0 falls=0 final=0\n",
                           "dir_a width=1 rises=0 falls=0 final=0\n"})
    EXPECT_NE(v.out.find(line), std::string::npos) << line << v.out;

  for (const char* png : {"path.png", "speed.png", "accel.png", "jerk.png"}) {
    EXPECT_TRUE(fs::exists(plots / png)) << png;
    EXPECT_TRUE(is_png(plots / png)) << png;
    EXPECT_GT(fs::file_size(plots / png), 1000u) << png;
  }
}

TEST(CliRun, PlanWritesExactlyTheWordsRunSends) {
  const fs::path job = write_job("small.ngc", kJob);
  const fs::path planned = kDir / "words_plan.bin", sent = kDir / "words_run.bin";
  fs::remove(planned);
  fs::remove(sent);
  const Outcome p = cpstep({"plan", job.string(), "--machine", kMachine, "-o", planned.string()}, "words_plan");
  ASSERT_EQ(p.rc, 0) << p.err;
  const Outcome r = cpstep({"run", job.string(), "--machine", kMachine, "--transport", "file", "--out",
                            sent.string()},
                           "words_run");
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::string a = slurp(planned), b = slurp(sent);
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_EQ(decode(b).error, "");
}

// The card's watchdog (docs/CORE.md "Watchdog"): kept alive through the job by
// POLLs at least every quarter of it (a short one asks for more of them than none),
// the job whole either way; a timeout the card's field cannot hold, or one shorter
// than four times the longest frame, is refused before anything is sent.
TEST(CliRun, WatchdogIsKeptAliveOrRefusedBeforeAnythingIsSent) {
  const fs::path job = write_job("small.ngc", kJob);
  const auto run = [&](const std::string& seconds) {
    const fs::path report = kDir / ("watchdog_" + seconds + ".json");
    fs::remove(report);
    const Outcome r = cpstep({"run", job.string(), "--machine", kMachine, "--watchdog", seconds, "--report",
                              report.string()},
                             "watchdog_" + seconds);
    return std::pair{r, report};
  };
  const auto [off, off_report] = run("0");
  const auto [on, on_report] = run("0.05");
  ASSERT_EQ(off.rc, 0) << off.err;
  ASSERT_EQ(on.rc, 0) << on.err;
  const json a = json::parse(slurp(off_report)), b = json::parse(slurp(on_report));
  EXPECT_EQ(a["faults"], json::array());
  EXPECT_EQ(b["faults"], json::array());
  EXPECT_EQ(b["moves"], a["moves"]);
  const double job_s = b["job_time_s"].get<double>();
  EXPECT_GE(b["link"]["polls"].get<double>(), job_s / 0.0125 - 2) << "a POLL at least every 12.5 ms of the job";
  EXPECT_GT(b["link"]["polls"].get<uint64_t>(), a["link"]["polls"].get<uint64_t>());
  // The watchdog sees no gap longer than a quarter of it and a frame (at most 8.2 ms
  // for the iCEBreaker's 512-word buffer at 2.06 MHz).
  EXPECT_LE(b["link"]["longest_gap_s"].get<double>(), 0.0125 + 0.0083);
  EXPECT_GT(b["link"]["longest_gap_s"].get<double>(), 0.0);

  for (const auto& [seconds, words] : {std::pair<std::string, std::string>{"100", "the longest the card's field holds"},
                                       {"0.001", "at least four times"}}) {
    const auto [r, report] = run(seconds);
    EXPECT_EQ(r.rc, 2) << seconds;
    EXPECT_NE(r.err.find("--watchdog"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("nothing was sent"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(report)) << report;
  }
}

// Feed override and hold (docs/CORE.md "Feed hold and override", docs/HOST.md): on
// the HX8K card --override 50 makes every move take twice its time (the job time
// doubles, the moves and end are the same); --feed holds and resumes (the job takes
// the time it stood longer); both are refused before anything is sent on the
// iCEBreaker card (no feed hold), above the machine's max_override_pct, or malformed.
TEST(CliRun, FeedOverrideAndHoldOrRefusedBeforeAnythingIsSent) {
  const fs::path job = write_job("small.ngc", kJob);
  const auto run = [&](const std::string& name, std::vector<std::string> extra) {
    const fs::path report = kDir / ("feed_" + name + ".json");
    fs::remove(report);
    std::vector<std::string> args = {"run", job.string(), "--machine", kMachine, "--report", report.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const Outcome r = cpstep(args, "feed_" + name);
    return std::pair{r, report};
  };
  const auto [plain, plain_report] = run("plain", {"--board", "hx8k"});
  const auto [half, half_report] = run("half", {"--board", "hx8k", "--override", "50"});
  const auto [held, held_report] = run("held", {"--board", "hx8k", "--feed", "0.01:hold,0.6:resume"});
  ASSERT_EQ(plain.rc, 0) << plain.err;
  ASSERT_EQ(half.rc, 0) << half.err;
  ASSERT_EQ(held.rc, 0) << held.err;
  const json p = json::parse(slurp(plain_report)), h = json::parse(slurp(half_report)),
             d = json::parse(slurp(held_report));
  // Without --klipper: the card's bytes alone, Klipper's not counted.
  EXPECT_EQ(p["wire"].size(), 1u) << p["wire"].dump();
  EXPECT_GT(p["wire"]["command_bytes"].get<uint64_t>(), 0u);
  EXPECT_NE(plain.out.find(" command bytes (--klipper: Klipper's queue_step bytes for the same steps)"),
            std::string::npos)
      << plain.out;
  for (const json* r : {&h, &d}) {
    EXPECT_EQ((*r)["faults"], json::array());
    EXPECT_EQ((*r)["moves"], p["moves"]);
    EXPECT_EQ((*r)["move_events"], p["move_events"]);
    for (const auto& [axis, a] : p["axes"].items())
      EXPECT_EQ((*r)["axes"][axis]["final_steps"], a["final_steps"]) << axis;
    EXPECT_TRUE((*r)["feed_scaled"].get<bool>());
  }
  EXPECT_FALSE(p["feed_scaled"].get<bool>());
  const double t = p["job_time_s"].get<double>();
  EXPECT_NEAR(h["job_time_s"].get<double>() / t, 2.0, 0.01) << "every interval doubled";
  ASSERT_EQ(d["feed"].size(), 2u);
  EXPECT_EQ(d["feed"][0]["what"], "hold");
  EXPECT_EQ(d["feed"][1]["what"], "resume");
  const double stood = d["feed"][1]["taken_s"].get<double>() - d["feed"][0]["taken_s"].get<double>();
  EXPECT_GT(d["job_time_s"].get<double>(), t + stood - 2 * d["feed_ramp"]["hold_s"].get<double>());
  EXPECT_NE(held.out.find("feed       hold taken at"), std::string::npos) << held.out;

  for (const auto& [name, extra, words] :
       {std::tuple<std::string, std::vector<std::string>, std::string>{
            "icebreaker", {"--override", "50"}, "has no feed hold or override"},
        {"above", {"--board", "hx8k", "--override", "150"}, "feed.max_override_pct"},
        {"malformed", {"--board", "hx8k", "--feed", "soon:hold"}, "--feed"}}) {
    const auto [r, report] = run(name, extra);
    EXPECT_EQ(r.rc, 2) << name;
    EXPECT_NE(r.err.find(words), std::string::npos) << name << ": " << r.err;
    EXPECT_NE(r.err.find("nothing was sent"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(report)) << report;
  }
}

// The machine file's limit switches reach the card (docs/CORE.md "Inputs"): on the
// HX8K card, whose simulated limit pins are low, x's max configured active low is
// closed, so the job (x moves up) stops with LIMIT before x's first step; configured
// active high (open) it runs whole. The iCEBreaker card, without inputs, refuses the
// machine file at the key before anything is sent.
TEST(CliRun, MachineFileLimitSwitchesReachTheCard) {
  const fs::path job = write_job("small.ngc", kJob);
  std::string text = slurp(kMachine);
  const auto with_limit = [&](const std::string& level) {
    std::string t = text;
    t.replace(t.find("[axes.x]\n"), 9, "[axes.x]\nlimit_max = \"" + level + "\"\n");
    const fs::path p = kDir / ("limit_" + level + ".toml");
    std::ofstream(p) << t;
    return p.string();
  };
  const auto run_on = [&](const std::string& board, const std::string& level) {
    const fs::path report = kDir / ("limit_" + board + "_" + level + ".json");
    fs::remove(report);
    const Outcome r = cpstep({"run", job.string(), "--machine", with_limit(level), "--board", board, "--report",
                              report.string()},
                             "limit_" + board + "_" + level);
    return std::pair{r, report};
  };
  const auto [closed, closed_report] = run_on("hx8k", "active_low");
  EXPECT_NE(closed.rc, 0);
  const json c = json::parse(slurp(closed_report));
  ASSERT_FALSE(c["faults"].empty());
  EXPECT_NE(c["faults"].dump().find("LIMIT"), std::string::npos) << c["faults"].dump();
  EXPECT_EQ(c["axes"]["x"]["final_steps"], 0) << c["axes"].dump();

  const auto [open, open_report] = run_on("hx8k", "active_high");
  ASSERT_EQ(open.rc, 0) << open.out << open.err;
  EXPECT_EQ(json::parse(slurp(open_report))["faults"], json::array());

  const auto [refused, refused_report] = run_on("icebreaker", "active_high");
  EXPECT_EQ(refused.rc, 2);
  EXPECT_NE(refused.err.find("limit switches, but the card"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("has no limit or probe inputs"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(refused_report));
}

// A refused job: exit 2, the file:line:col on stderr, nothing on stdout and
// no output file of any kind.
void expect_refused(const std::string& name, const std::string& text, const std::string& where,
                    const std::string& words) {
  const fs::path job = write_job(name, text);
  const fs::path report = kDir / (name + ".json"), vcd = kDir / (name + ".vcd"), plots = kDir / (name + ".plots"),
                 bin = kDir / (name + ".bin");
  for (const fs::path& f : {report, vcd, plots, bin}) fs::remove_all(f);
  const Outcome r = cpstep({"run", job.string(), "--machine", kMachine, "--report", report.string(), "--vcd",
                            vcd.string(), "--plots", plots.string()},
                           name + "_run");
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find(job.string() + ":" + where + ": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  const Outcome p = cpstep({"plan", job.string(), "--machine", kMachine, "-o", bin.string()}, name + "_plan");
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find(job.string() + ":" + where + ": "), std::string::npos) << p.err;
  const Outcome f = cpstep({"run", job.string(), "--machine", kMachine, "--transport", "file", "--out",
                            bin.string()},
                           name + "_file");
  EXPECT_EQ(f.rc, 2);
  for (const fs::path& out : {report, vcd, plots, bin}) EXPECT_FALSE(fs::exists(out)) << out;
}

// A plasma job from `cpstep cam` (M3, G4 pierce, cut, M5 per contour) on the
// simulated card: the torch pin (VCD signal `torch`) goes on once and off once per
// contour, each at its move boundary (the report's check), with at least the
// G-code's pierce delay before the cut's first step; `cpstep check` holds the VCD's
// torch to the plan, and a trace that lost one contour's torch is a finding.
TEST(CliRun, PlasmaTorchSwitchesAtItsMoveBoundaries) {
  const std::string src = CPSTEP_SOURCE_DIR;
  const fs::path job = kDir / "tabs.ngc", report = kDir / "tabs.json", vcd = kDir / "tabs.vcd";
  fs::create_directories(kDir);
  const Outcome cam = cpstep({"cam", src + "/examples/plasma/tab.dxf", "--sheet", src + "/examples/plasma/small.toml",
                              "-o", job.string()},
                             "torch_cam");
  ASSERT_EQ(cam.rc, 0) << cam.err;
  // The G-code's own contours and pierce: M3 lines, and the G4 P after each.
  const std::string text = slurp(job);
  size_t contours = 0;
  double pierce = 1e9;
  std::istringstream lines(text);
  bool after_m3 = false;
  for (std::string line; std::getline(lines, line);) {
    if (std::regex_search(line, std::regex(R"(^M0*3(\s|$))"))) ++contours, after_m3 = true;  // not M30
    else if (after_m3 && line.rfind("G4 P", 0) == 0) pierce = std::min(pierce, std::stod(line.substr(4))), after_m3 = false;
  }
  ASSERT_GE(contours, 2u);
  ASSERT_LT(pierce, 1e9);
  const std::string machine = src + "/examples/machines/router.toml";
  const Outcome run = cpstep({"run", job.string(), "--machine", machine, "--report", report.string(), "--vcd",
                              vcd.string(), "--no-progress"},
                             "torch_run");
  ASSERT_EQ(run.rc, 0) << run.out << run.err;
  const json r = json::parse(slurp(report));
  ASSERT_TRUE(r.contains("torch")) << r.dump();
  EXPECT_EQ(r["torch"]["planned_switches"].get<uint64_t>(), 2 * contours);
  EXPECT_EQ(r["torch"]["edges"].get<uint64_t>(), 2 * contours);
  EXPECT_TRUE(r["torch"]["as_planned"].get<bool>());
  EXPECT_EQ(r["torch"]["max_delay_cycles"].get<double>(), 0);
  EXPECT_GE(r["torch"]["min_pierce_s"].get<double>(), pierce - 1e-6);
  EXPECT_NE(run.out.find("torch      " + std::to_string(2 * contours) + " switches planned"), std::string::npos)
      << run.out;

  const Outcome check = cpstep({"check", "--vcd", vcd.string(), "--job", job.string(), "--machine", machine, "--json",
                                (kDir / "tabs_check.json").string()},
                               "torch_check");
  EXPECT_EQ(check.rc, 0) << check.out << check.err;
  const json v = json::parse(slurp(kDir / "tabs_check.json"));
  EXPECT_TRUE(v["conforms"].get<bool>());
  EXPECT_EQ(v["torch"]["edges"].get<uint64_t>(), 2 * contours);

  // The same trace without the first contour's torch: drop its first two changes.
  std::string code;
  {
    const std::regex var(R"(\$var wire 1 (\S+) torch \$end)");
    std::smatch m;
    const std::string vtext = slurp(vcd);
    ASSERT_TRUE(std::regex_search(vtext, m, var));
    code = m[1];
    std::istringstream in(vtext);
    std::ostringstream out;
    int dropped = 0;
    bool in_body = false;
    for (std::string line; std::getline(in, line);) {
      in_body = in_body || line.rfind("$enddefinitions", 0) == 0;
      if (in_body && dropped < 2 && line.size() == code.size() + 1 && line.substr(1) == code && line[0] != 'x' &&
          !(dropped == 0 && line[0] == '0')) {
        ++dropped;
        continue;
      }
      out << line << '\n';
    }
    ASSERT_EQ(dropped, 2);
    std::ofstream(kDir / "tabs_lost.vcd") << out.str();
  }
  const Outcome lost = cpstep({"check", "--vcd", (kDir / "tabs_lost.vcd").string(), "--job", job.string(), "--machine",
                               machine, "--json", (kDir / "tabs_lost.json").string()},
                              "torch_lost");
  EXPECT_NE(lost.rc, 0);
  const json lv = json::parse(slurp(kDir / "tabs_lost.json"));
  EXPECT_FALSE(lv["conforms"].get<bool>());
  EXPECT_EQ(lv["counts"].value("torch", 0), 1) << lv.dump();
}

TEST(CliRun, MalformedGcodeIsRefusedWithItsPosition) {
  // Line 3, column 7: a B word (a rotary axis the subset does not have).
  expect_refused("malformed.ngc", "G21 G90\nG1 X1 F600\nG1 X2 B5\n", "3:7", "axis B is not supported");
}

TEST(CliRun, MoveOutsideTheTravelIsRefusedNamingItsLine) {
  // plotter.toml: x travels 0..200 mm; the block on line 3 goes to 250.
  expect_refused("far.ngc", "G21 G90\nG1 X10 F600\nG1 X250\n", "3:1", "outside the travel");
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// `cpstep run --state`, `--stop-after-contours` and `--resume` (docs/PLASMA.md
// "Resume") as an operator runs them, on the cut job `cpstep cam` makes of two
// tabs (four contours). The programs run as processes; what they did is read
// back from their pin VCDs (host/check's reader) and state files, and every
// expected value comes from the job's G-code, read here line by line.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "check/vcd.h"
#include "common/process.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = CPSTEP_SOURCE_DIR;
const std::string kMachine = kSource + "/examples/machines/seed002.toml";
constexpr double kSpm = 80;  // seed002.toml's x and y

// A directory of the test's own (ctest runs the tests in parallel).
fs::path test_dir() {
  const auto* t = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::path(CPSTEP_TEST_DIR) / "cli_resume" / t->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

Outcome cpstep(const fs::path& dir, const std::vector<std::string>& args, const std::string& tag) {
  return run_program(CPSTEP_BIN, args, dir, tag);
}

int64_t steps(double mm) { return int64_t(std::floor(mm * kSpm + 0.5)); }

// ---- The job, read here: cpstep cam writes G21 G90, absolute X/Y words, and
// per contour M3, G4 P<s>, the cut, M5.
struct Contour {
  int m5_line = 0;
  double pierce_x = 0, pierce_y = 0;  // where M3 finds the torch
  double end_x = 0, end_y = 0;        // where M5 does
  double pierce_s = 0;
};
struct CamJob {
  std::string text;
  std::vector<Contour> contours;
  double end_x = 0, end_y = 0;
};

CamJob read_job(const fs::path& file) {
  CamJob j;
  j.text = slurp(file);
  EXPECT_NE(j.text.find("G21 G90"), std::string::npos);
  EXPECT_EQ(j.text.find("G91"), std::string::npos);
  EXPECT_EQ(j.text.find("G92"), std::string::npos);
  std::istringstream in(j.text);
  const std::regex word(R"(([A-Z])\s*(-?[0-9.]+))");
  double x = 0, y = 0;
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    line = std::regex_replace(line, std::regex(R"(\([^)]*\))"), "");
    for (std::sregex_iterator w(line.begin(), line.end(), word), end; w != end; ++w) {
      const char letter = (*w)[1].str()[0];
      const double v = std::stod((*w)[2]);
      if (letter == 'X') x = v;
      if (letter == 'Y') y = v;
      if (letter == 'M' && v == 3) j.contours.push_back({0, x, y, 0, 0, 0});
      if (letter == 'P') j.contours.back().pierce_s = v;
      if (letter == 'M' && v == 5) {
        j.contours.back().m5_line = n;
        j.contours.back().end_x = x;
        j.contours.back().end_y = y;
      }
    }
  }
  j.end_x = x;
  j.end_y = y;
  return j;
}

fs::path make_job(const fs::path& dir) {
  const fs::path job = dir / "tabs.ngc";
  const Outcome cam = cpstep(dir,
                             {"cam", kSource + "/examples/plasma/tab.dxf", "--sheet",
                              kSource + "/examples/plasma/small.toml", "-o", job.string()},
                             "cam");
  EXPECT_EQ(cam.rc, 0) << cam.err;
  return job;
}

// FNV-1a 64 of the file's bytes (the offset basis and prime of the FNV definition).
std::string fnv1a64(const std::string& bytes) {
  uint64_t h = 14695981039346656037ULL;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ULL;
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// ---- The pins: one move per time with a leading STEP edge (seed002: active
// high, DIR high = positive), its steps per axis.
struct Move {
  uint64_t cycle = 0;
  int64_t d[3] = {0, 0, 0};
  bool same_steps(const Move& o) const { return d[0] == o.d[0] && d[1] == o.d[1] && d[2] == o.d[2]; }
};
struct Pins {
  std::vector<Move> moves;
  int torch_rises = -1;  // -1: the VCD has no torch pin
};

Pins read_pins(const fs::path& vcd, double clock_hz) {
  Pins p;
  const auto trace = check::read_vcd(vcd);
  EXPECT_TRUE(trace.ok()) << plan::join(trace.errors);
  if (!trace.ok()) return p;
  std::map<uint64_t, Move> by_time;
  const char* axes[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const auto step = trace->find(std::string("step_") + axes[a]);
    const auto dir = trace->find(std::string("dir_") + axes[a]);
    EXPECT_EQ(step.size(), 1u);
    EXPECT_EQ(dir.size(), 1u);
    if (step.size() != 1 || dir.size() != 1) return p;
    const auto& dc = trace->changes[dir[0]->code];
    size_t di = 0;
    bool positive = false, high = false;
    for (const check::VcdChange& c : trace->changes[step[0]->code]) {
      while (di < dc.size() && dc[di].time <= c.time) positive = dc[di++].bits & 1;
      const bool now = c.bits & 1;
      if (now && !high) {
        Move& m = by_time[c.time];
        m.cycle = uint64_t(std::llround(double(c.time) * 1e-12 * clock_hz));
        m.d[a] += positive ? 1 : -1;
      }
      high = now;
    }
  }
  for (auto& [t, m] : by_time) p.moves.push_back(m);
  if (const auto torch = trace->find("torch"); torch.size() == 1) {
    p.torch_rises = 0;
    bool high = false;
    for (const check::VcdChange& c : trace->changes[torch[0]->code]) {
      p.torch_rises += (c.bits & 1) && !high;
      high = c.bits & 1;
    }
  }
  return p;
}

// The moves after which the pins pause at least `seconds` (a pierce dwell:
// other stops pause for a step or two at the jerk-limited start, ~34 ms here).
std::vector<size_t> pauses(const std::vector<Move>& m, double seconds, double clock_hz) {
  std::vector<size_t> at;
  for (size_t i = 1; i < m.size(); ++i)
    if (double(m[i].cycle - m[i - 1].cycle) >= seconds * clock_hz) at.push_back(i);
  return at;
}

double min_pierce(const CamJob& j) {
  double s = 1e9;
  for (const Contour& c : j.contours) s = std::min(s, c.pierce_s);
  return s;
}

// Steps summed over moves [from, to).
std::array<int64_t, 3> sum(const std::vector<Move>& m, size_t from, size_t to) {
  std::array<int64_t, 3> s{};
  for (size_t i = from; i < to; ++i)
    for (int a = 0; a < 3; ++a) s[a] += m[i].d[a];
  return s;
}

json read_json(const fs::path& f) { return json::parse(slurp(f)); }

// The full job, stopped after contour 2, then resumed: the three runs.
struct Runs {
  fs::path dir, job;
  CamJob gcode;
  double clock_hz = 0;
  Outcome full, stop, resume;
};

Runs three_runs() {
  Runs r;
  r.dir = test_dir();
  r.job = make_job(r.dir);
  r.gcode = read_job(r.job);
  const auto run = [&](const std::string& tag, std::vector<std::string> extra) {
    std::vector<std::string> args = {"run", r.job.string(), "--machine", kMachine, "--no-progress", "--vcd",
                                     (r.dir / (tag + ".vcd")).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return cpstep(r.dir, args, tag);
  };
  r.full = run("full", {"--report", (r.dir / "full_report.json").string(), "--state", (r.dir / "full.json").string()});
  r.stop = run("stop", {"--stop-after-contours", "2", "--state", (r.dir / "stop.json").string()});
  r.resume = run("resume", {"--resume", (r.dir / "stop.json").string(), "--state", (r.dir / "resumed.json").string()});
  if (fs::exists(r.dir / "full_report.json")) r.clock_hz = read_json(r.dir / "full_report.json")["clock_hz"];
  return r;
}

void expect_position(const json& state, int64_t x, int64_t y) {
  EXPECT_EQ(state["position_steps"]["x"].get<int64_t>(), x) << state.dump();
  EXPECT_EQ(state["position_steps"]["y"].get<int64_t>(), y) << state.dump();
  EXPECT_EQ(state["position_steps"]["z"].get<int64_t>(), 0) << state.dump();
  EXPECT_NEAR(state["position_mm"]["x"].get<double>(), double(x) / kSpm, 1e-9);
  EXPECT_NEAR(state["position_mm"]["y"].get<double>(), double(y) / kSpm, 1e-9);
}

// A state after the job's end: every contour done, the last one's M5, the job's last point.
void expect_finished(const Runs& r, const json& s) {
  EXPECT_EQ(s["contours_completed"], 4);
  EXPECT_EQ(s["ended"], "finished");
  EXPECT_EQ(s["last_m5_line"], r.gcode.contours[3].m5_line);
  expect_position(s, steps(r.gcode.end_x), steps(r.gcode.end_y));
}

TEST(CliResume, StopAfterTwoContoursRecordsTheState) {
  const Runs r = three_runs();
  ASSERT_EQ(r.gcode.contours.size(), 4u);
  ASSERT_EQ(r.stop.rc, 0) << r.stop.out << r.stop.err;
  EXPECT_EQ(r.stop.err, "");
  const json s = read_json(r.dir / "stop.json");
  EXPECT_EQ(s["version"], 1);
  EXPECT_EQ(s["job"], r.job.string());
  EXPECT_EQ(s["job_fnv1a64"], fnv1a64(r.gcode.text));
  EXPECT_EQ(s["machine"], kMachine);
  EXPECT_EQ(s["contours"], 4);
  EXPECT_EQ(s["contours_completed"], 2);
  EXPECT_EQ(s["ended"], "stopped");
  const Contour& c2 = r.gcode.contours[1];
  EXPECT_EQ(s["last_m5_line"], c2.m5_line);
  expect_position(s, steps(c2.end_x), steps(c2.end_y));
  EXPECT_NE(r.stop.out.find("contours   2 of 4 done"), std::string::npos) << r.stop.out;
  // The pins went there too, and pierced twice.
  const Pins p = read_pins(r.dir / "stop.vcd", r.clock_hz);
  const auto at = sum(p.moves, 0, p.moves.size());
  EXPECT_EQ(at[0], steps(c2.end_x));
  EXPECT_EQ(at[1], steps(c2.end_y));
  EXPECT_EQ(pauses(p.moves, min_pierce(r.gcode), r.clock_hz).size(), 2u);
  if (p.torch_rises >= 0) {
    EXPECT_EQ(p.torch_rises, 2);
  }
  // No temporary file is left beside the state.
  for (const auto& e : fs::directory_iterator(r.dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();

  // The uninterrupted run's state: every contour, ended finished, at the job's end.
  ASSERT_EQ(r.full.rc, 0) << r.full.out << r.full.err;
  expect_finished(r, read_json(r.dir / "full.json"));
}

TEST(CliResume, ResumeRapidsToTheNextPierceAndEndsAtTheJobsEnd) {
  const Runs r = three_runs();
  ASSERT_EQ(r.resume.rc, 0) << r.resume.out << r.resume.err;
  EXPECT_EQ(r.resume.err, "");
  EXPECT_NE(r.resume.out.find("resumed    from "), std::string::npos) << r.resume.out;
  const Contour &c2 = r.gcode.contours[1], &c3 = r.gcode.contours[2];
  const Pins p = read_pins(r.dir / "resume.vcd", r.clock_hz);
  const std::vector<size_t> pierces = pauses(p.moves, min_pierce(r.gcode), r.clock_hz);
  // One pierce dwell per contour left (3 and 4), each as long as its G4 (plus
  // the first step's time from rest).
  ASSERT_EQ(pierces.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const double gap = double(p.moves[pierces[k]].cycle - p.moves[pierces[k] - 1].cycle) / r.clock_hz;
    EXPECT_GE(gap, r.gcode.contours[2 + k].pierce_s);
    EXPECT_LT(gap, r.gcode.contours[2 + k].pierce_s + 0.05);
  }
  if (p.torch_rises >= 0) {
    EXPECT_EQ(p.torch_rises, 2);
  }
  // Before the first pierce: the rapid from contour 2's M5 to contour 3's pierce point.
  const auto rapid = sum(p.moves, 0, pierces[0]);
  EXPECT_EQ(rapid[0], steps(c3.pierce_x) - steps(c2.end_x));
  EXPECT_EQ(rapid[1], steps(c3.pierce_y) - steps(c2.end_y));
  EXPECT_EQ(rapid[2], 0);
  // The job's end, in the pins and in the new state.
  const auto moved = sum(p.moves, 0, p.moves.size());
  EXPECT_EQ(steps(c2.end_x) + moved[0], steps(r.gcode.end_x));
  EXPECT_EQ(steps(c2.end_y) + moved[1], steps(r.gcode.end_y));
  expect_finished(r, read_json(r.dir / "resumed.json"));
}

TEST(CliResume, StoppedAndResumedRunsCutWhatOneRunCuts) {
  const Runs r = three_runs();
  ASSERT_EQ(r.full.rc, 0) << r.full.err;
  ASSERT_EQ(r.stop.rc, 0) << r.stop.err;
  ASSERT_EQ(r.resume.rc, 0) << r.resume.err;
  const Pins full = read_pins(r.dir / "full.vcd", r.clock_hz);
  const Pins stop = read_pins(r.dir / "stop.vcd", r.clock_hz);
  const Pins resume = read_pins(r.dir / "resume.vcd", r.clock_hz);
  // The stop run is the full run's first moves, at the same cycles; the resumed
  // run (its rapid is the full run's after contour 2) the rest, with the same
  // steps and times: its plan starts at cycle 0 where the full run's part starts
  // between two cycles, so each move may round to its chunk time differently,
  // within the chunk tolerance (seed002.toml: 1 us) each way.
  ASSERT_EQ(stop.moves.size() + resume.moves.size(), full.moves.size());
  const double tolerance = 2 * 1e-6 * r.clock_hz + 1;
  size_t off_steps = 0, off_time = 0;
  for (size_t i = 0; i < full.moves.size(); ++i) {
    const bool first = i < stop.moves.size();
    const Move& part = first ? stop.moves[i] : resume.moves[i - stop.moves.size()];
    const Move& part0 = first ? stop.moves[0] : resume.moves[0];
    const Move& full0 = first ? full.moves[0] : full.moves[stop.moves.size()];
    off_steps += !part.same_steps(full.moves[i]);
    const double dt = double(part.cycle - part0.cycle) - double(full.moves[i].cycle - full0.cycle);
    off_time += first ? dt != 0 : std::abs(dt) > tolerance;
  }
  EXPECT_EQ(off_steps, 0u);
  EXPECT_EQ(off_time, 0u);
  // Per contour, the moves from its pierce to the next pierce (or the end).
  const double pierce = min_pierce(r.gcode);
  EXPECT_EQ(pauses(full.moves, pierce, r.clock_hz).size(), 4u);
  EXPECT_EQ(pauses(stop.moves, pierce, r.clock_hz).size() + pauses(resume.moves, pierce, r.clock_hz).size(), 4u);
}

TEST(CliResume, FaultMidContourResumesThatContourWithAFreshPierce) {
  Runs r = three_runs();
  ASSERT_EQ(r.full.rc, 0) << r.full.err;
  const Pins full = read_pins(r.dir / "full.vcd", r.clock_hz);
  const Pins stop = read_pins(r.dir / "stop.vcd", r.clock_hz);
  const std::vector<size_t> pierces = pauses(full.moves, min_pierce(r.gcode), r.clock_hz);
  ASSERT_EQ(pierces.size(), 4u);
  // Stop the card (--max-cycles: E-stop) halfway through contour 2's cut: after
  // its pierce, before its M5 (the stop run's last move).
  const uint64_t from = full.moves[pierces[1]].cycle, to = full.moves[stop.moves.size() - 1].cycle;
  ASSERT_LT(from, to);
  const fs::path vcd = r.dir / "fault.vcd", state = r.dir / "fault.json";
  const Outcome fault = cpstep(r.dir,
                               {"run", r.job.string(), "--machine", kMachine, "--no-progress", "--vcd", vcd.string(),
                                "--max-cycles", std::to_string((from + to) / 2), "--state", state.string()},
                               "fault");
  ASSERT_EQ(fault.rc, 1) << fault.out << fault.err;
  EXPECT_NE(fault.err.find("TIMEOUT"), std::string::npos) << fault.err;
  const json s = read_json(state);
  EXPECT_EQ(s["ended"], "fault");
  EXPECT_EQ(s["contours_completed"], 1);
  EXPECT_EQ(s["last_m5_line"], r.gcode.contours[0].m5_line);
  const Pins cut = read_pins(vcd, r.clock_hz);
  ASSERT_GT(cut.moves.size(), pierces[1]);
  ASSERT_LT(cut.moves.size(), stop.moves.size());
  const auto at = sum(cut.moves, 0, cut.moves.size());
  expect_position(s, at[0], at[1]);

  const fs::path again = r.dir / "again.vcd";
  const Outcome resume = cpstep(r.dir,
                                {"run", r.job.string(), "--machine", kMachine, "--no-progress", "--vcd", again.string(),
                                 "--resume", state.string(), "--state", (r.dir / "again.json").string()},
                                "again");
  ASSERT_EQ(resume.rc, 0) << resume.out << resume.err;
  const Pins p = read_pins(again, r.clock_hz);
  const std::vector<size_t> own = pauses(p.moves, min_pierce(r.gcode), r.clock_hz);
  ASSERT_EQ(own.size(), 3u);  // contour 2 again, 3 and 4
  const Contour& c2 = r.gcode.contours[1];
  const auto rapid = sum(p.moves, 0, own[0]);
  EXPECT_EQ(at[0] + rapid[0], steps(c2.pierce_x));
  EXPECT_EQ(at[1] + rapid[1], steps(c2.pierce_y));
  // From contour 2's pierce on, the full run's moves.
  ASSERT_EQ(p.moves.size() - own[0], full.moves.size() - pierces[1]);
  size_t off = 0;
  for (size_t i = own[0]; i < p.moves.size(); ++i) off += !p.moves[i].same_steps(full.moves[pierces[1] + i - own[0]]);
  EXPECT_EQ(off, 0u);
  expect_position(read_json(r.dir / "again.json"), steps(r.gcode.end_x), steps(r.gcode.end_y));
}

// ---- Refusals: exit 2, the reason on stderr, nothing run (no VCD, no state).
struct Refusal {
  Outcome o;
  fs::path vcd, state;
};
Refusal resume_with(const fs::path& dir, const fs::path& job, const fs::path& state_file, const std::string& tag) {
  Refusal f{{}, dir / (tag + ".vcd"), dir / (tag + "_out.json")};
  f.o = cpstep(dir,
               {"run", job.string(), "--machine", kMachine, "--no-progress", "--resume", state_file.string(), "--vcd",
                f.vcd.string(), "--state", f.state.string()},
               tag);
  return f;
}
void expect_refused(const Refusal& f, const std::vector<std::string>& said) {
  EXPECT_EQ(f.o.rc, 2) << f.o.out << f.o.err;
  for (const std::string& s : said) EXPECT_NE(f.o.err.find(s), std::string::npos) << s << "\n" << f.o.err;
  EXPECT_EQ(f.o.out, "");
  EXPECT_FALSE(fs::exists(f.vcd));
  EXPECT_FALSE(fs::exists(f.state));
}

// The stop run's state, edited.
fs::path edited_state(const Runs& r, const std::string& name, const std::function<void(json&)>& edit) {
  json s = read_json(r.dir / "stop.json");
  edit(s);
  const fs::path p = r.dir / name;
  std::ofstream(p) << s.dump(2);
  return p;
}

TEST(CliResume, ChangedJobIsRefused) {
  const Runs r = three_runs();
  ASSERT_EQ(r.stop.rc, 0) << r.stop.err;
  const fs::path changed = r.dir / "changed.ngc";
  std::ofstream(changed) << r.gcode.text << "(one more comment)\n";
  expect_refused(resume_with(r.dir, changed, r.dir / "stop.json", "changed"),
                 {changed.string(), "the job changed since the state was written"});
}

TEST(CliResume, MalformedStateIsRefusedNamingFileAndField) {
  const Runs r = three_runs();
  ASSERT_EQ(r.stop.rc, 0) << r.stop.err;
  const fs::path wrong = edited_state(r, "wrong.json", [](json& s) { s["contours_completed"] = "two"; });
  expect_refused(resume_with(r.dir, r.job, wrong, "wrong"),
                 {wrong.string(), "contours_completed: expected a whole number"});
  const fs::path missing = edited_state(r, "missing.json", [](json& s) { s.erase("position_steps"); });
  expect_refused(resume_with(r.dir, r.job, missing, "missing"), {missing.string(), "position_steps: missing"});
  const fs::path axis = edited_state(r, "axis.json", [](json& s) { s["position_steps"]["x"] = 1.5; });
  expect_refused(resume_with(r.dir, r.job, axis, "axis"), {axis.string(), "position_steps.x: expected a whole number"});
  const fs::path text = r.dir / "text.json";
  std::ofstream(text) << "{\"version\": 1,";
  expect_refused(resume_with(r.dir, r.job, text, "text"), {text.string(), "not a JSON state file"});
  expect_refused(resume_with(r.dir, r.job, r.dir / "none.json", "none"),
                 {(r.dir / "none.json").string(), "cannot read the state file"});
}

TEST(CliResume, StateThatDoesNotFitTheJobOrTheMachineIsRefused) {
  const Runs r = three_runs();
  ASSERT_EQ(r.stop.rc, 0) << r.stop.err;
  const fs::path more = edited_state(r, "more.json", [](json& s) {
    s["contours"] = 9;
    s["contours_completed"] = 7;
  });
  expect_refused(resume_with(r.dir, r.job, more, "more"),
                 {more.string(), "contours_completed: 7, but " + r.job.string() + " has 4 contours"});
  // Recorded with 100 steps per mm on x: the position would be another place.
  const fs::path spm = edited_state(r, "spm.json", [](json& s) { s["steps_per_mm"]["x"] = 100; });
  expect_refused(resume_with(r.dir, r.job, spm, "spm"), {spm.string(), "steps_per_mm.x: 100 in the state, 80 in"});
}

TEST(CliResume, NothingToResumeExitsZeroAndRunsNothing) {
  const Runs r = three_runs();
  ASSERT_EQ(r.full.rc, 0) << r.full.err;
  // A finished run.
  const Refusal done = resume_with(r.dir, r.job, r.dir / "full.json", "done");
  EXPECT_EQ(done.o.rc, 0) << done.o.err;
  EXPECT_NE(done.o.out.find("nothing to resume"), std::string::npos) << done.o.out;
  EXPECT_FALSE(fs::exists(done.vcd));
  // A run that faulted after its last contour.
  const fs::path last = edited_state(r, "last.json", [](json& s) {
    s["contours_completed"] = 4;
    s["ended"] = "fault";
  });
  const Refusal all = resume_with(r.dir, r.job, last, "all");
  EXPECT_EQ(all.o.rc, 0) << all.o.err;
  EXPECT_NE(all.o.out.find("every contour of " + r.job.string() + " is done (4 of 4)"), std::string::npos)
      << all.o.out;
  EXPECT_FALSE(fs::exists(all.vcd));
}

TEST(CliResume, OptionsOutsideTheirTransportsAreRefused) {
  const fs::path dir = test_dir();
  const fs::path job = make_job(dir);
  const auto refused = [&](std::vector<std::string> extra, const std::string& said, const std::string& tag) {
    std::vector<std::string> args = {"run", job.string(), "--machine", kMachine, "--no-progress"};
    args.insert(args.end(), extra.begin(), extra.end());
    const Outcome o = cpstep(dir, args, tag);
    EXPECT_EQ(o.rc, 2) << tag << ": " << o.out << o.err;
    EXPECT_NE(o.err.find(said), std::string::npos) << tag << ": " << o.err;
  };
  refused({"--transport", "file", "--out", (dir / "w.bin").string(), "--state", (dir / "s.json").string()},
          "--state and --resume need a card", "file_state");
  refused({"--transport", "spidev", "--stop-after-contours", "1"}, "--stop-after-contours is for --transport sim",
          "spidev_stop");
  refused({"--stop-after-contours", "5"}, "--stop-after-contours 5: the job has 4 contours", "stop_beyond");
  refused({"--stop-after-contours", "0"}, "--stop-after-contours", "stop_zero");
  EXPECT_FALSE(fs::exists(dir / "s.json"));
}

TEST(CliResume, SpidevReadsTheStateBeforeTheDevice) {
  const Runs r = three_runs();
  ASSERT_EQ(r.stop.rc, 0) << r.stop.err;
  const auto spidev = [&](const fs::path& state, const std::string& tag) {
    return cpstep(r.dir,
                  {"run", r.job.string(), "--machine", kMachine, "--no-progress", "--transport", "spidev", "--device",
                   "/dev/null", "--resume", state.string()},
                  tag);
  };
  // A bad state: refused before the device is opened (the error names the state only).
  const Outcome bad = spidev(r.dir / "none.json", "spidev_bad");
  EXPECT_EQ(bad.rc, 2);
  EXPECT_NE(bad.err.find("none.json: cannot read the state file"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find("/dev/null"), std::string::npos) << bad.err;
  // A good one: on to the device, which is not an SPI device.
  const Outcome good = spidev(r.dir / "stop.json", "spidev_good");
  EXPECT_EQ(good.rc, 2);
  EXPECT_NE(good.err.find("/dev/null"), std::string::npos) << good.err;
}

}  // namespace
}  // namespace cpstep::tb

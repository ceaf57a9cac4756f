// SPDX-License-Identifier: MIT
// `cpstep check` on cpstep's own RTL trace: the Verilated card runs a small
// job (tb/check/data/check.ngc on check.toml) and writes its pin VCD; the
// unmodified trace must conform (no false alarm), also read through a pin map
// that renames and inverts the pins; each mutation of it, made here on the
// parsed trace, must be caught as the right finding at the right segment,
// axis and move. Expected values come from the plan (checkpoints, card
// segments), the oracle's strings and the mutation itself; move events are
// found here independently, as the distinct times of the STEP rising edges
// (the card puts every edge of a move event on one clock edge).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "check/check.h"
#include "check/pin_map.h"
#include "check/vcd.h"
#include "model/oracle.h"
#include "run/card_job.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;
using check::Finding;
using check::FindingKind;
using check::VcdChange;
using check::VcdTrace;

const fs::path kData = CPSTEP_CHECK_DATA;
const fs::path kDir = fs::path(CPSTEP_TEST_DIR) / "check_traces";
constexpr int X = 0, Y = 1;

class Check : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto prepared = run::prepare_job(kData / "check.ngc", kData / "check.toml");
    ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
    job_ = new run::CardJob(std::move(*prepared.value));
    fs::create_directories(kDir);
    // One file per test process (ctest runs the tests in parallel).
    const fs::path vcd = kDir / ("trace." + std::to_string(::getpid()) + ".vcd");
    run::SimRunOptions o;
    o.vcd = vcd.string();
    const run::CardRun r = run::run_on_sim(*job_, o);
    ASSERT_TRUE(r.ok()) << r.faults.front().message;
    text_ = new std::string(*check::read_text(vcd));
    fs::remove(vcd);
  }
  static void TearDownTestSuite() {
    delete job_;
    delete text_;
  }

  void SetUp() override {
    ASSERT_NE(job_, nullptr);
    ASSERT_NE(text_, nullptr);
    trace_ = parse(*text_);
    // The move events, found here: distinct rising-edge times of the STEP pins.
    std::set<uint64_t> times;
    for (const char* pin : {"step_x", "step_y", "step_z", "step_a"})
      for (const VcdChange& c : changes(pin))
        if (c.bits == 1 && c.time > 0) times.insert(c.time);
    events_.assign(times.begin(), times.end());
    ASSERT_EQ(events_.size(), job_->moves());
    ps_per_cycle_ = 1e12 / job_->clock_hz();
  }

  static VcdTrace parse(const std::string& text) {
    auto r = check::parse_vcd(text, "trace.vcd");
    EXPECT_TRUE(r.ok()) << plan::join(r.errors);
    return r.ok() ? *r.value : VcdTrace{};
  }

  std::vector<VcdChange>& changes(const std::string& name) { return changes_of(trace_, name); }
  static std::vector<VcdChange>& changes_of(VcdTrace& t, const std::string& name) {
    const auto found = t.find(name);
    EXPECT_EQ(found.size(), 1u) << name;
    return t.changes.at(found.at(0)->code);
  }

  check::Verdict verdict(const VcdTrace& t, const check::PinMap& map = check::default_pin_map(),
                         const check::CheckOptions& o = {}) {
    auto pins = check::read_pins(t, map, *job_);
    EXPECT_TRUE(pins.ok()) << plan::join(pins.errors);
    if (!pins.ok()) return {};
    return check::check_trace(*job_, *pins, o);
  }
  check::Verdict verdict() { return verdict(trace_); }

  // Planned card segment s (0-based): its moves are events [first(s), end(s)).
  static uint64_t first(size_t s) { return s == 0 ? 0 : job_->checkpoints[s - 1].moves; }
  static uint64_t end(size_t s) { return job_->checkpoints[s].moves; }
  static std::string string_of(size_t s, int axis) {
    const plan::CardSegment& c = job_->planned.card[s].segment;
    const int64_t d = c.delta[axis];
    return oracle::closed_form(c.moves, uint64_t(d < 0 ? -d : d));
  }
  // Index of `axis`'s rising edge at event k, or -1.
  long rise_at(const std::string& pin, uint64_t k) {
    const auto& ch = changes(pin);
    for (size_t i = 0; i < ch.size(); ++i)
      if (ch[i].time == events_[k] && ch[i].bits == 1) return long(i);
    return -1;
  }
  static void sort_by_time(std::vector<VcdChange>& ch) {
    std::stable_sort(ch.begin(), ch.end(), [](const VcdChange& a, const VcdChange& b) { return a.time < b.time; });
  }

  static std::set<std::string> kinds(const check::Verdict& v) {
    std::set<std::string> s;
    for (const Finding& f : v.findings) s.insert(check::finding_name(f.kind));
    return s;
  }
  static const Finding* find(const check::Verdict& v, FindingKind kind, size_t segment, int axis) {
    for (const Finding& f : v.findings)
      if (f.kind == kind && f.segment == segment && f.axis == axis) return &f;
    return nullptr;
  }

  // The verdict's only finding, which must be `kind` at card segment
  // `segment` (1-based), `axis` and 1-based move `move`.
  static const Finding& single(const check::Verdict& v, FindingKind kind, size_t segment, int axis, uint64_t move) {
    static const Finding none{};
    EXPECT_EQ(v.findings.size(), 1u) << check::verdict_summary(v);
    if (v.findings.size() != 1) return none;
    const Finding& f = v.findings[0];
    EXPECT_EQ(check::finding_name(f.kind), std::string(check::finding_name(kind)));
    EXPECT_EQ(f.segment, segment);
    EXPECT_EQ(f.axis, axis);
    EXPECT_EQ(f.move, move);
    return f;
  }

  static inline run::CardJob* job_ = nullptr;
  static inline std::string* text_ = nullptr;
  VcdTrace trace_;
  std::vector<uint64_t> events_;  // trace time of each move event
  double ps_per_cycle_ = 0;
};

TEST_F(Check, TheCardsOwnTraceConforms) {
  const check::Verdict v = verdict();
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  EXPECT_TRUE(v.findings.empty());
  EXPECT_EQ(v.move_events, job_->moves());
  EXPECT_EQ(v.segments, job_->checkpoints.size());
  EXPECT_EQ(v.segments_on_endpoint, v.segments);
  EXPECT_EQ(v.segments_bit_exact, v.segments);
  EXPECT_EQ(v.moves_off_time, 0u);
  // The card fires exactly at its chunk times: every move at the same offset.
  EXPECT_NEAR(v.max_early_cycles, 0, 1e-3);
  EXPECT_NEAR(v.max_late_cycles, 0, 1e-3);
  for (int a = 0; a < 3; ++a) {
    const check::AxisSummary& s = v.axes[a];
    ASSERT_TRUE(s.present);
    EXPECT_EQ(s.final_position, job_->checkpoints.back().position[a]);
    EXPECT_LE(s.max_deviation, s.deviation_limit + 1e-9);
    // Every pulse as long as the card's configured high time (cycles rounded up from ns).
    const plan::AxisConfig& ax = job_->machine.axes[a];
    EXPECT_NEAR(s.min_high_ns, ax.pulse.step_high * 1e9 / job_->clock_hz(), 1e-2);
    EXPECT_GE(s.min_low_ns, ax.pulse_ns.step_low);
    EXPECT_GE(s.min_setup_ns, ax.pulse_ns.dir_setup);
    // The card holds DIR after the trailing edge: high + hold after the leading one.
    EXPECT_GE(s.min_hold_ns + 1e-2, (ax.pulse.step_high + ax.pulse.dir_hold) * 1e9 / job_->clock_hz());
  }
  // The JSON verdict has the fields docs/VALIDATING.md lists.
  const auto j = check::verdict_json(v);
  EXPECT_EQ(j["conforms"], true);
  EXPECT_EQ(j["findings"].size(), 0u);
  EXPECT_EQ(j["planned_moves"], job_->moves());
  EXPECT_EQ(j["move_events"], job_->moves());
  uint64_t x_rises = 0;
  for (const VcdChange& c : changes("step_x")) x_rises += c.bits == 1;
  EXPECT_EQ(j["axes"]["x"]["pulses"], x_rises);
  for (const char* field : {"trace", "job", "machine", "map", "clock_hz", "trace_unit_s", "resolution_cycles",
                            "skew_window_cycles", "time_tolerance_cycles", "segments", "segments_on_endpoint",
                            "segments_bit_exact", "timing", "axes", "counts", "warnings"})
    EXPECT_TRUE(j.contains(field)) << field;
}

TEST_F(Check, AMapRenamesNestsAndInvertsThePins) {
  // Rewritten as a logic analyzer might show it: other names, two scopes, STEP
  // active low and DIR low = positive on x, y and z.
  std::istringstream in(*text_);
  std::string line, out;
  std::set<std::string> inverted;
  const std::map<std::string, std::string> names = {{"step_x", "X_STEP"}, {"dir_x", "X_DIR"}, {"step_y", "Y_STEP"},
                                                    {"dir_y", "Y_DIR"},   {"step_z", "Z_STEP"}, {"dir_z", "Z_DIR"}};
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string w0, type, width, code, name;
    words >> w0;
    if (w0 == "$var" && words >> type >> width >> code >> name && names.count(name)) {
      line = "$var " + type + " " + width + " " + code + " " + names.at(name) + " $end";
      inverted.insert(code);
    } else if (w0 == "$scope") {
      line = "$scope module top $end\n$scope module la $end";
    } else if (w0 == "$upscope") {
      line = "$upscope $end\n$upscope $end";
    } else if ((line[0] == '0' || line[0] == '1') && inverted.count(line.substr(1))) {
      line[0] = line[0] == '0' ? '1' : '0';
    }
    out += line + "\n";
  }
  ASSERT_EQ(inverted.size(), 6u);
  auto map = check::parse_pin_map(
      "[axes.x]\nstep = \"X_STEP\"\ndir = \"top.la.X_DIR\"\nstep_active_high = false\ndir_positive_high = false\n"
      "[axes.y]\nstep = \"Y_STEP\"\ndir = \"Y_DIR\"\nstep_active_high = false\ndir_positive_high = false\n"
      "[axes.z]\nstep = \"Z_STEP\"\ndir = \"Z_DIR\"\nstep_active_high = false\ndir_positive_high = false\n",
      "pins.toml");
  ASSERT_TRUE(map.ok()) << plan::join(map.errors);
  const check::Verdict v = verdict(parse(out), *map);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  EXPECT_EQ(v.move_events, job_->moves());
  EXPECT_EQ(v.axes[X].step_name, "top.la.X_STEP");
  EXPECT_FALSE(v.axes[X].step_active_high);
  EXPECT_FALSE(v.axes[Y].dir_positive_high);
  EXPECT_EQ(v.axes[X].final_position, job_->checkpoints.back().position[X]);
  // step_a / dir_a keep their default names and polarity.
  EXPECT_EQ(v.axes[3].step_name, "top.la.step_a");
  EXPECT_TRUE(v.axes[3].step_active_high);

  // Read without the map's polarity, every step of x counts the other way.
  check::PinMap names_only = *map;
  for (auto& p : names_only.axes) p.dir_positive_high.reset();
  const check::Verdict w = verdict(parse(out), names_only);
  EXPECT_FALSE(w.conforms());
  EXPECT_NE(find(w, FindingKind::direction, 1, X), nullptr);
}

TEST_F(Check, ADroppedStepIsAnEndpointAndAStringError) {
  // y's middle step of card segment 1.
  std::vector<uint64_t> ys;
  for (uint64_t k = first(0); k < end(0); ++k)
    if (rise_at("step_y", k) >= 0) ys.push_back(k);
  ASSERT_GE(ys.size(), 3u);
  const uint64_t k = ys[ys.size() / 2];
  auto& ch = changes("step_y");
  const long r = rise_at("step_y", k);
  ch.erase(ch.begin() + r, ch.begin() + r + 2);  // its rise and fall

  const check::Verdict v = verdict();
  EXPECT_FALSE(v.conforms());
  const Finding* s = find(v, FindingKind::move_string, 1, -1);
  ASSERT_NE(s, nullptr) << check::verdict_summary(v);
  EXPECT_EQ(s->move, k + 1);
  EXPECT_EQ(s->segment_move, k + 1 - first(0));
  EXPECT_EQ(s->count, 1u);
  const Finding* e = find(v, FindingKind::endpoint, 1, Y);
  ASSERT_NE(e, nullptr);
  const int64_t planned = job_->checkpoints[0].position[Y];
  const int64_t sign = job_->planned.card[0].segment.delta[Y] > 0 ? 1 : -1;
  EXPECT_EQ(e->expected, double(planned));
  EXPECT_EQ(e->actual, double(planned - sign));
  EXPECT_EQ(find(v, FindingKind::endpoint, 1, X), nullptr);
  EXPECT_EQ(v.move_events, job_->moves());  // x steps at every move of the segment
  for (const char* k2 : {"move_count", "timing", "step_high", "step_low", "dir_setup", "dir_hold", "direction"})
    EXPECT_EQ(kinds(v).count(k2), 0u) << k2;
}

TEST_F(Check, AnExtraStepIsAnEndpointAndAStringError) {
  // A y pulse added at a move event of segment 1 where y does not step (nor
  // at the events around it), as long as y's other pulses.
  uint64_t k = 0;
  for (uint64_t c = (first(0) + end(0)) / 2; c + 1 < end(0); ++c)
    if (rise_at("step_y", c - 1) < 0 && rise_at("step_y", c) < 0 && rise_at("step_y", c + 1) < 0) {
      k = c;
      break;
    }
  ASSERT_GT(k, 0u);
  auto& ch = changes("step_y");
  long r = -1;
  for (uint64_t c = first(0); c < end(0) && r < 0; ++c) r = rise_at("step_y", c);
  ASSERT_GE(r, 0);
  const uint64_t width = ch[size_t(r) + 1].time - ch[size_t(r)].time;
  ch.push_back({events_[k], 1, true});
  ch.push_back({events_[k] + width, 0, true});
  sort_by_time(ch);

  const check::Verdict v = verdict();
  const Finding* s = find(v, FindingKind::move_string, 1, -1);
  ASSERT_NE(s, nullptr) << check::verdict_summary(v);
  EXPECT_EQ(s->move, k + 1);
  EXPECT_EQ(s->count, 1u);
  EXPECT_NE(s->message.find("cpstep steps x, the trace steps x y"), std::string::npos) << s->message;
  const Finding* e = find(v, FindingKind::endpoint, 1, Y);
  ASSERT_NE(e, nullptr);
  const int64_t sign = job_->planned.card[0].segment.delta[Y] > 0 ? 1 : -1;
  EXPECT_EQ(e->actual - e->expected, double(sign));
  EXPECT_EQ(v.move_events, job_->moves());
  for (const char* k2 : {"move_count", "timing", "step_high", "step_low", "dir_setup", "dir_hold", "direction"})
    EXPECT_EQ(kinds(v).count(k2), 0u) << k2;
}

TEST_F(Check, APulseTooShortIsAStepHighViolation) {
  // x's pulse at the middle move of segment 2, cut to half its length.
  const uint64_t k = (first(1) + end(1)) / 2;
  auto& ch = changes("step_x");
  const long r = rise_at("step_x", k);
  ASSERT_GE(r, 0);
  const uint64_t half = (ch[size_t(r) + 1].time - ch[size_t(r)].time) / 2;
  ch[size_t(r) + 1].time = ch[size_t(r)].time + half;

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::step_high, 2, X, k + 1);
  EXPECT_DOUBLE_EQ(f.expected, job_->machine.axes[X].pulse_ns.step_high);
  EXPECT_NEAR(f.actual, double(half) / 1000, 1e-6);  // ps to ns
}

TEST_F(Check, ADirChangeInsideTheSetupWindow) {
  // x reverses between segments 1 and 2: move its DIR change to 500 ns
  // before segment 2's first x step (the machine asks for 1000 ns).
  ASSERT_NE(job_->planned.card[0].segment.dir_positive[X], job_->planned.card[1].segment.dir_positive[X]);
  auto& dir = changes("dir_x");
  auto it = std::find_if(dir.begin(), dir.end(), [&](const VcdChange& c) {
    return c.time > events_[end(0) - 1] && c.time < events_[first(1)];
  });
  ASSERT_NE(it, dir.end());
  ASSERT_GE(rise_at("step_x", first(1)), 0);
  it->time = events_[first(1)] - 500'000;
  sort_by_time(dir);

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::dir_setup, 2, X, first(1) + 1);
  EXPECT_EQ(f.segment_move, 1u);
  EXPECT_NEAR(f.actual, 500, 1e-6);
  EXPECT_DOUBLE_EQ(f.expected, job_->machine.axes[X].pulse_ns.dir_setup);
}

TEST_F(Check, ADirChangeInsideTheHoldWindow) {
  // The same DIR change moved to 500 ns after segment 1's last x leading edge
  // (the machine asks for 1000 ns of hold).
  auto& dir = changes("dir_x");
  auto it = std::find_if(dir.begin(), dir.end(), [&](const VcdChange& c) {
    return c.time > events_[end(0) - 1] && c.time < events_[first(1)];
  });
  ASSERT_NE(it, dir.end());
  ASSERT_GE(rise_at("step_x", end(0) - 1), 0);
  it->time = events_[end(0) - 1] + 500'000;
  sort_by_time(dir);

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::dir_hold, 1, X, end(0));
  EXPECT_NEAR(f.actual, 500, 1e-6);
  EXPECT_DOUBLE_EQ(f.expected, job_->machine.axes[X].pulse_ns.dir_hold);
}

TEST_F(Check, SetupAndHoldEachAgainstItsOwnMinimum) {
  // check.toml gives x the same setup and hold (1000 ns); here they differ, so a
  // check that took one for the other is caught (scripts/mutants.toml
  // check-setup-field). DIR 500 ns before segment 2's first x step: a setup finding
  // against 1000 ns of setup; with the hold at 1000 and the setup at 100, none.
  struct Restore {
    plan::AxisConfig& ax;
    const plan::PulseTimingNs saved = ax.pulse_ns;
    ~Restore() { ax.pulse_ns = saved; }
  } restore{job_->machine.axes[X]};
  auto& dir = changes("dir_x");
  auto it = std::find_if(dir.begin(), dir.end(), [&](const VcdChange& c) {
    return c.time > events_[end(0) - 1] && c.time < events_[first(1)];
  });
  ASSERT_NE(it, dir.end());
  it->time = events_[first(1)] - 500'000;
  sort_by_time(dir);

  restore.ax.pulse_ns.dir_setup = 1000;
  restore.ax.pulse_ns.dir_hold = 100;
  const Finding& f = single(verdict(), FindingKind::dir_setup, 2, X, first(1) + 1);
  EXPECT_NEAR(f.actual, 500, 1e-6);
  EXPECT_DOUBLE_EQ(f.expected, 1000);

  restore.ax.pulse_ns.dir_setup = 100;
  restore.ax.pulse_ns.dir_hold = 1000;
  const check::Verdict v = verdict();
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
}

TEST_F(Check, ADirChangeOnAStepEdgeIsASetupFindingNotAHoldOne) {
  // DIR moved onto segment 2's first x leading edge: that edge had no setup (0 ns);
  // the hold is measured from the leading edge before it (segment 1's last), long
  // ago, not from the edge at the same instant (scripts/mutants.toml check-hold-bound).
  auto& dir = changes("dir_x");
  auto it = std::find_if(dir.begin(), dir.end(), [&](const VcdChange& c) {
    return c.time > events_[end(0) - 1] && c.time < events_[first(1)];
  });
  ASSERT_NE(it, dir.end());
  ASSERT_GE(rise_at("step_x", first(1)), 0);
  it->time = events_[first(1)];
  sort_by_time(dir);

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::dir_setup, 2, X, first(1) + 1);
  EXPECT_NEAR(f.actual, 0, 1e-6);
  EXPECT_EQ(find(v, FindingKind::dir_hold, 2, X), nullptr);
  EXPECT_EQ(find(v, FindingKind::direction, 2, X), nullptr);  // the edge sees the new DIR
}

TEST_F(Check, TwoAxesSwapped) {
  for (check::VcdVar& var : trace_.vars) {
    for (auto [a, b] : {std::pair{"step_x", "step_y"}, std::pair{"dir_x", "dir_y"}}) {
      if (var.name == a || var.name == b) {
        const std::string other = var.name == a ? b : a;
        var.path = var.path.substr(0, var.path.size() - var.name.size()) + other;
        var.name = other;
        break;
      }
    }
  }
  // The first move where the plan's x and y strings differ.
  size_t s = 0, i = 0;
  for (; s < job_->planned.card.size(); ++s) {
    const std::string xs = string_of(s, X), ys = string_of(s, Y);
    i = 0;
    while (i < xs.size() && xs[i] == ys[i]) ++i;
    if (i < xs.size()) break;
  }
  ASSERT_LT(s, job_->planned.card.size());

  const check::Verdict v = verdict();
  ASSERT_FALSE(v.findings.empty());
  const Finding* f = find(v, FindingKind::move_string, s + 1, -1);
  ASSERT_NE(f, nullptr) << check::verdict_summary(v);
  EXPECT_EQ(f->segment_move, i + 1);
  EXPECT_EQ(f->move, first(s) + i + 1);
  // No move_string finding in an earlier segment, and both axes miss the end.
  for (const Finding& g : v.findings) {
    if (g.kind == FindingKind::move_string) {
      EXPECT_GE(g.segment, s + 1);
    }
  }
  EXPECT_NE(find(v, FindingKind::endpoint, s + 1, X), nullptr);
  EXPECT_NE(find(v, FindingKind::endpoint, s + 1, Y), nullptr);
}

TEST_F(Check, ALateMoveBeyondTheTolerance) {
  // Every edge of the middle move event of segment 2, 10 cycles late.
  const uint64_t k = (first(1) + end(1)) / 2;
  const uint64_t late = uint64_t(std::llround(10 * ps_per_cycle_));
  const uint64_t t = events_[k];
  int moved = 0;
  for (const char* pin : {"step_x", "step_y", "step_z", "step_a"}) {
    auto& ch = changes(pin);
    const long r = rise_at(pin, k);
    if (r < 0) continue;
    ch[size_t(r)].time += late;
    ch[size_t(r) + 1].time += late;
    ++moved;
    ASSERT_EQ(ch[size_t(r)].time, t + late);
  }
  ASSERT_GE(moved, 1);

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::timing, 2, -1, k + 1);
  EXPECT_EQ(f.count, 1u);
  EXPECT_NEAR(f.actual, double(late) / ps_per_cycle_, 1e-3);
  EXPECT_NEAR(v.max_late_cycles, 10, 1e-3);
  EXPECT_EQ(v.max_late_move, k + 1);
  // Within a wider tolerance it conforms.
  EXPECT_TRUE(verdict(trace_, check::default_pin_map(), {11.0, std::nullopt}).conforms());
}

// The string of (T, d) with the tie at move `tie` rounded down, the others up:
// the minor position after move i is floor((2 d i + T) / (2 T)), and at the
// tie floor((2 d i + T - 1) / (2 T)).
std::string tie_rounded_down(uint64_t T, uint64_t d, uint64_t tie) {
  std::string s;
  uint64_t prev = 0;
  for (uint64_t i = 1; i <= T; ++i) {
    const uint64_t pos = (2 * d * i + T - (i == tie ? 1 : 0)) / (2 * T);
    s += pos != prev ? '1' : '0';
    prev = pos;
  }
  return s;
}

TEST_F(Check, ATieRoundedDownIsAStringError) {
  // The first card segment with a tie on x or y: move i (1-based) where the
  // ideal minor position 2·d·i / (2T) is exactly a half.
  size_t s = 0;
  int axis = -1;
  std::vector<uint64_t> ties;
  for (; s < job_->planned.card.size() && ties.empty(); ++s) {
    const plan::CardSegment& c = job_->planned.card[s].segment;
    for (int a : {X, Y}) {
      const uint64_t d = uint64_t(std::llabs(c.delta[a])), T = c.moves;
      if (d == 0 || d == T) continue;
      for (uint64_t i = 1; i < T; ++i)
        if (2 * d * i % (2 * T) == T) ties.push_back(i);
      if (!ties.empty()) {
        axis = a;
        break;
      }
    }
  }
  ASSERT_FALSE(ties.empty());
  --s;
  const uint64_t i = ties[ties.size() / 2];
  const plan::CardSegment& c = job_->planned.card[s].segment;
  // The mutation below gives exactly that string with tie i rounded down: one
  // step moved by one move event.
  const std::string up = string_of(s, axis), down = tie_rounded_down(c.moves, uint64_t(std::llabs(c.delta[axis])), i);
  ASSERT_EQ(up[i - 1], '1');
  ASSERT_EQ(up[i], '0');
  std::string moved = up;
  std::swap(moved[i - 1], moved[i]);
  ASSERT_EQ(moved, down);

  const std::string pin = axis == X ? "step_x" : "step_y";
  const uint64_t k = first(s) + i - 1;
  const long r = rise_at(pin, k);
  ASSERT_GE(r, 0);
  ASSERT_LT(rise_at(pin, k + 1), 0);
  auto& ch = changes(pin);
  const uint64_t shift = events_[k + 1] - events_[k];
  ch[size_t(r)].time += shift;
  ch[size_t(r) + 1].time += shift;

  const check::Verdict v = verdict();
  const Finding& f = single(v, FindingKind::move_string, s + 1, -1, k + 1);
  EXPECT_EQ(f.segment_move, i);
  EXPECT_EQ(f.count, 2u);  // moves i and i + 1
}

TEST_F(Check, AxisSkewWithinTheWindowIsOneMoveEvent) {
  // Every y pulse 20 cycles after its move event's other edges.
  const uint64_t skew = uint64_t(std::llround(20 * ps_per_cycle_));
  for (VcdChange& c : changes("step_y"))
    if (c.time > 0) c.time += skew;
  const check::Verdict v = verdict();
  EXPECT_GT(v.skew_cycles, 20);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  // With a window narrower than the skew, y's edges become move events of their own.
  const check::Verdict w = verdict(trace_, check::default_pin_map(), {std::nullopt, 10.0});
  EXPECT_FALSE(w.conforms());
  uint64_t y_steps = 0;
  for (const VcdChange& c : changes("step_y")) y_steps += c.bits == 1;
  EXPECT_EQ(w.move_events, job_->moves() + y_steps);
  EXPECT_EQ(w.findings.front().kind, FindingKind::move_count);
}

// A VCD in sigrok-cli's dialect (one scope "libsigrok", channels D0.., the
// time and every change of a sample on one line) from pins given as changes
// at card cycles; `time_of(cycle)` writes a cycle in the trace's time unit.
struct Pin {
  std::string name;
  std::vector<std::pair<uint64_t, uint64_t>> changes;  // (cycle, level)
};
std::string sigrok_vcd(const std::vector<Pin>& pins, const std::string& timescale,
                       const std::function<uint64_t(uint64_t)>& time_of) {
  // Built by append: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string.
  std::string out = "$date today $end\n$version libsigrok 0.5.2 $end\n$comment\n  Acquisition\n$end\n";
  out.append("$timescale ").append(timescale).append(" $end\n$scope module libsigrok $end\n");
  std::map<uint64_t, std::string> lines;  // time -> changes
  for (size_t i = 0; i < pins.size(); ++i) {
    const char code = char('!' + i);
    out.append("$var wire 1 ").append(1, code).append(" ").append(pins[i].name).append(" $end\n");
    for (const auto& [cycle, level] : pins[i].changes)
      lines[time_of(cycle)].append(" ").append(1, char('0' + level)).append(1, code);
  }
  out.append("$upscope $end\n$enddefinitions $end\n");
  for (const auto& [t, changes] : lines) out.append("#").append(std::to_string(t)).append(changes).append("\n");
  return out;
}

TEST_F(Check, ACaptureInCyclesWithTheClockInTheMap) {
  // A trace whose time unit is one card cycle (as a simulator counting clocks
  // writes it) under a $timescale that says otherwise.
  std::vector<Pin> pins;
  for (const char* name : {"step_x", "dir_x", "step_y", "dir_y", "step_z", "dir_z"}) {
    Pin p{name, {}};
    for (const VcdChange& c : changes(name)) p.changes.emplace_back(std::llround(double(c.time) / ps_per_cycle_), c.bits);
    pins.push_back(std::move(p));
  }
  const VcdTrace cycles = parse(sigrok_vcd(pins, "1 ns", [](uint64_t c) { return c; }));
  auto map = check::parse_pin_map("clock_hz = 16_500_000\n", "pins.toml");
  ASSERT_TRUE(map.ok()) << plan::join(map.errors);
  ASSERT_EQ(job_->clock_hz(), 16.5e6);  // the default board's card
  const check::Verdict v = verdict(cycles, *map);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  // Read as nanoseconds, every pulse is 16.5 MHz / 1 GHz as long: far too short.
  const check::Verdict w = verdict(cycles);
  EXPECT_EQ(kinds(w).count("step_high"), 1u);
}

TEST_F(Check, ALogicAnalyzerAtACoarseSampleRate) {
  // Sampled every 7 card cycles (16.5 MHz / 7), as sigrok-cli exports it: an edge
  // shows at the first sample at or after it; the time unit is 1 ns.
  const uint64_t every = 7;
  const double sample_ns = every * 1e9 / job_->clock_hz();  // 388.9 ns
  std::vector<Pin> pins;
  const char* names[] = {"step_x", "dir_x", "step_y", "dir_y", "step_z", "dir_z"};
  for (int i = 0; i < 6; ++i) {
    Pin p{"D" + std::to_string(i), {}};
    for (const VcdChange& c : changes(names[i])) {
      const uint64_t cycle = uint64_t(std::llround(double(c.time) / ps_per_cycle_));
      p.changes.emplace_back((cycle + every - 1) / every, c.bits);
    }
    pins.push_back(std::move(p));
  }
  const VcdTrace capture = parse(sigrok_vcd(pins, "1 ns", [&](uint64_t n) { return uint64_t(std::llround(n * sample_ns)); }));
  const std::string axes =
      "[axes.x]\nstep = \"D0\"\ndir = \"D1\"\n[axes.y]\nstep = \"D2\"\ndir = \"D3\"\n"
      "[axes.z]\nstep = \"D4\"\ndir = \"D5\"\n";
  auto map = check::parse_pin_map(fmt::format("sample_hz = {:.10f}\n", job_->clock_hz() / double(every)) + axes,
                                  "pins.toml");
  ASSERT_TRUE(map.ok()) << plan::join(map.errors);
  const check::Verdict v = verdict(capture, *map);
  EXPECT_TRUE(v.conforms()) << check::verdict_summary(v);
  EXPECT_NEAR(v.resolution_cycles, double(every), 1e-6);
  EXPECT_LE(v.max_late_cycles + v.max_early_cycles, double(every));
  // Without the sample rate the reader cannot know what a sample hides: x's
  // 2000 ns pulses read as a whole number of samples shorter than 2000 ns, where the
  // rise is just after a sample and the fall on one.
  auto names_only = check::parse_pin_map(axes, "pins.toml");
  ASSERT_TRUE(names_only.ok());
  const check::Verdict w = verdict(capture, *names_only);
  const Finding* f = find(w, FindingKind::step_high, 1, X);
  ASSERT_NE(f, nullptr) << check::verdict_summary(w);
  EXPECT_NEAR(f->actual, std::round(f->actual / sample_ns) * sample_ns, 1.0);  // whole-ns stamps
  EXPECT_LT(f->actual, 2000.0);
}

TEST_F(Check, MissingPinsAreBadInput) {
  auto map = check::parse_pin_map("[axes.y]\nstep = \"Y_STEP\"\n", "pins.toml");
  ASSERT_TRUE(map.ok());
  auto pins = check::read_pins(trace_, *map, *job_);
  ASSERT_FALSE(pins.ok());
  EXPECT_EQ(plan::join(pins.errors),
            "pins.toml:2:8: axes.y.step: no signal named 'Y_STEP' in trace.vcd (axis y's STEP pin)");
}

}  // namespace
}  // namespace cpstep::tb

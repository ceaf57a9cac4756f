// SPDX-License-Identifier: MIT
#include "check/check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <tuple>

#include "model/oracle.h"
#include "plan/reduce.h"
#include "run/torch.h"

namespace cpstep::check {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEps = 1e-9;

char letter(int axis) { return plan::kAxisLetters[size_t(axis)]; }

std::string axes_text(uint32_t mask) {
  std::string s;
  for (int a = 0; a < plan::kAxes; ++a)
    if (mask >> a & 1) s += fmt::format("{}{}", s.empty() ? "" : " ", letter(a));
  return s.empty() ? "none" : s;
}

// The signal a map entry names, or an error naming where the name came from.
struct Lookup {
  const VcdVar* var = nullptr;
  std::optional<plan::Diagnostic> error;
};
Lookup find_pin(const VcdTrace& vcd, const PinMap& map, int axis, bool step, bool required) {
  const AxisPins& p = map.axes[size_t(axis)];
  const std::string& name = step ? p.step : p.dir;
  const plan::SourceLoc loc = step ? p.step_loc : p.dir_loc;
  const std::string field = fmt::format("axes.{}.{}", letter(axis), step ? "step" : "dir");
  auto error = [&](std::string message) {
    Lookup l;
    if (loc.line > 0)
      l.error = plan::Diagnostic{map.file, loc, fmt::format("{}: {}", field, message)};
    else
      l.error = plan::Diagnostic{vcd.file, {}, message + fmt::format(" (name it with {} in a --map file)", field)};
    return l;
  };
  const auto found = vcd.find(name);
  if (found.empty()) {
    if (!required) return {};
    return error(fmt::format("no signal named '{}' in {} (axis {}'s {} pin)", name, vcd.file, letter(axis),
                             step ? "STEP" : "DIR"));
  }
  if (found.size() > 1) {
    std::string paths;
    for (const VcdVar* v : found) paths += fmt::format("{}{}", paths.empty() ? "" : ", ", v->path);
    return error(fmt::format("'{}' matches {} signals in {} ({}); give the full path", name, found.size(), vcd.file,
                             paths));
  }
  if (found[0]->width != 1)
    return error(fmt::format("signal '{}' ({}:{}) is {} bits wide; a pin is 1 bit", found[0]->path, vcd.file,
                             found[0]->loc.line, found[0]->width));
  return {found[0], std::nullopt};
}

// Edges of one axis's pins, in cycles.
void extract(const VcdTrace& vcd, const VcdVar& step, const VcdVar& dir, double cycles_per_unit,
             AxisPinTrace& out) {
  const auto& dir_changes = vcd.changes[dir.code];
  size_t d = 0;
  int dir_level = -1;  // -1 unknown
  auto advance_dir = [&](uint64_t until) {
    for (; d < dir_changes.size() && dir_changes[d].time <= until; ++d) {
      const VcdChange& c = dir_changes[d];
      const int level = c.known ? int(c.bits & 1) : -1;
      if (level >= 0 && dir_level >= 0 && level != dir_level) out.dir_changes.push_back(double(c.time) * cycles_per_unit);
      dir_level = level;
    }
  };
  int active = -1;  // -1 unknown, else whether STEP is at its active level
  for (const VcdChange& c : vcd.changes[step.code]) {
    const int now = c.known ? int(bool(c.bits & 1) == out.step_active_high) : -1;
    const double t = double(c.time) * cycles_per_unit;
    if (active == 0 && now == 1) {
      advance_dir(c.time);
      out.leading.push_back(t);
      out.trailing.push_back(kNaN);
      out.dir.push_back(dir_level < 0 ? 0 : (bool(dir_level) == out.dir_positive_high ? 1 : -1));
    } else if (active == 1 && now == 0 && !out.trailing.empty() && std::isnan(out.trailing.back())) {
      out.trailing.back() = t;
    }
    active = now;
  }
  advance_dir(std::numeric_limits<uint64_t>::max());
}

// What the plan says about one card segment.
struct SegmentPlan {
  uint64_t first = 0;                    // its first move, 0-based over the job
  uint32_t moves = 0;
  plan::PerAxis<std::string> string;     // per axis: '1' where it steps ("" for no step)
  plan::PerAxis<int> sign{};             // planned direction: +1, -1, 0 (still)
  size_t parent = 0;                     // its step segment
  uint64_t parent_move = 0;              // moves of the step segment before it
  int line = 0;
  // A CONIC segment: the plane's walk (each move's direction), where the segment
  // starts, its circle in steps and how far cpstep's own walk strays from it.
  std::shared_ptr<const plan::ConicWalk> conic;
  plan::PerAxis<int64_t> start{};
  double limit = 0.5;
};

// A step segment: the straight line its parts follow and how close cpstep's
// own strings stay to it.
struct LinePlan {
  plan::PerAxis<int64_t> start{}, delta{};
  int64_t moves = 0;
  double limit = 0.5;
};

struct Event {
  double t = 0;
  uint32_t mask = 0;
  plan::PerAxis<int8_t> dir{};
};

class Checker {
 public:
  Checker(const run::CardJob& job, const PinTrace& trace, const CheckOptions& o)
      : job_(job), trace_(trace), chunk_cycles_(run::chunk_cycles(job)) {
    plan_segments();
    v_.trace = trace.file;
    v_.job = job.job_file;
    v_.machine = job.machine.file;
    v_.clock_hz = job.clock_hz();
    v_.unit_s = trace.unit_s;
    v_.resolution_cycles = trace.resolution_cycles;
    v_.segments = segs_.size();
    v_.planned_moves = job.moves();
    v_.time_tol_cycles = o.time_tol_cycles.value_or(kDefaultTimeTolCycles);
    v_.skew_cycles = o.skew_cycles.value_or(default_skew());
    for (const plan::Diagnostic& w : job.warnings) v_.warnings.push_back(w.str());
  }

  Verdict run() {
    group();
    v_.move_events = events_.size();
    if (events_.size() != job_.moves())
      add(FindingKind::move_count, 0, -1, std::nullopt, -1, double(job_.moves()), double(events_.size()),
          fmt::format("{} move events in the trace, {} planned", events_.size(), job_.moves()));
    path();
    timing();
    torch();
    for (int a = 0; a < plan::kAxes; ++a) pulses(a);
    summarize();
    return std::move(v_);
  }

 private:
  void plan_segments() {
    const plan::PlannedJob& pj = job_.planned;
    uint64_t first = 0;
    std::map<size_t, std::vector<plan::CardSegment>> parts;
    // Pause segments (a long dwell's moves that step no axis) never show at the pins.
    for (const plan::PlannedCardSegment& c : pj.card)
      if (!c.segment.pause && !c.conic) parts[c.segment.step_segment].push_back(c.segment);
    for (const auto& [p, list] : parts) {
      LinePlan& l = lines_[p];
      l.start = pj.step_segments[p].start;
      l.delta = pj.step_segments[p].delta();
      for (const plan::CardSegment& s : list) l.moves += s.moves;
      l.limit = std::max(0.5, plan::max_deviation(l.delta, list));
    }
    plan::PerAxis<int64_t> at = pj.step_segments.empty() ? plan::PerAxis<int64_t>{} : pj.step_segments.front().start;
    for (const plan::PlannedCardSegment& c : pj.card) {
      if (c.segment.pause) continue;
      SegmentPlan s;
      s.first = first;
      s.moves = c.segment.moves;
      s.parent = c.segment.step_segment;
      s.parent_move = c.segment.first_move;
      s.line = c.segment.loc.line;
      s.start = at;
      for (int a = 0; a < plan::kAxes; ++a) {
        const int64_t d = c.segment.delta[a];
        s.sign[a] = d > 0 ? 1 : d < 0 ? -1 : 0;
        if (d != 0) s.string[a] = oracle::closed_form(s.moves, uint64_t(d < 0 ? -d : d));
        at[a] += d;
      }
      if (c.conic) conic_plan(s, c.conic);
      first += s.moves;
      segs_.push_back(std::move(s));
      seg_of_move_.resize(first, segs_.size() - 1);
    }
    if (!pj.step_segments.empty()) start_ = pj.step_segments.front().start;
  }

  // A CONIC segment's plane: each move's steps and directions from the walk, the
  // G-code's circle the walk stands for, and the farthest cpstep's own nodes lie from
  // it (half a step, or more where the walker's circle had to go through a start node
  // the rounding put off the G-code's).
  static void conic_plan(SegmentPlan& s, std::shared_ptr<const plan::ConicWalk> w) {
    const int u = w->axis_u, v = w->axis_v;
    s.string[u].assign(s.moves, '0');
    s.string[v].assign(s.moves, '0');
    s.sign[u] = s.sign[v] = 0;  // per move: the walk's
    int64_t x = w->u0, y = w->v0;
    double worst = w->off_curve(double(x), double(y));
    for (uint32_t j = 0; j < s.moves && j < w->moves.size(); ++j) {
      const int dx = plan::ConicWalk::dx_of(w->moves[j]), dy = plan::ConicWalk::dy_of(w->moves[j]);
      if (dx) s.string[u][j] = '1';
      if (dy) s.string[v][j] = '1';
      x += dx;
      y += dy;
      worst = std::max(worst, w->off_curve(double(x), double(y)));
    }
    s.limit = std::max(0.5, worst);
    s.conic = std::move(w);
  }

  double default_skew() const {
    const std::vector<int64_t>& t = chunk_cycles_;
    double shortest = t.empty() ? 0 : double(t.front());
    for (size_t k = 1; k < t.size(); ++k) shortest = std::min(shortest, double(t[k] - t[k - 1]));
    return shortest / 4;
  }

  // Leading edges of every axis into move events; per axis, the event of each edge.
  void group() {
    struct Edge {
      double t;
      int axis;
      size_t index;
    };
    std::vector<Edge> edges;
    for (int a = 0; a < plan::kAxes; ++a)
      for (size_t i = 0; i < trace_.axes[a].leading.size(); ++i) edges.push_back({trace_.axes[a].leading[i], a, i});
    std::sort(edges.begin(), edges.end(),
              [](const Edge& x, const Edge& y) { return std::tie(x.t, x.axis) < std::tie(y.t, y.axis); });
    for (int a = 0; a < plan::kAxes; ++a) event_of_[a].resize(trace_.axes[a].leading.size());
    for (const Edge& e : edges) {
      if (events_.empty() || e.t - events_.back().t > v_.skew_cycles + kEps || (events_.back().mask >> e.axis & 1))
        events_.push_back({e.t, 0, {}});
      Event& ev = events_.back();
      ev.mask |= 1u << e.axis;
      ev.dir[e.axis] = trace_.axes[e.axis].dir[e.index];
      event_of_[e.axis][e.index] = events_.size() - 1;
    }
  }

  size_t segment_of(uint64_t move) const { return move < seg_of_move_.size() ? seg_of_move_[move] + 1 : 0; }
  int line_of(size_t segment) const { return segment ? segs_[segment - 1].line : 0; }

  // Records one occurrence. Findings are one per (kind, segment, axis): the
  // first occurrence names the move, time and message; `actual` keeps the
  // worst (by `worse`).
  void add(FindingKind kind, size_t segment, int axis, std::optional<uint64_t> move, double cycle, double expected,
           double actual,
           std::string message, bool (*worse)(double, double) = nullptr) {
    const auto key = std::make_tuple(int(kind), segment, axis);
    const auto it = index_.find(key);
    if (it != index_.end()) {
      Finding& f = v_.findings[it->second];
      ++f.count;
      if (worse && worse(actual, f.actual)) f.actual = actual;
      return;
    }
    index_.emplace(key, v_.findings.size());
    Finding f;
    f.kind = kind;
    f.segment = segment;
    f.line = line_of(segment);
    f.axis = axis;
    f.move = move ? *move + 1 : 0;
    if (move && segment && *move >= segs_[segment - 1].first && *move < segs_[segment - 1].first + segs_[segment - 1].moves)
      f.segment_move = *move + 1 - segs_[segment - 1].first;
    f.cycle = cycle;
    f.expected = expected;
    f.actual = actual;
    f.message = std::move(message);
    v_.findings.push_back(std::move(f));
  }

  std::string where(uint64_t move) const {
    const size_t s = segment_of(move);
    if (!s) return fmt::format("move {} (after the plan)", move + 1);
    return fmt::format("move {} (segment {} move {}, {}:{})", move + 1, s, move + 1 - segs_[s - 1].first, job_.job_file,
                       segs_[s - 1].line);
  }

  // Positions, endpoints, deviation from the lines, strings and directions.
  void path() {
    plan::PerAxis<int64_t> pos = start_;
    const uint64_t n = job_.moves();
    size_t next_end = 0;  // the next segment whose end is checked
    auto check_end = [&](size_t s, bool reached) {
      const SegmentPlan& sp = segs_[s];
      const run::Checkpoint& cp = job_.checkpoints[s];
      const uint64_t last = std::min<uint64_t>(cp.moves, events_.size());
      for (int a = 0; a < plan::kAxes; ++a) {
        if (pos[a] == cp.position[a]) continue;
        std::string msg = fmt::format("segment {} ({}:{}): {} at {} steps after move {}, the plan ends it at {} ({:+})",
                                      s + 1, job_.job_file, sp.line, letter(a), pos[a], cp.moves, cp.position[a],
                                      pos[a] - cp.position[a]);
        if (!reached) msg += fmt::format("; the trace ends after {} move events", events_.size());
        add(FindingKind::endpoint, s + 1, a, last ? std::optional<uint64_t>(last - 1) : std::nullopt,
            last ? events_[last - 1].t : -1,
            double(cp.position[a]), double(pos[a]), std::move(msg));
      }
    };
    for (uint64_t k = 0; k < events_.size(); ++k) {
      const Event& e = events_[k];
      for (int a = 0; a < plan::kAxes; ++a)
        if (e.mask >> a & 1) pos[a] += e.dir[a];
      if (k >= n) continue;
      const size_t s = seg_of_move_[k];
      const SegmentPlan& sp = segs_[s];
      const uint64_t i = k - sp.first;  // 0-based within the segment
      uint32_t expected = 0;
      for (int a = 0; a < plan::kAxes; ++a)
        if (!sp.string[a].empty() && sp.string[a][i] == '1') expected |= 1u << a;
      if (expected != e.mask)
        add(FindingKind::move_string, s + 1, -1, k, e.t, 0, 0,
            fmt::format("{}: cpstep steps {}, the trace steps {}", where(k), axes_text(expected), axes_text(e.mask)));
      for (int a = 0; a < plan::kAxes; ++a) {
        int want = sp.sign[a];
        if (sp.conic && (a == sp.conic->axis_u || a == sp.conic->axis_v) && i < sp.conic->moves.size())
          want = a == sp.conic->axis_u ? plan::ConicWalk::dx_of(sp.conic->moves[i])
                                       : plan::ConicWalk::dy_of(sp.conic->moves[i]);
        if (!(e.mask >> a & 1) || want == 0 || e.dir[a] == want) continue;
        add(FindingKind::direction, s + 1, a, k, e.t, want, e.dir[a],
            fmt::format("{}: {} steps {} but the {} moves it {}", where(k), letter(a),
                        e.dir[a] > 0 ? "+" : e.dir[a] < 0 ? "-" : "with DIR unknown (x/z)",
                        sp.conic ? "conic's walk" : "segment", want > 0 ? "+" : "-"));
      }
      deviation(k, s, pos, e.t);
      if (k + 1 == job_.checkpoints[s].moves) check_end(next_end++, true);
    }
    for (uint64_t k = events_.size(); k < n; ++k)
      add(FindingKind::move_string, seg_of_move_[k] + 1, -1, k, -1, 0, 0,
          fmt::format("{}: the trace has no move event here (cpstep steps {})", where(k), axes_text(expected_mask(k))));
    for (; next_end < segs_.size(); ++next_end) check_end(next_end, false);
    final_ = pos;
  }

  uint32_t expected_mask(uint64_t k) const {
    const SegmentPlan& sp = segs_[seg_of_move_[k]];
    uint32_t m = 0;
    for (int a = 0; a < plan::kAxes; ++a)
      if (!sp.string[a].empty() && sp.string[a][k - sp.first] == '1') m |= 1u << a;
    return m;
  }

  // |position - the step segment's line| at its move m, exactly over its moves.
  void deviation(uint64_t k, size_t s, const plan::PerAxis<int64_t>& pos, double t) {
    const SegmentPlan& sp = segs_[s];
    if (sp.conic) return conic_deviation(k, s, pos, t);
    const LinePlan& l = lines_.at(sp.parent);
    const int64_t m = int64_t(sp.parent_move + (k - sp.first) + 1);
    __extension__ using i128 = __int128;
    for (int a = 0; a < plan::kAxes; ++a) {
      const i128 off = i128(pos[a] - l.start[a]) * l.moves - i128(l.delta[a]) * m;
      const double dev = double(off < 0 ? -off : off) / double(l.moves);
      AxisSummary& ax = v_.axes[a];
      ax.max_deviation = std::max(ax.max_deviation, dev);
      ax.deviation_limit = std::max(ax.deviation_limit, l.limit);
      if (dev > l.limit + kEps)
        add(FindingKind::deviation, s + 1, a, k, t, l.limit, dev,
            fmt::format("{}: {} is {:.3f} steps from the planned line; cpstep's string stays within {:.3f}", where(k),
                        letter(a), dev, l.limit),
            [](double x, double y) { return x > y; });
    }
  }

  // A CONIC segment's move: the plane's node against the walk's circle (radially),
  // every other axis against the segment's own line over its moves.
  void conic_deviation(uint64_t k, size_t s, const plan::PerAxis<int64_t>& pos, double t) {
    const SegmentPlan& sp = segs_[s];
    const int u = sp.conic->axis_u, v = sp.conic->axis_v;
    const double radial = sp.conic->off_curve(double(pos[u]), double(pos[v]));
    const int64_t m = int64_t(k - sp.first) + 1;
    for (int a = 0; a < plan::kAxes; ++a) {
      double dev = radial, limit = sp.limit;
      const char* from = "the arc";
      if (a != u && a != v) {
        const int64_t d = segment_delta(sp, a);
        dev = std::abs(double(pos[a] - sp.start[a]) * double(sp.moves) - double(d) * double(m)) / double(sp.moves);
        limit = 0.5;
        from = "the planned line";
      }
      AxisSummary& ax = v_.axes[a];
      ax.max_deviation = std::max(ax.max_deviation, dev);
      ax.deviation_limit = std::max(ax.deviation_limit, limit);
      if (dev > limit + kEps)
        add(FindingKind::deviation, s + 1, a, k, t, limit, dev,
            fmt::format("{}: {} is {:.3f} steps from {}; cpstep's stays within {:.3f}", where(k), letter(a), dev,
                        from, limit),
            [](double x, double y) { return x > y; });
    }
  }
  static int64_t segment_delta(const SegmentPlan& sp, int a) {
    const std::string& str = sp.string[a];
    return sp.sign[a] * int64_t(std::count(str.begin(), str.end(), '1'));
  }

  // Each move event against its planned time, START placed at the median offset.
  void timing() {
    const uint64_t n = std::min<uint64_t>(events_.size(), job_.moves());
    if (n == 0) return;
    std::vector<double> offsets(n);
    for (uint64_t k = 0; k < n; ++k) offsets[k] = events_[k].t - double(chunk_cycles_[k]);
    std::nth_element(offsets.begin(), offsets.begin() + long(n / 2), offsets.end());
    const double offset = offsets[n / 2];
    v_.time_offset_cycles = offset;
    const double tol = v_.time_tol_cycles + v_.resolution_cycles;
    for (uint64_t k = 0; k < n; ++k) {
      const double dev = events_[k].t - offset - double(chunk_cycles_[k]);
      if (-dev > v_.max_early_cycles) v_.max_early_cycles = -dev, v_.max_early_move = k + 1;
      if (dev > v_.max_late_cycles) v_.max_late_cycles = dev, v_.max_late_move = k + 1;
      if (std::abs(dev) <= tol + kEps) continue;
      ++v_.moves_off_time;
      add(FindingKind::timing, segment_of(k), -1, k, events_[k].t, tol, dev,
          fmt::format("{}: {:.1f} cycles {} (tolerance {:.1f})", where(k), std::abs(dev), dev > 0 ? "late" : "early",
                      tol),
          [](double x, double y) { return std::abs(x) > std::abs(y); });
    }
  }

  // The torch pin's changes against the plan's switches, START placed as timing() did
  // (a move's STEP edge is its chunk time + 1 from START, as the card shows it).
  void torch() {
    const size_t planned = run::torch_switches(job_).size();
    if (!trace_.torch_present) {
      if (planned)
        v_.warnings.push_back(fmt::format("no signal named 'torch' in {}: the plan's {} torch switches are not checked",
                                          trace_.file, planned));
      return;
    }
    const double from_start = 1 - v_.time_offset_cycles;
    std::vector<run::TorchEdge> edges;
    for (size_t k = 0; k < trace_.torch_changes.size(); ++k)
      edges.push_back({trace_.torch_changes[k] + from_start, k % 2 == 0});
    std::vector<double> moves;
    for (const Event& e : events_) moves.push_back(e.t + from_start);
    const run::TorchVerdict t =
        run::check_torch(job_, edges, moves, v_.time_tol_cycles + trace_.resolution_cycles + kEps);
    v_.torch_checked = true;
    v_.torch_planned = t.planned;
    v_.torch_edges = t.edges;
    v_.torch_max_delay_cycles = t.max_delay_cycles;
    for (const std::string& e : t.errors) add(FindingKind::torch, 0, -1, std::nullopt, -1, 0, 0, e);
  }

  // Pulse widths and DIR setup/hold of one axis against its driver's minimums.
  void pulses(int a) {
    const AxisPinTrace& p = trace_.axes[a];
    const plan::AxisConfig& cfg = job_.machine.axes[a];
    AxisSummary& sum = v_.axes[a];
    if (!p.present || !cfg.present) return;
    const double ns_per_cycle = 1e9 / job_.clock_hz();
    const double slack = trace_.resolution_cycles * ns_per_cycle + kEps;
    auto smaller = [](double x, double y) { return x < y; };
    auto note_min = [](double& m, double v) { m = m < 0 ? v : std::min(m, v); };
    auto check = [&](FindingKind kind, double measured_cycles, double required_ns, size_t edge, const char* what) {
      const double ns = measured_cycles * ns_per_cycle;
      if (ns >= required_ns - slack) return ns;
      const uint64_t k = event_of_[a][edge];
      add(kind, segment_of(k), a, k, p.leading[edge], required_ns, ns,
          fmt::format("{}: {} {} {:.0f} ns; the driver needs {:.0f} ns", where(k), letter(a), what, ns, required_ns),
          smaller);
      return ns;
    };
    for (size_t j = 0; j < p.leading.size(); ++j) {
      if (!std::isnan(p.trailing[j]))
        note_min(sum.min_high_ns,
                 check(FindingKind::step_high, p.trailing[j] - p.leading[j], cfg.pulse_ns.step_high, j, "STEP high for"));
      if (j > 0 && !std::isnan(p.trailing[j - 1]))
        note_min(sum.min_low_ns, check(FindingKind::step_low, p.leading[j] - p.trailing[j - 1], cfg.pulse_ns.step_low,
                                       j, "STEP low before it for"));
      // The last DIR change at or before this leading edge.
      const auto after = std::upper_bound(p.dir_changes.begin(), p.dir_changes.end(), p.leading[j]);
      if (after != p.dir_changes.begin())
        note_min(sum.min_setup_ns, check(FindingKind::dir_setup, p.leading[j] - *(after - 1), cfg.pulse_ns.dir_setup, j,
                                         "DIR changed before its STEP edge by"));
    }
    for (const double td : p.dir_changes) {
      // The last leading edge strictly before this DIR change.
      const auto after = std::lower_bound(p.leading.begin(), p.leading.end(), td);
      if (after == p.leading.begin()) continue;
      const size_t j = size_t(after - p.leading.begin()) - 1;
      note_min(sum.min_hold_ns,
               check(FindingKind::dir_hold, td - p.leading[j], cfg.pulse_ns.dir_hold, j, "DIR changed after its STEP edge by"));
    }
  }

  void summarize() {
    for (int a = 0; a < plan::kAxes; ++a) {
      AxisSummary& s = v_.axes[a];
      const AxisPinTrace& p = trace_.axes[a];
      s.present = p.present;
      s.step_name = p.step_name;
      s.dir_name = p.dir_name;
      s.step_active_high = p.step_active_high;
      s.dir_positive_high = p.dir_positive_high;
      s.pulses = p.leading.size();
      s.final_position = final_[a];
      s.planned_final = job_.checkpoints.empty() ? start_[a] : job_.checkpoints.back().position[a];
      s.driver = job_.machine.axes[a].present;
      if (s.driver) s.required = job_.machine.axes[a].pulse_ns;
    }
    std::vector<bool> endpoint_ok(segs_.size(), true), string_ok(segs_.size(), true);
    for (const Finding& f : v_.findings) {
      if (f.segment == 0) continue;
      if (f.kind == FindingKind::endpoint) endpoint_ok[f.segment - 1] = false;
      if (f.kind == FindingKind::move_string) string_ok[f.segment - 1] = false;
    }
    v_.segments_on_endpoint = size_t(std::count(endpoint_ok.begin(), endpoint_ok.end(), true));
    v_.segments_bit_exact = size_t(std::count(string_ok.begin(), string_ok.end(), true));
    // Global first, then by segment (after the plan last), kind and axis.
    std::stable_sort(v_.findings.begin(), v_.findings.end(), [](const Finding& x, const Finding& y) {
      auto key = [](const Finding& f) {
        const size_t s = f.kind == FindingKind::move_count ? 0 : f.segment ? f.segment : SIZE_MAX;
        return std::make_tuple(s, int(f.kind), f.axis);
      };
      return key(x) < key(y);
    });
  }

  const run::CardJob& job_;
  const PinTrace& trace_;
  const std::vector<int64_t> chunk_cycles_;  // every move's planned chunk time (the trace is whole anyway)
  Verdict v_;
  std::vector<SegmentPlan> segs_;
  std::map<size_t, LinePlan> lines_;
  std::vector<uint32_t> seg_of_move_;
  plan::PerAxis<int64_t> start_{}, final_{};
  std::vector<Event> events_;
  plan::PerAxis<std::vector<size_t>> event_of_;
  std::map<std::tuple<int, size_t, int>, size_t> index_;
};

}  // namespace

const char* finding_name(FindingKind k) {
  switch (k) {
    case FindingKind::move_count: return "move_count";
    case FindingKind::endpoint: return "endpoint";
    case FindingKind::deviation: return "deviation";
    case FindingKind::move_string: return "move_string";
    case FindingKind::direction: return "direction";
    case FindingKind::timing: return "timing";
    case FindingKind::step_high: return "step_high";
    case FindingKind::step_low: return "step_low";
    case FindingKind::dir_setup: return "dir_setup";
    case FindingKind::dir_hold: return "dir_hold";
    case FindingKind::torch: return "torch";
  }
  return "unknown";
}

plan::Result<PinTrace> read_pins(const VcdTrace& vcd, const PinMap& map, const run::CardJob& job) {
  plan::Result<PinTrace> r;
  PinTrace t;
  t.file = vcd.file;
  if (!map.unit_s && !vcd.unit_s) {
    r.errors.push_back({vcd.file, {}, "no $timescale: give timescale or clock_hz in a --map file"});
    return r;
  }
  t.unit_s = map.unit_s ? *map.unit_s : *vcd.unit_s;
  const double cycles_per_unit = t.unit_s * job.clock_hz();
  t.resolution_cycles = map.sample_s.value_or(t.unit_s) * job.clock_hz();
  t.end_cycles = double(vcd.end_time) * cycles_per_unit;
  plan::PerAxis<bool> moves{};
  for (const plan::PlannedCardSegment& c : job.planned.card)
    for (int a = 0; a < plan::kAxes; ++a) moves[a] = moves[a] || c.segment.delta[a] != 0;
  for (int a = 0; a < plan::kAxes; ++a) {
    const AxisPins& pins = map.axes[a];
    const plan::AxisConfig& cfg = job.machine.axes[a];
    const Lookup step = find_pin(vcd, map, a, true, moves[a] || pins.step_loc.line > 0);
    if (step.error) r.errors.push_back(*step.error);
    if (!step.var) continue;
    const Lookup dir = find_pin(vcd, map, a, false, true);
    if (dir.error) r.errors.push_back(*dir.error);
    if (!dir.var) continue;
    AxisPinTrace& ax = t.axes[a];
    ax.present = true;
    ax.step_name = step.var->path;
    ax.dir_name = dir.var->path;
    // Axes the machine does not have: the card's reset polarity (active high, DIR high = +).
    ax.step_active_high = pins.step_active_high.value_or(!cfg.present || cfg.step_active_high);
    ax.dir_positive_high = pins.dir_positive_high.value_or(!cfg.present || cfg.dir_positive_high);
    extract(vcd, *step.var, *dir.var, cycles_per_unit, ax);
  }
  if (const auto torch = vcd.find("torch"); torch.size() == 1 && torch[0]->width == 1) {
    t.torch_present = true;
    t.torch_name = torch[0]->path;
    bool level = false;
    for (const VcdChange& c : vcd.changes[torch[0]->code]) {
      if (!c.known || bool(c.bits & 1) == level) continue;
      level = !level;
      t.torch_changes.push_back(double(c.time) * cycles_per_unit);
    }
  }
  if (r.errors.empty()) r.value = std::move(t);
  return r;
}

Verdict check_trace(const run::CardJob& job, const PinTrace& trace, const CheckOptions& options) {
  return Checker(job, trace, options).run();
}

}  // namespace cpstep::check

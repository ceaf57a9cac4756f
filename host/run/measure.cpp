// SPDX-License-Identifier: MIT
#include "run/measure.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "plan/gcode.h"
#include "plan/nurbs.h"

namespace cpstep::run {

Windows peak_windows(const plan::AxisConfig& axis) {
  const double spm = axis.steps_per_mm;
  return {1 / (0.02 * axis.max_velocity * spm), std::sqrt(4 / (0.05 * axis.max_accel * spm)),
          std::cbrt(6 / (0.1 * axis.max_jerk * spm))};
}

namespace {

// STEP edge times of an axis in seconds from START.
std::vector<double> edge_times(const AxisPulses& p, uint64_t start_cycle, double clock_hz) {
  std::vector<double> t(p.cycles.size());
  for (size_t i = 0; i < t.size(); ++i) t[i] = double(int64_t(p.cycles[i] - start_cycle)) / clock_hz;
  return t;
}

}  // namespace

std::vector<plan::StepperSteps> klipper_path_steps(const CardJob& job) {
  if (!(job.machine.planner.fit_arcs_mm > 0)) return plan::path_steps(job.planned, job.clock_hz());
  plan::Machine m = job.machine;
  m.planner.fit_arcs_mm = 0;
  plan::PerAxis<double> start_mm{};
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present) start_mm[a] = double(job.start[a]) / m.axes[a].steps_per_mm;
  auto parsed = plan::load_gcode(job.job_file, plan::gcode_options(m, start_mm));
  if (!parsed.ok()) return {};
  auto segs = plan::make_step_segments(*parsed, m);
  if (!segs.ok()) return {};
  auto feeds = plan::plan_feeds(*segs.value, m, job.job_file);
  if (!feeds.ok()) return {};
  plan::PlannedJob p;
  p.step_segments = std::move(*segs.value);
  p.feeds = std::move(*feeds.value);
  return plan::path_steps(p, job.clock_hz());
}

RunMeasure measure_run(const CardJob& job, const CardRun& run) {
  RunMeasure m;
  m.moves = run.move_cycles.size();
  const int64_t start = int64_t(run.start_cycle);
  const size_t n = std::min({run.move_cycles.size(), job.ideal_cycles.size(), job.chunk_cycles.size()});
  for (size_t i = 0; i < n; ++i) {
    const int64_t event = int64_t(run.move_cycles[i]);
    const double err = std::abs(double(event - start) - job.ideal_cycles[i]);
    if (err > m.max_timing_error_cycles) {
      m.max_timing_error_cycles = err;
      m.max_timing_error_move = i + 1;
    }
    const int64_t chunk_err = std::abs(event - start - job.chunk_cycles[i]);
    m.max_chunk_error_cycles = std::max(m.max_chunk_error_cycles, chunk_err);
    if (chunk_err != 0) ++m.moves_off_chunk_time;
  }
  if (!run.move_cycles.empty()) {
    m.job_time_cycles = run.move_cycles.back() - run.start_cycle;
    m.job_time_s = double(m.job_time_cycles) / job.clock_hz();
  }
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job.machine.axes[a];
    AxisMeasure& am = m.axes[a];
    am.present = ax.present;
    if (!ax.present) continue;
    const AxisPulses& p = run.pulses[a];
    am.pulses = p.cycles.size();
    const Windows h = peak_windows(ax);
    am.window = h;
    const std::vector<double> times = edge_times(p, run.start_cycle, job.clock_hz());
    const std::vector<int> dirs(p.dirs.begin(), p.dirs.end());
    const double spm = ax.steps_per_mm;
    am.peak.v = plan::realized_peaks(times, dirs, spm, h.v, kEvaluationsPerWindow).v;
    am.peak.a = plan::realized_peaks(times, dirs, spm, h.a, kEvaluationsPerWindow).a;
    am.peak.j = plan::realized_peaks(times, dirs, spm, h.j, kEvaluationsPerWindow).j;
    am.tolerance = {1 / (h.v * spm), 4 / (h.a * h.a * spm), 6 / (h.j * h.j * h.j * spm)};
    am.within_limits = am.peak.v <= ax.max_velocity + am.tolerance.v &&
                       am.peak.a <= ax.max_accel + am.tolerance.a &&
                       am.peak.j <= ax.max_jerk + am.tolerance.j;
  }
  if (run.pins_observed) m.curve = curve_deviation(job, run);
  if (run.pins_observed) {
    std::vector<plan::StepperSteps> steppers;
    for (int a = 0; a < plan::kAxes; ++a) {
      const AxisPulses& p = run.pulses[a];
      if (p.cycles.empty()) continue;
      plan::StepperSteps s;
      s.cycles.reserve(p.cycles.size());
      for (uint64_t c : p.cycles) s.cycles.push_back(c - run.start_cycle);
      s.dirs = p.dirs;
      steppers.push_back(std::move(s));
    }
    m.klipper_pins_25us = plan::queue_step_cost(steppers, 25e-6 * job.clock_hz());
    const std::vector<plan::StepperSteps> path = klipper_path_steps(job);
    m.klipper_25us = plan::queue_step_cost(path, 25e-6 * job.clock_hz());
    m.klipper_1us = plan::queue_step_cost(path, 1e-6 * job.clock_hz());
  }
  return m;
}

CurveDeviation curve_deviation(const CardJob& job, const CardRun& run) {
  CurveDeviation d;
  // The curves of the job, by the G-code block they came from.
  auto parsed = plan::load_gcode(job.job_file, plan::gcode_options(job.machine));
  if (!parsed.ok()) return d;
  std::map<std::pair<int, int>, const plan::MotionBlock*> curves;
  for (const auto& b : parsed->blocks)
    if (b.kind == plan::MotionKind::nurbs && b.curve) curves[{b.loc.line, b.loc.col}] = &b;
  if (curves.empty()) return d;
  const std::vector<plan::PerAxis<double>> path = card_path(job, run);
  std::unique_ptr<plan::CurveDistance> dist;
  const plan::MotionBlock* current = nullptr;
  double sum2 = 0;
  uint64_t prev = 0;  // moves before this checkpoint's card segment
  for (const Checkpoint& cp : job.checkpoints) {
    auto it = curves.find({cp.loc.line, cp.loc.col});
    if (it != curves.end()) {
      if (it->second != current) {
        current = it->second;
        dist = std::make_unique<plan::CurveDistance>(*current->curve);
        ++d.curves;
      }
      const double z = current->curve->points().front()[2];
      for (uint64_t i = prev; i <= cp.moves && i < path.size(); ++i) {
        const double e = (*dist)(Eigen::Vector3d(path[i][0], path[i][1], z));
        ++d.positions;
        sum2 += e * e;
        if (e > d.max_mm) {
          d.max_mm = e;
          d.worst_loc = cp.loc;
          d.worst_x_mm = path[i][0];
          d.worst_y_mm = path[i][1];
        }
      }
    } else {
      current = nullptr;
    }
    prev = cp.moves;
  }
  if (d.positions) d.rms_mm = std::sqrt(sum2 / double(d.positions));
  return d;
}

namespace {

// Position in mm of one axis at each grid time: the piecewise-linear curve
// through (edge time, steps after the edge), 0 before the first edge.
std::vector<double> sample_position(const std::vector<double>& times, const std::vector<int8_t>& dirs,
                                    double spm, const std::vector<double>& grid) {
  std::vector<double> out(grid.size());
  size_t next = 0;     // first edge later than the grid time
  double after = 0;    // steps after edge next - 1
  for (size_t g = 0; g < grid.size(); ++g) {
    while (next < times.size() && times[next] <= grid[g]) after += dirs[next++];
    double steps = after;
    if (next > 0 && next < times.size() && times[next] > times[next - 1]) {
      const double f = (grid[g] - times[next - 1]) / (times[next] - times[next - 1]);
      steps += f * dirs[next];
    }
    out[g] = steps / spm;
  }
  return out;
}

// Central differences of y on a grid with k samples per h: first, second and
// third derivative at sample i (0 where the stencil leaves the grid).
struct Derivatives {
  const std::vector<double>& y;
  size_t k;
  double h;
  double d1(size_t i) const {
    return i >= k && i + k < y.size() ? (y[i + k] - y[i - k]) / (2 * h) : 0;
  }
  double d2(size_t i) const {
    return i >= k && i + k < y.size() ? (y[i + k] - 2 * y[i] + y[i - k]) / (h * h) : 0;
  }
  double d3(size_t i) const {
    return i >= 2 * k && i + 2 * k < y.size()
               ? (y[i + 2 * k] - 2 * y[i + k] + 2 * y[i - k] - y[i - 2 * k]) / (2 * h * h * h)
               : 0;
  }
};

}  // namespace

KinematicSeries kinematic_series(const CardJob& job, const CardRun& run, const RunMeasure& m) {
  KinematicSeries s;
  // One window per quantity for the whole plot: the longest any moving axis needs.
  Windows h;
  for (const AxisMeasure& am : m.axes) {
    if (!am.present || am.pulses == 0) continue;
    h = {std::max(h.v, am.window.v), std::max(h.a, am.window.a), std::max(h.j, am.window.j)};
  }
  if (h.j <= 0 || m.moves == 0) return s;
  const double duration = m.job_time_s;
  const double dt = std::max(duration / 4000, 2.5e-4);
  auto samples = [dt](double w) { return std::max<size_t>(1, size_t(std::lround(w / dt))); };
  const size_t kv = samples(h.v), ka = samples(h.a), kj = samples(h.j);
  s.window = {double(kv) * dt, double(ka) * dt, double(kj) * dt};
  // The grid runs beyond both ends so that every stencil of the shown part fits.
  const size_t pad = 4 * std::max({kv, ka, kj});
  const size_t shown = size_t(std::ceil(duration / dt)) + 1;
  std::vector<double> grid(shown + 2 * pad);
  for (size_t g = 0; g < grid.size(); ++g) grid[g] = (double(g) - double(pad)) * dt;

  std::vector<int> moving;
  plan::PerAxis<std::vector<double>> pos;
  for (int a = 0; a < plan::kAxes; ++a) {
    if (!m.axes[a].present || m.axes[a].pulses == 0) continue;
    moving.push_back(a);
    pos[a] = sample_position(edge_times(run.pulses[a], run.start_cycle, job.clock_hz()),
                             run.pulses[a].dirs, job.machine.axes[a].steps_per_mm, grid);
  }
  // Path speed with the window of each quantity; its derivatives are the
  // measured path acceleration and jerk.
  auto path_speed = [&](size_t k, double w) {
    std::vector<double> speed(grid.size(), 0.0);
    for (int a : moving) {
      const Derivatives d{pos[a], k, w};
      for (size_t g = 0; g < grid.size(); ++g) speed[g] += d.d1(g) * d.d1(g);
    }
    for (double& v : speed) v = std::sqrt(v);
    return speed;
  };
  const std::vector<double> speed_v = path_speed(kv, s.window.v), speed_a = path_speed(ka, s.window.a),
                            speed_j = path_speed(kj, s.window.j);
  const Derivatives dsa{speed_a, ka, s.window.a}, dsj{speed_j, kj, s.window.j};

  const auto& feeds = job.planned.feeds;
  size_t f = 0;
  for (size_t g = pad; g < pad + shown; ++g) {
    const double t = grid[g];
    s.t.push_back(t);
    for (int a : moving) {
      s.v[a].push_back(Derivatives{pos[a], kv, s.window.v}.d1(g));
      s.a[a].push_back(Derivatives{pos[a], ka, s.window.a}.d2(g));
      s.j[a].push_back(Derivatives{pos[a], kj, s.window.j}.d3(g));
    }
    s.path_v.push_back(speed_v[g]);
    s.path_a.push_back(dsa.d1(g));
    s.path_j.push_back(dsj.d2(g));
    while (f + 1 < feeds.size() && feeds[f + 1].t_start <= t) ++f;
    plan::KinState st;
    if (f < feeds.size() && feeds[f].profile.duration > 0 && t >= feeds[f].t_start &&
        t <= feeds[f].t_start + feeds[f].profile.duration)
      st = feeds[f].profile.at(t - feeds[f].t_start);
    s.plan_v.push_back(st.v);
    s.plan_a.push_back(st.a);
    s.plan_j.push_back(st.j);
  }
  return s;
}

std::vector<plan::PerAxis<double>> card_path(const CardJob& job, const CardRun& run) {
  std::vector<plan::PerAxis<double>> out;
  out.reserve(run.move_cycles.size() + 1);
  plan::PerAxis<int64_t> steps = run.start_position;  // where the card stood (a resumed run: not 0)
  plan::PerAxis<size_t> next{};
  auto mm = [&] {
    plan::PerAxis<double> p{};
    for (int a = 0; a < plan::kAxes; ++a)
      if (job.machine.axes[a].present) p[a] = double(steps[a]) / job.machine.axes[a].steps_per_mm;
    return p;
  };
  out.push_back(mm());
  for (uint64_t move : run.move_cycles) {
    for (int a = 0; a < plan::kAxes; ++a) {
      const AxisPulses& p = run.pulses[a];
      while (next[a] < p.cycles.size() && p.cycles[next[a]] == move + 1) steps[a] += p.dirs[next[a]++];
    }
    out.push_back(mm());
  }
  return out;
}

}  // namespace cpstep::run

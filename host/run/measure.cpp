// SPDX-License-Identifier: MIT
#include "run/measure.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <tuple>
#include <memory>

#include <fmt/format.h>

#include "plan/arc_fit.h"
#include "plan/gcode.h"
#include "plan/planner.h"
#include "plan/segments.h"
#include "plan/nurbs.h"

namespace cpstep::run {

Windows peak_windows(const plan::AxisConfig& axis) {
  const double spm = axis.steps_per_mm;
  return {1 / (0.02 * axis.max_velocity * spm), std::sqrt(4 / (0.05 * axis.max_accel * spm)),
          std::cbrt(6 / (0.1 * axis.max_jerk * spm))};
}

namespace {

// The job as Klipper takes it: its own plan, or, when the plan fitted arcs (G1
// chains, planner.fit_arcs_mm; NURBS on a card that walks arcs), the feeds of the G-code as written (Klipper takes
// the lines as they are). Empty when that plan fails.
plan::PlannedJob klipper_plan(const CardJob& job) {
  plan::Machine m = job.machine;
  m.planner.fit_arcs_mm = 0;
  plan::PerAxis<double> start_mm{};
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present) start_mm[a] = double(job.start[a]) / m.axes[a].steps_per_mm;
  plan::PlannedJob p;
  auto parsed = plan::load_gcode(job.job_file, plan::gcode_options(m, start_mm));
  if (!parsed.ok()) return p;
  auto segs = plan::make_step_segments(*parsed, m);
  if (!segs.ok()) return p;
  auto feeds = plan::plan_feeds(*segs.value, m, job.job_file);
  if (!feeds.ok()) return p;
  p.step_segments = std::move(*segs.value);
  p.feeds = std::move(*feeds.value);
  return p;
}

// Whether the plan's blocks were fitted (G1 chains, or NURBS as arcs on a card that walks them).
bool fits_arcs(const CardJob& job) { return plan::arc_fit_tolerances(job.machine).any(); }

}  // namespace

std::vector<plan::StepperSteps> klipper_path_steps(const CardJob& job) {
  if (!fits_arcs(job)) return plan::path_steps(job.planned, job.clock_hz());
  return plan::path_steps(klipper_plan(job), job.clock_hz());
}

std::pair<plan::QueueStepCost, plan::QueueStepCost> klipper_path_costs(const CardJob& job) {
  plan::QueueStepCounter at25(25e-6 * job.clock_hz()), at1(1e-6 * job.clock_hz());
  const auto add = [&](int stepper, uint64_t cycle, int8_t dir) {
    at25.add(stepper, cycle, dir);
    at1.add(stepper, cycle, dir);
  };
  // Step by step, whichever plan: no step kept.
  if (fits_arcs(job)) {
    // The G-code's lines as they are, read and planned as they stream (step
    // segments and feeds: what klipper_plan() makes whole).
    plan::Machine m = job.machine;
    m.planner.fit_arcs_mm = 0;
    plan::PerAxis<double> start_mm{};
    for (int a = 0; a < plan::kAxes; ++a)
      if (m.axes[a].present) start_mm[a] = double(job.start[a]) / m.axes[a].steps_per_mm;
    plan::StepSegmenter segmenter(m, job.job_file);
    plan::FeedPlanner feeds(m, job.job_file);
    std::deque<plan::StepSegment> waiting;  // their feeds not yet out
    const auto pump = [&] {
      while (auto s = segmenter.next()) {
        feeds.push(*s);
        waiting.push_back(std::move(*s));
      }
      while (auto f = feeds.next()) {
        plan::for_each_segment_step(waiting.front(), *f, job.clock_hz(), add);
        waiting.pop_front();
      }
    };
    auto read = plan::stream_gcode(job.job_file, plan::gcode_options(m, start_mm), [&](plan::MotionBlock&& b, size_t i) {
      segmenter.push(b, i);
      pump();
    });
    segmenter.finish();
    pump();
    feeds.finish();
    pump();
    if (!read.ok() || !segmenter.done() || !feeds.done()) return {};
  } else if (job.streamed) {
    PlanCursor cursor(job);
    for (plan::StreamedStep st; cursor.next_step(st);) plan::for_each_segment_step(st.segment, st.feed, job.clock_hz(), add);
  } else {
    plan::for_each_path_step(job.planned, job.clock_hz(), add);
  }
  return {at25.finish(), at1.finish()};
}

// The job's NURBS blocks by their G-code position, and the distance to the one
// the card is on.
struct RunMeter::Curves {
  std::shared_ptr<const plan::Job> parsed;  // a streamed job's own blocks, or the G-code read again
  std::deque<plan::MotionBlock> curves;     // or the curves of its G-code's text, read again
  std::map<std::pair<int, int>, const plan::MotionBlock*> by_loc;
  const plan::MotionBlock* current = nullptr;
  std::unique_ptr<plan::CurveDistance> distance;
  const plan::MotionBlock* at(const plan::SourceLoc& loc) const {
    const auto it = by_loc.find({loc.line, loc.col});
    return it == by_loc.end() ? nullptr : it->second;
  }
};

struct RunMeter::AxisState {
  bool present = false;
  double spm = 1;
  Windows window;
  std::unique_ptr<plan::PeakMeter> v, a, j;
  uint64_t pulses = 0;
  // The series: steps after the edges so far (from 0 at START), the time of the
  // last edge, the next grid sample not yet taken and the samples taken.
  double after = 0;
  double last_t = 0;
  bool any = false;
  size_t next = 0;
  std::vector<double> samples;  // mm
};

RunMeter::RunMeter(const CardJob& job, bool klipper)
    : job_(job), clock_(job), pins_(25e-6 * job.clock_hz()), klipper_(klipper) {
  axes_.resize(plan::kAxes);
  size_t k_max = 1;
  dt_ = std::max(job.planned.stats.duration_s / 4000, 2.5e-4);
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job.machine.axes[a];
    AxisState& st = axes_[size_t(a)];
    st.present = ax.present;
    if (!ax.present) continue;
    st.spm = ax.steps_per_mm;
    st.window = peak_windows(ax);
    st.v = std::make_unique<plan::PeakMeter>(st.spm, st.window.v, kEvaluationsPerWindow);
    st.a = std::make_unique<plan::PeakMeter>(st.spm, st.window.a, kEvaluationsPerWindow);
    st.j = std::make_unique<plan::PeakMeter>(st.spm, st.window.j, kEvaluationsPerWindow);
    for (double w : {st.window.v, st.window.a, st.window.j})
      k_max = std::max(k_max, size_t(std::max(1L, std::lround(w / dt_))));
  }
  pad_ = 4 * k_max + 2;
}

RunMeter::~RunMeter() = default;

void RunMeter::start(uint64_t start_cycle, const plan::PerAxis<int64_t>& position) {
  start_cycle_ = start_cycle;
  for (int a = 0; a < plan::kAxes; ++a) steps_[a] = position[a] + origin_[a];
  position_point();
  // The curves, when the job has any (its step segments say), and the first checkpoint's.
  const bool nurbs = job_.has_nurbs;
  std::shared_ptr<const plan::Job> blocks = job_.blocks;
  if (nurbs && job_.gcode_file) {
    // Only the curves of the job's file are kept.
    curves_ = std::make_unique<Curves>();
    plan::GcodeBlockReader reader(job_.gcode_file, job_.gcode_options);
    while (auto b = reader.next())
      if (b->kind == plan::MotionKind::nurbs && b->curve) {
        const plan::MotionBlock& kept = curves_->curves.emplace_back(std::move(*b));
        curves_->by_loc[{kept.loc.line, kept.loc.col}] = &kept;
      }
    if (curves_->by_loc.empty()) curves_.reset();
  }
  // The curves of parsed blocks, by their line and column; none: no Curves.
  const auto index = [this](std::shared_ptr<const plan::Job> parsed) {
    curves_ = std::make_unique<Curves>();
    curves_->parsed = std::move(parsed);
    for (const auto& b : curves_->parsed->blocks)
      if (b.kind == plan::MotionKind::nurbs && b.curve) curves_->by_loc[{b.loc.line, b.loc.col}] = &b;
    if (curves_->by_loc.empty()) curves_.reset();
  };
  if (nurbs && !curves_ && blocks) index(std::move(blocks));
  if (nurbs && !curves_ && !job_.gcode_file) {
    // No blocks given, or fitted blocks, which hold the arcs a NURBS became on a card
    // that walks them (plan/arc_fit.h), not the curve: the G-code as written has it, at
    // the same line and column as its arcs.
    auto parsed = plan::load_gcode(job_.job_file, plan::gcode_options(job_.machine));
    if (parsed.ok()) index(std::make_shared<const plan::Job>(std::move(*parsed.value)));
  }
  checkpoint_from_ = 0;
  checkpoints_.reset();
  checkpoint_ = nullptr;
  if (curves_) {
    checkpoints_.emplace(job_);
    checkpoint_ = checkpoints_->next();
  }
  if (curves_ && checkpoint_) {
    curves_->current = curves_->at(checkpoint_->loc);
    if (curves_->current) {
      curves_->distance = std::make_unique<plan::CurveDistance>(*curves_->current->curve);
      ++m_.curve.curves;
    }
  }
  curve_point();
}

void RunMeter::position_point() {
  plan::PerAxis<double> p{};
  for (int a = 0; a < plan::kAxes; ++a)
    if (axes_[size_t(a)].present) p[a] = double(steps_[a]) / axes_[size_t(a)].spm;
  if (path_.size() == kMaxPathPoints) {
    // Every other point stays (the start among them); from now on every 2^k-th move.
    for (size_t i = 0; 2 * i < path_.size(); ++i) path_[i] = path_[2 * i];
    path_.resize((path_.size() + 1) / 2);
    path_stride_ *= 2;
  }
  path_.push_back(p);
}

void RunMeter::curve_point() {
  if (!curves_) return;
  const uint64_t i = m_.moves;  // the position after i moves
  for (;;) {
    if (!checkpoint_) return;
    const Checkpoint& cp = *checkpoint_;
    if (curves_->current && i >= checkpoint_from_ && i <= cp.moves) {
      const double z = curves_->current->curve->points().front()[2];
      const double x = double(steps_[0]) / axes_[0].spm, y = double(steps_[1]) / axes_[1].spm;
      const double e = (*curves_->distance)(Eigen::Vector3d(x, y, z));
      ++m_.curve.positions;
      curve_sum2_ += e * e;
      if (e > m_.curve.max_mm) {
        m_.curve.max_mm = e;
        m_.curve.worst_loc = cp.loc;
        m_.curve.worst_x_mm = x;
        m_.curve.worst_y_mm = y;
      }
    }
    if (i != cp.moves) return;
    // The card segment ends here: the next one starts at this position.
    checkpoint_from_ = cp.moves;
    checkpoint_ = checkpoints_->next();
    if (!checkpoint_) return;
    const plan::MotionBlock* b = curves_->at(checkpoint_->loc);
    if (b && b != curves_->current) {
      curves_->distance = std::make_unique<plan::CurveDistance>(*b->curve);
      ++m_.curve.curves;
    }
    curves_->current = b;
  }
}

void RunMeter::decimate() {
  // Keep the samples at even multiples of the doubled spacing: old index i = i0 + 2 n.
  const size_t i0 = pad_ % 2;
  for (AxisState& st : axes_) {
    if (!st.present) continue;
    std::vector<double> kept;
    for (size_t i = i0; i < st.samples.size(); i += 2) kept.push_back(st.samples[i]);
    st.samples = std::move(kept);
    st.next = st.next > i0 ? (st.next - i0 + 1) / 2 : 0;
  }
  pad_ = (pad_ - i0) / 2;
  dt_ *= 2;
}

void RunMeter::move(uint64_t edge_cycle, uint32_t leading, const plan::PerAxis<int8_t>& dirs) {
  const double hz = job_.clock_hz();
  const int64_t event = int64_t(edge_cycle) - 1 - int64_t(start_cycle_);
  ++m_.moves;
  last_edge_ = edge_cycle;
  if (clock_.next()) {
    const double err = std::abs(double(event) - clock_.ideal());
    if (err > m_.max_timing_error_cycles) {
      m_.max_timing_error_cycles = err;
      m_.max_timing_error_move = m_.moves;
    }
    const int64_t chunk_err = std::abs(event - clock_.chunk());
    m_.max_chunk_error_cycles = std::max(m_.max_chunk_error_cycles, chunk_err);
    if (chunk_err != 0) ++m_.moves_off_chunk_time;
  }
  const double t = double(int64_t(edge_cycle - start_cycle_)) / hz;
  while (t > double(kMaxSeriesSamples - 1) * dt_) decimate();
  for (int a = 0; a < plan::kAxes; ++a) {
    if (!(leading >> a & 1)) continue;
    steps_[a] += dirs[a];
    AxisState& st = axes_[size_t(a)];
    if (!st.present) continue;
    ++st.pulses;
    st.v->add(t, dirs[a]);
    st.a->add(t, dirs[a]);
    st.j->add(t, dirs[a]);
    if (klipper_) pins_.add(a, edge_cycle - start_cycle_, dirs[a]);
    // The series' samples before this edge: between the last edge and this one.
    for (;; ++st.next) {
      const double g = (double(st.next) - double(pad_)) * dt_;
      if (!(g < t)) break;
      double steps = st.after;
      if (st.any && t > st.last_t) steps += (g - st.last_t) / (t - st.last_t) * dirs[a];
      if (st.samples.size() <= st.next) st.samples.resize(st.next + 1);
      st.samples[st.next] = steps / st.spm;
    }
    st.after += dirs[a];
    st.last_t = t;
    st.any = true;
  }
  if (m_.moves % path_stride_ == 0) position_point();
  curve_point();
}

RunMeasure RunMeter::finish(const CardRun& run) {
  finished_ = true;
  if (m_.moves > 0) {
    m_.job_time_cycles = last_edge_ - 1 - start_cycle_;
    m_.job_time_s = double(m_.job_time_cycles) / job_.clock_hz();
  }
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job_.machine.axes[a];
    AxisMeasure& am = m_.axes[a];
    AxisState& st = axes_[size_t(a)];
    am.present = ax.present;
    if (!ax.present) continue;
    am.pulses = st.pulses;
    am.window = st.window;
    am.peak = {st.v->finish().v, st.a->finish().a, st.j->finish().j};
    const Windows& h = st.window;
    const double spm = ax.steps_per_mm;
    am.tolerance = {1 / (h.v * spm), 4 / (h.a * h.a * spm), 6 / (h.j * h.j * h.j * spm)};
    am.within_limits = am.peak.v <= ax.max_velocity + am.tolerance.v && am.peak.a <= ax.max_accel + am.tolerance.a &&
                       am.peak.j <= ax.max_jerk + am.tolerance.j;
    if (st.pulses > 0) window_ = {std::max(window_.v, h.v), std::max(window_.a, h.a), std::max(window_.j, h.j)};
  }
  // The series to the end of the grid: shown samples to the job's time, a pad after.
  const size_t shown = size_t(std::ceil(m_.job_time_s / dt_)) + 1;
  const size_t total = shown + 2 * pad_;
  for (AxisState& st : axes_) {
    if (!st.present) continue;
    st.samples.resize(total, 0.0);
    for (; st.next < total; ++st.next) st.samples[st.next] = st.after / st.spm;
  }
  samples_ = total;
  if (path_.size() < 2 || m_.moves % path_stride_ != 0) position_point();
  if (m_.curve.positions) m_.curve.rms_mm = std::sqrt(curve_sum2_ / double(m_.curve.positions));
  if (run.pins_observed && klipper_) {
    m_.klipper = true;
    m_.klipper_pins_25us = pins_.finish();
    try {
      std::tie(m_.klipper_25us, m_.klipper_1us) = klipper_path_costs(job_);
    } catch (const JobFileChanged& e) {
      // The run is done as planned; its path cannot be planned again.
      m_.klipper_25us = m_.klipper_1us = {};
      m_.klipper_25us.error = m_.klipper_1us.error = e.what();
    }
  }
  if (!run.pins_observed) m_.curve = {};
  return m_;
}

namespace {

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

KinematicSeries RunMeter::series() const {
  KinematicSeries s;
  if (!finished_ || window_.j <= 0 || m_.moves == 0) return s;
  const double dt = dt_;
  auto samples = [dt](double w) { return std::max<size_t>(1, size_t(std::lround(w / dt))); };
  const size_t kv = samples(window_.v), ka = samples(window_.a), kj = samples(window_.j);
  s.window = {double(kv) * dt, double(ka) * dt, double(kj) * dt};
  std::vector<int> moving;
  for (int a = 0; a < plan::kAxes; ++a)
    if (axes_[size_t(a)].present && axes_[size_t(a)].pulses > 0) moving.push_back(a);
  // Path speed with the window of each quantity; its derivatives are the
  // measured path acceleration and jerk.
  auto path_speed = [&](size_t k, double w) {
    std::vector<double> speed(samples_, 0.0);
    for (int a : moving) {
      const Derivatives d{axes_[size_t(a)].samples, k, w};
      for (size_t g = 0; g < samples_; ++g) speed[g] += d.d1(g) * d.d1(g);
    }
    for (double& v : speed) v = std::sqrt(v);
    return speed;
  };
  const std::vector<double> speed_v = path_speed(kv, s.window.v), speed_a = path_speed(ka, s.window.a),
                            speed_j = path_speed(kj, s.window.j);
  const Derivatives dsa{speed_a, ka, s.window.a}, dsj{speed_j, kj, s.window.j};
  // The plan's feeds in time order (a streamed job's made again as the series reaches them).
  std::optional<PlanCursor> cursor;
  if (job_.streamed) cursor.emplace(job_);
  size_t next_feed = 0;
  const auto feed_after = [&](std::optional<plan::PlannedSegment>& out) {
    out.reset();
    if (cursor) {
      plan::StreamedStep st;
      try {
        if (cursor->next_step(st)) out = std::move(st.feed);
      } catch (const JobFileChanged&) {
        cursor.reset();  // the plan's columns end there (the file written over since the job was planned)
      }
    } else if (next_feed < job_.planned.feeds.size()) {
      out = job_.planned.feeds[next_feed++];
    }
  };
  std::optional<plan::PlannedSegment> feed, following;
  feed_after(feed);
  feed_after(following);
  for (size_t g = pad_; g + pad_ < samples_; ++g) {
    const double t = (double(g) - double(pad_)) * dt;
    s.t.push_back(t);
    for (int a : moving) {
      const std::vector<double>& y = axes_[size_t(a)].samples;
      s.v[a].push_back(Derivatives{y, kv, s.window.v}.d1(g));
      s.a[a].push_back(Derivatives{y, ka, s.window.a}.d2(g));
      s.j[a].push_back(Derivatives{y, kj, s.window.j}.d3(g));
    }
    s.path_v.push_back(speed_v[g]);
    s.path_a.push_back(dsa.d1(g));
    s.path_j.push_back(dsj.d2(g));
    while (following && following->t_start <= t) {
      feed = std::move(following);
      feed_after(following);
    }
    plan::KinState st;
    if (feed && feed->profile.duration > 0 && t >= feed->t_start && t <= feed->t_start + feed->profile.duration)
      st = feed->profile.at(t - feed->t_start);
    s.plan_v.push_back(st.v);
    s.plan_a.push_back(st.a);
    s.plan_j.push_back(st.j);
  }
  return s;
}

void replay(const CardRun& run, RunMeter& meter) {
  meter.start(run.start_cycle, run.start_position);
  plan::PerAxis<size_t> next{};
  for (uint64_t move : run.move_cycles) {
    uint32_t leading = 0;
    plan::PerAxis<int8_t> dirs{};
    for (int a = 0; a < plan::kAxes; ++a) {
      const AxisPulses& p = run.pulses[a];
      if (next[a] < p.cycles.size() && p.cycles[next[a]] == move + 1) {
        leading |= 1u << a;
        dirs[a] = p.dirs[next[a]++];
      }
    }
    meter.move(move + 1, leading, dirs);
  }
}

void add_phase_timer_fault(const CardJob& job, const RunMeasure& m, CardRun& run) {
  if (!job.caps.ptimer || !run.pins_observed || run.feed_scaled || m.moves_off_chunk_time == 0) return;
  run.faults.push_back(host_fault(
      HostFault::late, fmt::format("{} move(s) fired off the cycles the host computed for the phase-timer card, "
                                   "the farthest {} cycles off",
                                   m.moves_off_chunk_time, m.max_chunk_error_cycles)));
}

RunMeasure measure_run(const CardJob& job, const CardRun& run) {
  RunMeter meter(job);
  replay(run, meter);
  return meter.finish(run);
}

}  // namespace cpstep::run

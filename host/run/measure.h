// SPDX-License-Identifier: MIT
// What a card run amounts to, measured from its pins against the plan:
// timing errors, per-axis realized velocity / acceleration / jerk peaks
// (plan::realized_peaks on the STEP edge times) and the series the plots show.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "plan/common.h"
#include "plan/kinematics.h"
#include "plan/queue_step.h"
#include "run/card_job.h"
#include "run/sim_run.h"

namespace cpstep::run {

// Difference windows h (s) for velocity, acceleration and jerk.
struct Windows {
  double v = 0, a = 0, j = 0;
};

struct AxisMeasure {
  bool present = false;
  uint64_t pulses = 0;            // leading STEP edges
  Windows window;                 // h of realized_peaks, per quantity
  plan::AxisPeaks peak;           // realized, mm/s, mm/s^2, mm/s^3
  plan::AxisPeaks tolerance;      // one step of quantization: 1/(h_v spm), 4/(h_a^2 spm), 6/(h_j^3 spm)
  bool within_limits = false;     // every peak <= its machine limit + its tolerance
};

// The stepped path's deviation from the job's NURBS curves (G5, G5.1,
// G5.2..G5.3), measured from the pins: the card's position after every move
// of a curve's card segments (and before its first), each at its distance
// from the curve (XY; plan::CurveDistance, exact within 1e-6 mm).
struct CurveDeviation {
  uint64_t curves = 0;        // NURBS blocks run
  uint64_t positions = 0;     // card positions measured
  double max_mm = 0, rms_mm = 0;
  plan::SourceLoc worst_loc;  // the block of the worst position
  double worst_x_mm = 0, worst_y_mm = 0;
};

struct RunMeasure {
  uint64_t moves = 0;                  // move events seen
  double job_time_s = 0;               // START to the last move event
  uint64_t job_time_cycles = 0;
  double max_timing_error_cycles = 0;  // max |event - (START + ideal time)|
  uint64_t max_timing_error_move = 0;  // 1-based move where it occurs
  int64_t max_chunk_error_cycles = 0;  // max |event - (START + chunk time)|: 0 unless stretched
  uint64_t moves_off_chunk_time = 0;
  plan::PerAxis<AxisMeasure> axes;
  CurveDeviation curve;
  // The job's steps on Klipper's wire (plan/queue_step.h), per stepper: where
  // Klipper places them (plan::path_steps) at its default max_error of 25 us
  // and at 1 us, and where the card's pins put them, at 25 us (run.pins_observed only).
  plan::QueueStepCost klipper_25us, klipper_1us, klipper_pins_25us;
  bool klipper = false;  // the three above were measured (RunMeter's klipper)
};

// The windows for an axis: each as short as it can be while one step of
// quantization moves the estimate by at most a fixed share of the axis's
// limit: 2 % of vmax, 5 % of amax, 10 % of jmax, i.e.
//   h_v = 1 / (0.02 vmax spm), h_a = sqrt(4 / (0.05 amax spm)), h_j = cbrt(6 / (0.1 jmax spm)).
Windows peak_windows(const plan::AxisConfig& axis);
// realized_peaks evaluates its differences this many times per window.
inline constexpr int kEvaluationsPerWindow = 8;

// The run measured from its recorded events (CardRun::move_cycles and pulses,
// SimRunOptions::record_pins): RunMeter fed with them. A run whose pins were
// not observed (a real card) gives the counts only.
RunMeasure measure_run(const CardJob& job, const CardRun& run);
// A phase-timer card counts no move as stretched (its timer fires a move when it comes
// due; docs/CORE.md "Phase-timer builds"): there the pins measured against the cycles
// the host computed are the check. Adds a LATE fault to `run` when its pins were
// observed, its time not scaled by the feed, and some move fired off its cycle.
void add_phase_timer_fault(const CardJob& job, const RunMeasure& m, CardRun& run);
class RunMeter;
// A run's recorded events fed to a meter (START, then every move event).
void replay(const CardRun& run, RunMeter& meter);

// The job's steps where Klipper would place them (plan::path_steps): from the
// plan, or, when the machine file fits arcs to G1 chains (planner.fit_arcs_mm),
// from a plan of the G-code as written (Klipper takes the lines as they are).
std::vector<plan::StepperSteps> klipper_path_steps(const CardJob& job);

// Time series for the plots, on a common grid of times from START (s).
struct KinematicSeries {
  Windows window;                               // difference spacing h per quantity
  std::vector<double> t;
  plan::PerAxis<std::vector<double>> v, a, j;   // per axis, mm/s, mm/s^2, mm/s^3
  std::vector<double> path_v, path_a, path_j;   // measured along the path (speed and its derivatives)
  std::vector<double> plan_v, plan_a, plan_j;   // the planner's profile along the path
};

// The job's steps on Klipper's wire where Klipper places them, at max_error 25 us
// and 1 us (RunMeasure::klipper_25us, klipper_1us), counted step by step from
// the plan (plan::QueueStepCounter): bounded memory, whatever the job's length.
std::pair<plan::QueueStepCost, plan::QueueStepCost> klipper_path_costs(const CardJob& job);

// What a run's pins amount to, measured as the run goes (docs/SIM.md
// "Memory"): fed with START and every move event's STEP edges (run_on_sim with
// SimRunOptions::meter, or measure_run from recorded events), it keeps no
// per-move record. Memory is bounded whatever the job's length: the timing
// through MoveClock, the peaks through plan::PeakMeter, Klipper's cost through
// plan::QueueStepCounter, the plots' series on a grid of at most
// kMaxSeriesSamples times (its spacing doubles when the run outlasts it) and
// the path plot at most kMaxPathPoints card positions (every 2^k-th move).
class RunMeter {
 public:
  // klipper: also put the job's steps on Klipper's wire (RunMeasure::klipper_*):
  // the card's pin steps as they come (plan::QueueStepCounter, on every step:
  // on a job of short moves as costly as the simulation itself) and, after the
  // run, the path's steps (the plan made again). `cpstep run --klipper`.
  explicit RunMeter(const CardJob& job, bool klipper = true);
  RunMeter(const RunMeter&) = delete;
  RunMeter& operator=(const RunMeter&) = delete;
  ~RunMeter();

  // START was taken in `start_cycle`; the card's counters read `position`
  // (steps), plus the origin (set_origin: a job run counted from zero).
  void start(uint64_t start_cycle, const plan::PerAxis<int64_t>& position);
  void set_origin(const plan::PerAxis<int64_t>& origin) { origin_ = origin; }
  // A move event whose STEP edges show on the pins in `edge_cycle` (the move's
  // cycle + 1): bit a of `leading` for each axis that stepped, `dirs[a]` its
  // direction (+1 / -1).
  void move(uint64_t edge_cycle, uint32_t leading, const plan::PerAxis<int8_t>& dirs);
  // The measures (once, after the last move). run: whether its pins were
  // observed (the per-pin measures) and its start position.
  RunMeasure finish(const CardRun& run);

  // After finish(): the plots' series, and the card's position in mm before the
  // first move and after every path_stride()-th move and the last.
  [[nodiscard]] KinematicSeries series() const;
  [[nodiscard]] const std::vector<plan::PerAxis<double>>& path() const { return path_; }
  [[nodiscard]] uint64_t path_stride() const { return path_stride_; }

  static constexpr size_t kMaxSeriesSamples = 8192;
  static constexpr size_t kMaxPathPoints = size_t{1} << 18;

 private:
  struct Curves;      // the job's NURBS blocks, for CurveDeviation
  struct AxisState;   // per axis: peaks, Klipper's counter, the series' samples
  void decimate();           // the series' grid spacing doubled
  void position_point();     // the path plot's point at the current position
  void curve_point();        // the current position against the curve it is on

  const CardJob& job_;
  MoveClock clock_;
  plan::QueueStepCounter pins_;  // the pins' steps on Klipper's wire, 25 us
  bool klipper_ = true;
  RunMeasure m_;
  std::unique_ptr<Curves> curves_;
  std::vector<AxisState> axes_;
  uint64_t start_cycle_ = 0;
  bool finished_ = false;
  plan::PerAxis<int64_t> steps_{}, origin_{};
  uint64_t last_edge_ = 0;
  // The series: samples at t = (i - pad_) dt_, i = 0, 1, ...
  double dt_ = 0;
  size_t pad_ = 0, samples_ = 0;
  Windows window_;  // the longest window of any moving axis (finish())
  std::vector<plan::PerAxis<double>> path_;
  uint64_t path_stride_ = 1;
  // CurveDeviation: the checkpoint the current move belongs to.
  std::optional<CheckpointCursor> checkpoints_;
  const Checkpoint* checkpoint_ = nullptr;
  uint64_t checkpoint_from_ = 0;  // moves before its card segment
  double curve_sum2_ = 0;
};

}  // namespace cpstep::run

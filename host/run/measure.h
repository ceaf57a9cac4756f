// SPDX-License-Identifier: MIT
// What a card run amounts to, measured from its pins against the plan:
// timing errors, per-axis realized velocity / acceleration / jerk peaks
// (plan::realized_peaks on the STEP edge times) and the series the plots show.
#pragma once

#include <cstdint>
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
};

// CurveDeviation of a run (zero positions when the job has no curves).
CurveDeviation curve_deviation(const CardJob& job, const CardRun& run);

// The windows for an axis: each as short as it can be while one step of
// quantization moves the estimate by at most a fixed share of the axis's
// limit: 2 % of vmax, 5 % of amax, 10 % of jmax, i.e.
//   h_v = 1 / (0.02 vmax spm), h_a = sqrt(4 / (0.05 amax spm)), h_j = cbrt(6 / (0.1 jmax spm)).
Windows peak_windows(const plan::AxisConfig& axis);
// realized_peaks evaluates its differences this many times per window.
inline constexpr int kEvaluationsPerWindow = 8;

RunMeasure measure_run(const CardJob& job, const CardRun& run);

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
KinematicSeries kinematic_series(const CardJob& job, const CardRun& run, const RunMeasure& m);

// The card's position in mm after every move event (x, y for the path plot),
// from run.start_position.
std::vector<plan::PerAxis<double>> card_path(const CardJob& job, const CardRun& run);

}  // namespace cpstep::run

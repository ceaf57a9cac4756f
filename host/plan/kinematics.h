// SPDX-License-Identifier: MIT
// Realized kinematics: what the card's step events amount to as velocity,
// acceleration and jerk of each axis, to check limits against what was
// actually emitted rather than what was planned.
#pragma once

#include <span>

namespace cpstep::plan {

struct AxisPeaks {
    double v = 0;  // mm/s
    double a = 0;  // mm/s^2
    double j = 0;  // mm/s^3
};

// `times` are the axis's step event times (s, non-decreasing) and `dirs`
// their directions (+1/-1). The position is the piecewise-linear curve
// through (times[k], steps after event k), starting at 0 steps at times[0]
// minus nothing (the curve starts at the first event), resampled every
// window_s / evaluations_per_window seconds; the derivatives are central
// differences over the window h = window_s, evaluated at every sample:
//   v = (p(t+h) - p(t-h)) / 2h, a = (p(t+h) - 2p(t) + p(t-h)) / h^2,
//   j = (p(t+2h) - 2p(t+h) + 2p(t-h) - p(t-2h)) / 2h^3.
// One step of quantization moves them by at most 1/(h spm), 4/(h^2 spm) and
// 6/(h^3 spm): choose h so those are small against the limits. More
// evaluations per window find a peak that falls between two grid points of
// spacing h (the default 1 evaluates on that grid only).
AxisPeaks realized_peaks(std::span<const double> times, std::span<const int> dirs,
                         double steps_per_mm, double window_s, int evaluations_per_window = 1);

}  // namespace cpstep::plan

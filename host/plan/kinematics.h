// SPDX-License-Identifier: MIT
// Realized kinematics: what the card's step events amount to as velocity,
// acceleration and jerk of each axis, to check limits against what was
// actually emitted rather than what was planned.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

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

// realized_peaks() fed one step event at a time (times non-decreasing), in
// memory bounded by the samples of one stencil (4 m + 1, m the evaluations
// per window): the same result, bit for bit, for jobs too long to hold every
// event time. Each grid sample p(t0 + i dt) is computed as soon as an event
// after t arrives (then the two events around t are the last one seen and
// the new one), and each difference is folded into the peaks as soon as its
// stencil is complete and known to lie inside the grid, whose length
// floor((t1 - t0) / dt) + 1 only grows with the last event time t1.
class PeakMeter {
 public:
    PeakMeter(double steps_per_mm, double window_s, int evaluations_per_window = 1);
    void add(double time, int dir);
    // The peaks of the events so far, as realized_peaks would give for them;
    // callable at any time (it completes the grid on local state, in O(m)).
    AxisPeaks finish() const;

 private:
    // Folds the differences whose stencils end before sample `limit`, reading
    // samples through `at`, into `pk`, advancing the next centres `va`, `j`.
    template <class At>
    void fold(std::size_t limit, const At& at, AxisPeaks& pk, std::size_t& va,
              std::size_t& j) const;
    void push(double sample);

    double spm_, h_;
    std::size_t m_;
    double dt_;                     // grid spacing h / m
    bool enabled_;                  // window_s > 0: realized_peaks gives zeros otherwise
    std::size_t events_ = 0;
    double t0_ = 0;                 // first event time: the grid's origin
    double last_t_ = 0, last_pos_ = 0;  // latest event: its time, steps after it
    std::size_t n_ = 0;             // grid length for the events so far
    std::size_t produced_ = 0;      // samples computed: exactly those at t < last_t_
    std::size_t next_va_, next_j_;  // next centres to fold for v/a and for j
    AxisPeaks pk_;                  // peaks of the differences folded so far
    std::vector<double> ring_;      // samples [next_j_ - 2m, produced_), at index & (size - 1)
};

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// Interpolating a NURBS at a fixed period T (seed 002): the parameter u is
// advanced once per period so that the tool moves along the curve at the feed
// V(t) of one 7-phase S-curve over the curve's length (profile.h), by one of
// three updates of du/dt = V(t) / |C'(u)|:
//
//   taylor1  u+ = u + V T / |C'|
//   taylor2  u+ = u + V T / |C'| + T^2/2 (A / |C'| - V^2 (C'.C'') / |C'|^4)   (seed 002 eq. 3)
//   milne    Milne's predictor and Simpson's corrector (eqs. 23-24), started
//            by taylor2 for the first three periods
//
// and measured: the relative feed fluctuation |ds / dS - 1| per period (ds
// the true arc length between successive samples by quadrature of |C'|, dS
// the S-curve's own advance over the period, i.e. V T with V its mean feed
// over the period) and the chord error (docs/CURVES.md).
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "plan/nurbs.h"
#include "plan/profile.h"

namespace cpstep::plan {

enum class InterpMethod { taylor1, taylor2, milne };

std::string_view method_name(InterpMethod m);
std::optional<InterpMethod> parse_method(std::string_view name);

struct InterpLimits {
    double feed = 0;   // mm/s: the S-curve's cruise speed
    double accel = 0;  // mm/s^2
    double jerk = 0;   // mm/s^3
};

struct InterpOptions {
    double period_s = 1e-3;
    InterpMethod method = InterpMethod::milne;
    int max_corrections = 8;          // Simpson corrector iterations (stops earlier when converged)
    int starter_substeps = 256;       // Milne's starter: taylor2 on this many sub-steps of a period
    double low_feed_fraction = 0.1;   // feed_fluctuation_max skips periods slower than this share of the peak
};

struct InterpSample {
    double t = 0;  // s
    double u = 0;  // curve parameter
};

struct InterpResult {
    std::vector<InterpSample> samples;  // t = 0, T, 2T, ...; the last at the curve's end (u_max)
    double length_mm = 0;
    double duration_s = 0;              // of the S-curve
    double v_peak = 0;                  // its cruise speed, mm/s
    // Worst |ds/dS - 1| over the periods whose mean commanded feed is at least
    // low_feed_fraction of v_peak (the main figure), over every period, and
    // over the periods inside the cruise phase (constant feed). The last,
    // shortened period that ends on the curve's end is not a period: it is
    // reported as end_gap_mm.
    double feed_fluctuation_max = 0;
    double feed_fluctuation_all_max = 0;
    double feed_fluctuation_cruise_max = 0;
    double chord_error_max_mm = 0;      // every chord between successive samples
    double lag_max_mm = 0;              // worst |s(u_k) - S(t_k)|: arc length behind (or ahead of) the S-curve
    double end_gap_mm = 0;              // arc length left between the last periodic sample and the end
    std::size_t periods = 0;
};

// Interpolates `curve` from rest to rest. The curve must have a length > 0.
InterpResult interpolate(const Nurbs& curve, const InterpLimits& limits, const InterpOptions& options);

}  // namespace cpstep::plan

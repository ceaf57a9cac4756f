// SPDX-License-Identifier: MIT
#include "plan/interp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cpstep::plan {

std::string_view method_name(InterpMethod m) {
    switch (m) {
        case InterpMethod::taylor1: return "taylor1";
        case InterpMethod::taylor2: return "taylor2";
        case InterpMethod::milne: return "milne";
    }
    return "?";
}

std::optional<InterpMethod> parse_method(std::string_view name) {
    for (InterpMethod m : {InterpMethod::taylor1, InterpMethod::taylor2, InterpMethod::milne})
        if (method_name(m) == name) return m;
    return std::nullopt;
}

InterpResult interpolate(const Nurbs& c, const InterpLimits& lim, const InterpOptions& opt) {
    InterpResult r;
    const double L = c.length();
    if (!(L > 0)) throw std::invalid_argument("interpolate: the curve has no length");
    if (!(opt.period_s > 0)) throw std::invalid_argument("interpolate: the period must be > 0");
    const auto prof = make_profile(L, 0, 0, lim.feed, lim.accel, lim.jerk);
    if (!prof) throw std::invalid_argument("interpolate: no S-curve for these limits");
    r.length_mm = L;
    r.duration_s = prof->duration;
    r.v_peak = prof->v_peak;
    const double T = opt.period_s;
    const double u_end = c.u_max();

    // du/dt = V(t) / |C'(u)|.
    auto f = [&](double t, double u) { return prof->at(t).v / c.eval(u).d1.norm(); };
    auto taylor2_h = [&](double t, double u, double h) {
        const KinState k = prof->at(t);
        const NurbsPoint e = c.eval(u);
        const double s = e.d1.norm();
        return u + k.v * h / s + h * h / 2 * (k.a / s - k.v * k.v * e.d1.dot(e.d2) / (s * s * s * s));
    };
    auto taylor2 = [&](double t, double u) { return taylor2_h(t, u, T); };
    // Milne's starter: taylor2 on sub-steps of the period, so that the
    // starting values are as accurate as the multistep method needs (see
    // docs/CURVES.md: Simpson's corrector keeps any odd/even mismatch of its
    // starting values for ever, as an alternating error).
    const int sub = std::max(1, opt.starter_substeps);
    auto starter = [&](double t, double u) {
        const double h = T / sub;
        for (int i = 0; i < sub; ++i) u = taylor2_h(t + i * h, u, h);
        return u;
    };
    // Times where the S-curve's jerk switches: f is not smooth across them,
    // so the multistep history must not straddle one (the method restarts).
    std::vector<double> kinks;
    for (std::size_t i = 1; i < prof->phases.size(); ++i) {
        if (prof->phases[i].jerk != prof->phases[i - 1].jerk) kinks.push_back(prof->phases[i].t0);
    }

    // Knots: C''' (so the second derivative of f) jumps there; the
    // multistep history must not straddle one either.
    std::vector<double> knots = c.breakpoints();
    knots.erase(knots.begin());
    knots.pop_back();
    auto knot_within = [&](double ua, double ub) {
        auto it = std::upper_bound(knots.begin(), knots.end(), ua);
        return it != knots.end() && *it < ub;
    };

    std::vector<double> us{c.u_min()};
    std::vector<double> fs{f(0, us[0])};
    for (std::size_t k = 0; static_cast<double>(k + 1) * T < prof->duration; ++k) {
        const double t = static_cast<double>(k) * T, t1 = static_cast<double>(k + 1) * T;
        const double u = us[k];
        double un = 0;
        if (opt.method == InterpMethod::taylor1) {
            const KinState ks = prof->at(t);
            un = u + ks.v * T / c.eval(u).d1.norm();
        } else if (opt.method == InterpMethod::taylor2) {
            un = taylor2(t, u);
        } else if (k < 3 || std::any_of(kinks.begin(), kinks.end(), [&](double tk) {
                       return tk > static_cast<double>(k - 3) * T && tk < t1;
                   })) {
            // The start, and a restart around every jerk switch: the starter
            // until the history u_{k-3} .. u_{k+1} lies within one phase.
            un = starter(t, u);
        } else {
            // Milne's predictor (eq. 23), then Simpson's corrector (eq. 24)
            // iterated with f evaluated at the newest estimate.
            un = us[k - 3] + 4 * T / 3 * (2 * fs[k] - fs[k - 1] + 2 * fs[k - 2]);
            const bool across_knot = knot_within(us[k - 3], std::max(un, u) + 1e-12 * std::max(1.0, std::abs(un)));
            for (int n = 0; n < opt.max_corrections && !across_knot; ++n) {
                const double next = us[k - 1] + T / 3 * (f(t1, un) + 4 * fs[k] + fs[k - 1]);
                const bool converged = std::abs(next - un) <= 1e-15 * std::max(1.0, std::abs(next));
                un = next;
                if (converged) break;
            }
            if (across_knot) un = starter(t, u);
        }
        if (un >= u_end) break;  // reached the end early: the end sample closes the curve
        us.push_back(un);
        fs.push_back(f(t1, un));
    }

    const std::size_t K = us.size() - 1;  // periods computed
    r.periods = K;
    const double t_cruise0 = prof->phases[3].t0;
    const double t_cruise1 = t_cruise0 + prof->phases[3].duration;
    double s = 0;
    for (std::size_t k = 0; k < K; ++k) {
        const double t = static_cast<double>(k) * T, t1 = static_cast<double>(k + 1) * T;
        const double ds = c.length(us[k], us[k + 1]);
        const double dS = prof->at(t1).s - prof->at(t).s;
        s += ds;
        r.lag_max_mm = std::max(r.lag_max_mm, std::abs(s - prof->at(t1).s));
        r.chord_error_max_mm = std::max(r.chord_error_max_mm, c.chord_error(us[k], us[k + 1]));
        if (!(dS > 0)) continue;
        const double fl = std::abs(ds / dS - 1);
        r.feed_fluctuation_all_max = std::max(r.feed_fluctuation_all_max, fl);
        if (dS / T >= opt.low_feed_fraction * prof->v_peak) r.feed_fluctuation_max = std::max(r.feed_fluctuation_max, fl);
        if (t >= t_cruise0 && t1 <= t_cruise1 && prof->phases[3].duration > 0)
            r.feed_fluctuation_cruise_max = std::max(r.feed_fluctuation_cruise_max, fl);
    }
    r.chord_error_max_mm = std::max(r.chord_error_max_mm, c.chord_error(us[K], u_end));
    r.end_gap_mm = c.length(us[K], u_end);
    r.samples.reserve(K + 2);
    for (std::size_t k = 0; k <= K; ++k) r.samples.push_back({static_cast<double>(k) * T, us[k]});
    r.samples.push_back({prof->duration, u_end});
    return r;
}

}  // namespace cpstep::plan

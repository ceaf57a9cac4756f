// SPDX-License-Identifier: MIT
#include "plan/profile.h"

#include <algorithm>
#include <cmath>

namespace cpstep::plan {

Ramp ramp(double va, double vb, double A, double J) {
    const double dv = std::abs(vb - va);
    Ramp r;
    if (dv <= 0) return r;
    if (dv >= A * A / J) {
        r.t_jerk = A / J;
        r.t_const = dv / A - A / J;
        r.a_peak = A;
    } else {
        r.t_jerk = std::sqrt(dv / J);
        r.a_peak = J * r.t_jerk;
    }
    r.duration = 2 * r.t_jerk + r.t_const;
    r.distance = (va + vb) / 2 * r.duration;
    return r;
}

double reachable_speed(double v_from, double L, double A, double J, double cap) {
    if (cap <= v_from) return cap;
    if (!(L > 0)) return v_from;
    if (ramp(v_from, cap, A, J).distance <= L) return cap;
    // Closed form of ramp(v_from, v_from + x).distance = L for x:
    // A not reached (x < A^2/J): (2 v0 + x) sqrt(x/J) = L, i.e. with y = sqrt(x)
    // the depressed cubic y^3 + 2 v0 y - L sqrt(J) = 0 (one real root);
    // A reached: (2 v0 + x)(x/A + A/J) = 2L, a quadratic in x.
    const double v0 = v_from;
    double x;
    const double p = 2 * v0, q = L * std::sqrt(J);
    double y;
    if (p == 0) {
        y = std::cbrt(q);
    } else {
        // y = 2 sqrt(p/3) sinh(asinh(3q/(2p) sqrt(3/p)) / 3), stable for every p > 0.
        const double k = std::sqrt(p / 3);
        y = 2 * k * std::sinh(std::asinh(q / (2 * k * k * k)) / 3);
    }
    x = y * y;
    if (x >= A * A / J) {
        // x^2/A + x (2 v0/A + A/J) + 2 v0 A/J - 2L = 0
        const double a2 = 1 / A, b2 = 2 * v0 / A + A / J, c2 = 2 * v0 * A / J - 2 * L;
        const double disc = std::max(0.0, b2 * b2 - 4 * a2 * c2);
        x = (2 * (-c2)) / (b2 + std::sqrt(disc));  // the positive root, no cancellation
    }
    double v = std::min(cap, v0 + std::max(0.0, x));
    // Rounding may put the distance a hair above L: step down until it fits.
    for (int i = 0; i < 60 && v > v0 && ramp(v0, v, A, J).distance > L; ++i) {
        v = v0 + (v - v0) * (1 - 1e-12 * (1 << std::min(i, 40)));
    }
    return std::max(v0, v);
}

namespace {

KinState advance(const Phase& p, double tau) {
    const double j = p.jerk;
    return {p.s0 + p.v0 * tau + p.a0 * tau * tau / 2 + j * tau * tau * tau / 6,
            p.v0 + p.a0 * tau + j * tau * tau / 2, p.a0 + j * tau, j};
}

}  // namespace

std::optional<Profile> make_profile(double L, double v0, double v1, double vmax, double A,
                                    double J) {
    const double vlo = std::max(v0, v1);
    auto dist = [&](double vp) {
        return ramp(v0, vp, A, J).distance + ramp(vp, v1, A, J).distance;
    };
    double vp = std::max(vmax, vlo);
    if (dist(vp) > L) {
        // Reduced peak: bisection keeps dist(lo) <= L, the rest is cruise.
        if (dist(vlo) > L * (1 + 1e-12) + 1e-15) return std::nullopt;
        double lo = vlo, hi = vp;
        for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
            const double mid = (lo + hi) / 2;
            (dist(mid) <= L ? lo : hi) = mid;
        }
        vp = lo;
    }
    // Standing still covers no length: a path from rest to rest with no speed
    // allowed (vmax = v0 = v1 = 0) cannot be joined (it would be a profile of
    // zero duration that claims to cover L).
    if (!(vp > 0)) {
        if (L > 0) return std::nullopt;
    }
    const Ramp up = ramp(v0, vp, A, J);
    const Ramp down = ramp(vp, v1, A, J);
    const double cruise = vp > 0 ? std::max(0.0, (L - up.distance - down.distance) / vp) : 0.0;

    Profile p;
    p.length = L;
    p.v_entry = v0;
    p.v_exit = v1;
    p.v_peak = vp;
    const double durations[7] = {up.t_jerk,   up.t_const,   up.t_jerk, cruise,
                                 down.t_jerk, down.t_const, down.t_jerk};
    const double jerks[7] = {J, 0, -J, 0, -J, 0, J};
    KinState st{0, v0, 0, 0};
    double t = 0;
    for (std::size_t k = 0; k < 7; ++k) {
        Phase& ph = p.phases[k];
        ph.duration = durations[k];
        ph.jerk = durations[k] > 0 ? jerks[k] : 0;
        ph.t0 = t;
        ph.s0 = st.s;
        ph.v0 = st.v;
        ph.a0 = (k == 3) ? 0.0 : st.a;  // the cruise starts at exactly zero acceleration
        st = advance(ph, ph.duration);
        t += ph.duration;
    }
    p.duration = t;
    return p;
}

Profile Profile::slice(double ta, double tb, double sa, double L) const {
    Profile out;
    out.length = L;
    std::size_t n = 0;
    for (const Phase& ph : phases) {
        if (!(ph.duration > 0)) continue;
        const double b = std::max(ph.t0, ta);
        const double e = std::min(ph.t0 + ph.duration, tb);
        if (!(e > b)) continue;
        const KinState st = advance(ph, b - ph.t0);
        Phase& q = out.phases[n++];
        q.duration = e - b;
        q.jerk = ph.jerk;
        q.t0 = b - ta;
        q.s0 = st.s - sa;
        q.v0 = st.v;
        q.a0 = st.a;
        if (n == out.phases.size()) break;
    }
    if (n > 0) {
        out.phases[0].t0 = 0;
        out.phases[0].s0 = 0;
    }
    out.duration = tb - ta;
    // The ends of this profile keep its exact speeds; inner cuts evaluate it.
    out.v_entry = ta <= 0 ? v_entry : at(ta).v;
    out.v_exit = tb >= duration ? v_exit : at(tb).v;
    out.v_peak = v_peak;
    return out;
}

KinState Profile::at(double t) const {
    t = std::clamp(t, 0.0, duration);
    std::size_t k = 0;
    for (std::size_t i = 0; i < phases.size(); ++i) {
        if (phases[i].duration > 0 && phases[i].t0 <= t) k = i;
    }
    return advance(phases[k], std::min(t - phases[k].t0, phases[k].duration));
}

double Profile::time_at(double s) const {
    if (s <= 0) return 0;
    if (s >= length) return duration;
    // The last phase whose start is at or before s.
    std::size_t k = 0;
    for (std::size_t i = 0; i < phases.size(); ++i) {
        if (phases[i].duration > 0 && phases[i].s0 <= s) k = i;
    }
    const Phase& ph = phases[k];
    // s(tau) is non-decreasing on the phase (v >= 0): safeguarded Newton in a bracket.
    double lo = 0, hi = ph.duration;
    double tau = (ph.v0 > 0) ? std::min(hi, (s - ph.s0) / ph.v0) : hi / 2;
    for (int i = 0; i < 100; ++i) {
        const KinState st = advance(ph, tau);
        const double f = st.s - s;
        if (f > 0) hi = tau; else lo = tau;
        if (f == 0 || hi - lo <= 1e-15 * std::max(1.0, ph.t0 + hi)) break;
        double next = st.v > 0 ? tau - f / st.v : (lo + hi) / 2;
        if (!(next > lo && next < hi)) next = (lo + hi) / 2;
        if (next == tau) break;
        tau = next;
    }
    return ph.t0 + tau;
}

}  // namespace cpstep::plan

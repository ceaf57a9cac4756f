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
    if (ramp(v_from, cap, A, J).distance <= L) return cap;
    double lo = v_from, hi = cap;
    for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
        const double mid = (lo + hi) / 2;
        (ramp(v_from, mid, A, J).distance <= L ? lo : hi) = mid;
    }
    return lo;
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

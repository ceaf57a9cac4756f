// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plan/profile.h"

using namespace cpstep::plan;

namespace {

// Seed 002's example limits.
constexpr double J = 2000, A = 500, F = 60;

// Every invariant of a profile, checked by dense sampling and at the phase
// boundaries.
void check_profile(const Profile& p, double L, double v0, double v1, double vmax, double a_max,
                   double j_max) {
    const double tol = 1e-9 * std::max({1.0, vmax, a_max});
    // Exact length and end speeds.
    const KinState end = p.at(p.duration);
    EXPECT_NEAR(end.s, L, 1e-9 * std::max(1.0, L));
    EXPECT_NEAR(end.v, v1, 1e-7 * std::max(1.0, vmax));
    EXPECT_NEAR(end.a, 0, 1e-6 * a_max);
    EXPECT_NEAR(p.at(0).v, v0, tol);
    EXPECT_EQ(p.at(0).s, 0);
    // Continuity of s, v and a across every phase boundary.
    for (std::size_t k = 0; k + 1 < p.phases.size(); ++k) {
        const Phase& a = p.phases[k];
        const Phase& b = p.phases[k + 1];
        const double t = a.duration;
        const double s = a.s0 + a.v0 * t + a.a0 * t * t / 2 + a.jerk * t * t * t / 6;
        const double v = a.v0 + a.a0 * t + a.jerk * t * t / 2;
        const double acc = a.a0 + a.jerk * t;
        EXPECT_NEAR(b.t0, a.t0 + t, 1e-12 * std::max(1.0, p.duration));
        EXPECT_NEAR(b.s0, s, 1e-9 * std::max(1.0, L));
        EXPECT_NEAR(b.v0, v, 1e-7 * std::max(1.0, vmax));
        EXPECT_NEAR(b.a0, acc, 1e-6 * a_max);
        EXPECT_LE(std::abs(a.jerk), j_max);
    }
    // Limits and monotone position over 2000 samples.
    double prev_s = -1;
    for (int i = 0; i <= 2000; ++i) {
        const KinState st = p.at(p.duration * i / 2000);
        EXPECT_LE(st.v, vmax + tol);
        EXPECT_GE(st.v, -tol);
        EXPECT_LE(std::abs(st.a), a_max * (1 + 1e-9));
        EXPECT_LE(std::abs(st.j), j_max);
        EXPECT_GE(st.s, prev_s - 1e-12);
        prev_s = st.s;
    }
    // time_at inverts the position.
    for (int i = 0; i <= 200; ++i) {
        const double s = L * i / 200;
        const double t = p.time_at(s);
        EXPECT_NEAR(p.at(t).s, s, 1e-9 * std::max(1.0, L)) << "s=" << s;
        if (i > 0) { EXPECT_GE(t, p.time_at(L * (i - 1) / 200)); }
    }
}

}  // namespace

TEST(Profile, RampClosedForm) {
    // 0 -> 60 with A^2/J = 125 > 60: A is not reached, peak sqrt(J dv).
    Ramp r = ramp(0, 60, A, J);
    EXPECT_NEAR(r.a_peak, std::sqrt(2000.0 * 60), 1e-9);
    EXPECT_NEAR(r.t_jerk, std::sqrt(60.0 / 2000), 1e-12);
    EXPECT_EQ(r.t_const, 0);
    EXPECT_NEAR(r.distance, 30 * 2 * std::sqrt(0.03), 1e-12);
    // 0 -> 400: A reached, t_j = A/J = 0.25, t_a = 400/500 - 0.25.
    Ramp r2 = ramp(400, 0, A, J);
    EXPECT_EQ(r2.a_peak, A);
    EXPECT_DOUBLE_EQ(r2.t_jerk, 0.25);
    EXPECT_DOUBLE_EQ(r2.t_const, 0.55);
    EXPECT_DOUBLE_EQ(r2.distance, 200 * 1.05);
}

TEST(Profile, LongMoveCruisesAtFeed) {
    auto p = make_profile(100, 0, 0, F, A, J);
    ASSERT_TRUE(p);
    EXPECT_EQ(p->v_peak, F);
    const double tr = 2 * std::sqrt(60.0 / 2000);  // one ramp
    const double dr = 30 * tr;
    EXPECT_NEAR(p->duration, 2 * tr + (100 - 2 * dr) / 60, 1e-12);
    EXPECT_NEAR(p->phases[3].duration, (100 - 2 * dr) / 60, 1e-12);
    check_profile(*p, 100, 0, 0, F, A, J);
}

TEST(Profile, ShortMoveHasNoCruise) {
    // Peak below A^2/J: D(vp) = 2 vp sqrt(vp / J) = L  =>  vp = (L sqrt(J) / 2)^(2/3).
    const double L = 5;
    auto p = make_profile(L, 0, 0, F, A, J);
    ASSERT_TRUE(p);
    EXPECT_NEAR(p->v_peak, std::pow(L * std::sqrt(J) / 2, 2.0 / 3), 1e-9);
    EXPECT_NEAR(p->phases[3].duration, 0, 1e-9);
    check_profile(*p, L, 0, 0, F, A, J);
}

TEST(Profile, AccelerationLimitReached) {
    // vmax 400 > A^2/J = 125: trapezoidal acceleration with the A plateau.
    auto p = make_profile(1000, 0, 0, 400, A, J);
    ASSERT_TRUE(p);
    EXPECT_DOUBLE_EQ(p->phases[1].duration, 0.55);
    EXPECT_DOUBLE_EQ(p->at(p->phases[1].t0).a, A);
    check_profile(*p, 1000, 0, 0, 400, A, J);
    // Short enough that the peak is reduced but A is still reached:
    // D(vp) = 2 * vp/2 * (vp/A + A/J) = vp^2/A + vp A/J = L.
    const double L = 100;
    auto q = make_profile(L, 0, 0, 400, A, J);
    ASSERT_TRUE(q);
    const double b = A / J;
    EXPECT_NEAR(q->v_peak, (-b + std::sqrt(b * b + 4 * L / A)) / 2 * A, 1e-8);
    check_profile(*q, L, 0, 0, 400, A, J);
}

TEST(Profile, NonZeroEntryAndExit) {
    auto p = make_profile(20, 20, 40, F, A, J);
    ASSERT_TRUE(p);
    check_profile(*p, 20, 20, 40, F, A, J);
    auto q = make_profile(10, 50, 10, F, A, J);
    ASSERT_TRUE(q);
    check_profile(*q, 10, 50, 10, F, A, J);
    // A pure deceleration that exactly fits: no cruise, no acceleration part.
    const double L = ramp(60, 0, A, J).distance;
    auto d = make_profile(L, 60, 0, F, A, J);
    ASSERT_TRUE(d);
    EXPECT_NEAR(d->duration, ramp(60, 0, A, J).duration, 1e-9);
    check_profile(*d, L, 60, 0, F, A, J);
}

TEST(Profile, InfeasibleEntryExitIsRefused) {
    EXPECT_FALSE(make_profile(1, 60, 0, F, A, J));
    EXPECT_FALSE(make_profile(ramp(0, 60, A, J).distance * 0.99, 0, 60, F, A, J));
    // No speed allowed, from rest to rest: nothing covers the length (a
    // profile of zero duration over 1 mm would claim infinite speed).
    EXPECT_FALSE(make_profile(1, 0, 0, 0, A, J));
    EXPECT_FALSE(make_profile(1e-9, 0, 0, 0, A, J));
    // A tiny allowed speed does cover it, at that speed.
    auto slow = make_profile(1, 0, 0, 1e-3, A, J);
    ASSERT_TRUE(slow);
    EXPECT_GE(slow->duration, 1 / 1e-3);
}

TEST(Profile, ReachableSpeedInvertsRampDistance) {
    for (double L : {0.01, 1.0, 10.0, 1000.0}) {
        const double v = reachable_speed(5, L, A, J, 1e9);
        EXPECT_NEAR(ramp(5, v, A, J).distance, L, 1e-9 * L);
    }
    EXPECT_EQ(reachable_speed(5, 1000, A, J, 60), 60);
}

TEST(Profile, RandomProfilesKeepEveryInvariant) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(0, 1);
    int built = 0;
    for (int k = 0; k < 300; ++k) {
        const double j = 100 + 20000 * U(rng);
        const double a = 10 + 2000 * U(rng);
        const double vmax = 1 + 200 * U(rng);
        const double L = std::pow(10, -3 + 5 * U(rng));
        const double v0 = vmax * U(rng), v1 = vmax * U(rng);
        auto p = make_profile(L, v0, v1, vmax, a, j);
        // Feasible exactly when the direct ramp fits.
        ASSERT_EQ(p.has_value(), ramp(v0, v1, a, j).distance <= L * (1 + 1e-12)) << k;
        if (!p) continue;
        ++built;
        check_profile(*p, L, v0, v1, vmax, a, j);
    }
    EXPECT_GT(built, 50);
}

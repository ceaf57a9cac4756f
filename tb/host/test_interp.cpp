// SPDX-License-Identifier: MIT
// Fixed-period NURBS interpolation (plan/interp.h): the samples' timing, the
// orders of convergence the three parameter updates must show (Taylor-1: the
// per-period feed error halves when T halves; Taylor-2: quarters; Milne-
// Simpson: far below both), and the airfoil job of seed 002.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "plan/gcode.h"
#include "plan/interp.h"
#include "plan/nurbs.h"
#include "plan/profile.h"

using namespace cpstep::plan;
using Eigen::Vector3d;

namespace {

const std::string kDir = CPSTEP_EXAMPLES_DIR;
const InterpLimits kSeed{60, 500, 2000};  // seed 002: fmax, Amax, Jmax

Nurbs quarter_circle(double r) {
    const double s = std::sqrt(0.5);
    return Nurbs(3, {Vector3d(r, 0, 0), Vector3d(r, r, 0), Vector3d(0, r, 0)}, {1, s, 1}, {0, 0, 0, 1, 1, 1});
}

InterpResult run(const Nurbs& c, InterpMethod m, double T, const InterpLimits& lim = kSeed) {
    InterpOptions o;
    o.method = m;
    o.period_s = T;
    return interpolate(c, lim, o);
}

}  // namespace

TEST(Interp, SamplesEveryPeriodFromStartToEnd) {
    // A long quarter circle (r = 50: 78.5 mm) so that the feed reaches its cruise.
    const Nurbs c = quarter_circle(50);
    const auto prof = make_profile(c.length(), 0, 0, 60, 500, 2000);
    ASSERT_TRUE(prof);
    for (InterpMethod m : {InterpMethod::taylor1, InterpMethod::taylor2, InterpMethod::milne}) {
        const InterpResult r = run(c, m, 1e-3);
        ASSERT_GE(r.samples.size(), 3u);
        EXPECT_DOUBLE_EQ(r.duration_s, prof->duration);
        EXPECT_EQ(r.samples.front().u, c.u_min());
        EXPECT_EQ(r.samples.back().u, c.u_max());
        EXPECT_EQ(r.samples.back().t, prof->duration);
        for (std::size_t k = 0; k + 1 < r.samples.size(); ++k) {
            EXPECT_DOUBLE_EQ(r.samples[k].t, static_cast<double>(k) * 1e-3);
            EXPECT_LE(r.samples[k].u, r.samples[k + 1].u);
        }
        // One sample per whole period of the S-curve. Milne-Simpson keeps to
        // the S-curve to well under a period's advance, so none is lost; the
        // Taylor updates run ahead by up to their lag and may reach the end a
        // few periods early (the last periods are slow).
        const auto whole = static_cast<std::size_t>(std::ceil(prof->duration / 1e-3)) - 1;
        if (m == InterpMethod::milne) {
            EXPECT_EQ(r.periods, whole);
        } else {
            EXPECT_LE(r.periods, whole);
            EXPECT_GE(r.periods + 5, whole) << method_name(m);
        }
        // The chords of 60 mm/s x 1 ms on r = 50 stand off by (0.06)^2 / (8 r).
        EXPECT_LE(r.chord_error_max_mm, 0.06 * 0.06 / (8 * 50) * 1.01);
    }
}

TEST(Interp, OrdersOfConvergenceAtConstantFeed) {
    // In the cruise phase V is constant: the per-period error of the arc
    // length is O(T^2) for Taylor-1 and O(T^3) for Taylor-2, i.e. relative to
    // V T of order T and T^2: halving T halves and quarters the figure.
    const Nurbs c = quarter_circle(50);
    const double t1a = run(c, InterpMethod::taylor1, 1e-3).feed_fluctuation_cruise_max;
    const double t1b = run(c, InterpMethod::taylor1, 0.5e-3).feed_fluctuation_cruise_max;
    const double t2a = run(c, InterpMethod::taylor2, 1e-3).feed_fluctuation_cruise_max;
    const double t2b = run(c, InterpMethod::taylor2, 0.5e-3).feed_fluctuation_cruise_max;
    const double ma = run(c, InterpMethod::milne, 1e-3).feed_fluctuation_cruise_max;
    EXPECT_GT(t1a, 0);
    EXPECT_GT(t2a, 0);
    EXPECT_NEAR(t1a / t1b, 2.0, 0.4);
    EXPECT_NEAR(t2a / t2b, 4.0, 0.8);
    // Milne-Simpson (local error O(T^5)) far below Taylor-2 at the same T.
    EXPECT_LT(ma, t2a / 100);
}

TEST(Interp, AirfoilJob) {
    auto job = load_gcode(kDir + "/jobs/naca0025.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    const MotionBlock* b = nullptr;
    for (const auto& blk : job->blocks)
        if (blk.kind == MotionKind::nurbs) b = &blk;
    ASSERT_NE(b, nullptr);
    const Nurbs& c = *b->curve;
    // A closed contour: it ends where it starts.
    EXPECT_LT((c.points().front() - c.points().back()).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(b->feed, 60.0);
    const InterpResult t1 = run(c, InterpMethod::taylor1, 1e-3);
    const InterpResult t2 = run(c, InterpMethod::taylor2, 1e-3);
    const InterpResult ms = run(c, InterpMethod::milne, 1e-3);
    // Seed 002's cycle: 1,650 ms at 3600 mm/min peak (the chord was chosen so).
    EXPECT_NEAR(ms.duration_s, 1.650, 1e-6);
    EXPECT_DOUBLE_EQ(ms.v_peak, 60.0);
    // Higher order, smaller feed error and lag behind the S-curve.
    EXPECT_LT(ms.feed_fluctuation_max, t2.feed_fluctuation_max);
    EXPECT_LT(t2.feed_fluctuation_max, t1.feed_fluctuation_max);
    EXPECT_LT(ms.lag_max_mm, t2.lag_max_mm);
    EXPECT_LT(t2.lag_max_mm, t1.lag_max_mm);
    // Chord error: at most the sagitta of a period's path (<= 60 mm/s x T) on
    // the tightest radius of the curve (its leading edge).
    double r_min = HUGE_VAL;
    for (int i = 0; i <= 20000; ++i) r_min = std::min(r_min, c.radius(c.u_min() + (c.u_max() - c.u_min()) * i / 20000));
    // NACA 4-digit leading-edge radius 1.1019 t^2 c (t = 0.25, c = 36.73 mm): about 2.53 mm.
    EXPECT_NEAR(r_min, 1.1019 * 0.0625 * 36.7295, 0.1);
    for (const InterpResult* r : {&t1, &t2, &ms}) {
        EXPECT_LE(r->chord_error_max_mm, 0.06 * 0.06 / (8 * r_min) * 1.05);
    }
}

TEST(Interp, RefusesDegenerateInput) {
    const Nurbs c = quarter_circle(1);
    InterpOptions o;
    o.period_s = 0;
    EXPECT_THROW(interpolate(c, kSeed, o), std::invalid_argument);
    EXPECT_EQ(parse_method("milne"), InterpMethod::milne);
    EXPECT_EQ(parse_method("taylor3"), std::nullopt);
}

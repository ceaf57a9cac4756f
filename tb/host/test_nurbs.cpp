// SPDX-License-Identifier: MIT
// NURBS curves (plan/nurbs.h) and their G-code forms G5, G5.1, G5.2 ... G5.3
// (plan/gcode.h), against independent evaluations: circles that rational
// quadratics represent exactly, the Cox-de Boor basis recursion written here
// on its own, finite differences and the Bezier closed forms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/nurbs.h"
#include "plan/segments.h"

using namespace cpstep::plan;
using Eigen::Vector3d;

namespace {

const double kS = std::sqrt(0.5);  // cos 45 degrees: the weight of a quarter circle's middle point

Nurbs quarter_circle(double r) {
    return Nurbs(3, {Vector3d(r, 0, 0), Vector3d(r, r, 0), Vector3d(0, r, 0)}, {1, kS, 1}, {0, 0, 0, 1, 1, 1});
}

// A full circle of radius r about (cx, cy): four quarter arcs, the knots
// doubled between them (C1 there, as the circle needs).
Nurbs full_circle(double r, double cx, double cy) {
    std::vector<Vector3d> p;
    const double xs[] = {1, 1, 0, -1, -1, -1, 0, 1, 1};
    const double ys[] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
    for (int i = 0; i < 9; ++i) p.emplace_back(cx + r * xs[i], cy + r * ys[i], 2.0);
    std::vector<double> w{1, kS, 1, kS, 1, kS, 1, kS, 1};
    return Nurbs(3, p, w, {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1});
}

// The B-spline basis N_{i,p}(u) by the Cox-de Boor recursion (the half-open
// convention; at the very end of the domain the last basis function is 1).
double basis(const std::vector<double>& t, std::size_t i, int p, double u) {
    if (p == 0) {
        const bool last = u == t.back() && t[i] < t[i + 1] && t[i + 1] == t.back();
        return (t[i] <= u && u < t[i + 1]) || last ? 1.0 : 0.0;
    }
    double v = 0;
    const auto P = static_cast<std::size_t>(p);
    if (t[i + P] > t[i]) v += (u - t[i]) / (t[i + P] - t[i]) * basis(t, i, p - 1, u);
    if (t[i + P + 1] > t[i + 1]) v += (t[i + P + 1] - u) / (t[i + P + 1] - t[i + 1]) * basis(t, i + 1, p - 1, u);
    return v;
}

Vector3d by_basis(const Nurbs& c, double u) {
    Vector3d num = Vector3d::Zero();
    double den = 0;
    for (std::size_t i = 0; i < c.points().size(); ++i) {
        const double b = basis(c.knots(), i, c.degree(), u) * c.weights()[i];
        num += b * c.points()[i];
        den += b;
    }
    return num / den;
}

Nurbs wavy() {
    // Order 4, non-uniform knots, uneven weights, a 3-D control polygon.
    return Nurbs(4,
                 {Vector3d(0, 0, 0), Vector3d(3, 5, 1), Vector3d(7, -2, 0.5), Vector3d(11, 4, -1), Vector3d(14, 9, 0),
                  Vector3d(18, 1, 2), Vector3d(21, 3, 0)},
                 {1, 0.6, 2.5, 1.3, 0.8, 1.7, 1}, {0, 0, 0, 0, 0.7, 1.1, 2.5, 4, 4, 4, 4});
}

}  // namespace

TEST(Nurbs, QuarterAndFullCirclesStayOnTheirRadius) {
    const Nurbs q = quarter_circle(7.5);
    for (int i = 0; i <= 200; ++i) {
        const double u = i / 200.0;
        EXPECT_NEAR(q.point(u).norm(), 7.5, 1e-12) << u;
        EXPECT_NEAR(q.radius(u), 7.5, 1e-9) << u;  // curvature from C' and C''
    }
    const Nurbs f = full_circle(3, 40, 50);
    for (int i = 0; i <= 400; ++i) {
        const double u = i / 400.0;
        const Vector3d p = f.point(u);
        EXPECT_NEAR(std::hypot(p[0] - 40, p[1] - 50), 3, 1e-12) << u;
        EXPECT_DOUBLE_EQ(p[2], 2.0);
        EXPECT_NEAR(f.radius(u), 3, 1e-9) << u;
    }
    EXPECT_NEAR(q.length(), std::numbers::pi * 7.5 / 2, 1e-12);
    EXPECT_NEAR(f.length(), 2 * std::numbers::pi * 3, 1e-11);
    // The chord of the whole quarter stands off by the sagitta r (1 - cos 45).
    EXPECT_NEAR(q.chord_error(0, 1), 7.5 * (1 - kS), 1e-10);
}

TEST(Nurbs, DeBoorMatchesTheBasisSum) {
    const Nurbs c = wavy();
    for (int i = 0; i <= 400; ++i) {
        const double u = 4.0 * i / 400;
        EXPECT_LT((c.point(u) - by_basis(c, u)).norm(), 1e-12) << u;
    }
    EXPECT_LT((c.point(0) - c.points().front()).norm(), 1e-15);
    EXPECT_LT((c.point(4) - c.points().back()).norm(), 1e-12);
}

TEST(Nurbs, DerivativesMatchFiniteDifferences) {
    const Nurbs c = wavy();
    const double h = 1e-5;
    for (int i = 0; i < 200; ++i) {
        // Midway between grid points: never within h of a knot (0.7, 1.1, 2.5),
        // where C''' jumps and the differences lose an order.
        const double u = 4.0 * (i + 0.5) / 200;
        const NurbsPoint e = c.eval(u);
        const Vector3d d1 = (c.point(u + h) - c.point(u - h)) / (2 * h);
        const Vector3d d2 = (c.eval(u + h).d1 - c.eval(u - h).d1) / (2 * h);
        EXPECT_LT((e.d1 - d1).norm(), 1e-6 * std::max(1.0, e.d1.norm())) << u;
        EXPECT_LT((e.d2 - d2).norm(), 1e-5 * std::max(1.0, e.d2.norm())) << u;
    }
}

TEST(Nurbs, LinuxCncUniformKnots) {
    // knot_vector_creator(n = points - 1, k = order): k zeros, i - k + 1 for
    // i = k..n, then n - k + 2.
    EXPECT_EQ(Nurbs::uniform_clamped_knots(5, 3), (std::vector<double>{0, 0, 0, 1, 2, 3, 3, 3}));
    EXPECT_EQ(Nurbs::uniform_clamped_knots(4, 4), (std::vector<double>{0, 0, 0, 0, 1, 1, 1, 1}));
    EXPECT_EQ(Nurbs::uniform_clamped_knots(6, 4), (std::vector<double>{0, 0, 0, 0, 1, 2, 3, 3, 3, 3}));
}

TEST(Nurbs, RefusesBadInput) {
    auto msg = [](int order, std::size_t n, std::vector<double> w, std::vector<double> k) {
        auto e = Nurbs::validate(order, n, w, k);
        return e ? *e : std::string();
    };
    EXPECT_EQ(msg(1, 3, {1, 1, 1}, {0, 1, 2, 3}), "NURBS order 1 is outside 2..16");
    EXPECT_EQ(msg(4, 3, {1, 1, 1}, {0, 0, 0, 0, 1, 1, 1}),
              "a NURBS of order 4 needs at least 4 control points, got 3");
    EXPECT_EQ(msg(3, 3, {1, 0, 1}, {0, 0, 0, 1, 1, 1}), "weight 0 of control point 2 must be > 0");
    EXPECT_EQ(msg(3, 3, {1, -2, 1}, {0, 0, 0, 1, 1, 1}), "weight -2 of control point 2 must be > 0");
    EXPECT_EQ(msg(3, 3, {1, 1, 1}, {0, 0, 0, 1, 1}),
              "a NURBS of order 3 with 3 control points needs 6 knots, got 5");
    EXPECT_EQ(msg(3, 4, {1, 1, 1, 1}, {0, 0, 0, 2, 1, 1, 1}),
              "knots must not decrease: knot 5 (1) is below knot 4 (2)");
    EXPECT_NE(msg(3, 4, {1, 1, 1, 1}, {0, 0, 0.1, 0.5, 1, 1, 1}).find("the first 3 knots must be equal"),
              std::string::npos);
    EXPECT_NE(msg(3, 4, {1, 1, 1, 1}, {0, 0, 0, 0.5, 1, 1, 2}).find("the last 3 knots must be equal"),
              std::string::npos);
    EXPECT_NE(msg(3, 6, {1, 1, 1, 1, 1, 1}, {0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1}).find("repeated 3 times"),
              std::string::npos);
    EXPECT_THROW(Nurbs(3, {Vector3d::Zero(), Vector3d::Ones(), Vector3d::Zero()}, {1, 1, 1}, {0, 0, 0, 1, 1}),
                 std::invalid_argument);
    EXPECT_FALSE(Nurbs::validate(3, 5, {1, 1, 1, 1, 1}, Nurbs::uniform_clamped_knots(5, 3)));
}

namespace {

// xorshift64 to [0, 1): the random curves' numbers.
struct Unit {
    uint64_t s = 0x9e3779b97f4a7c15ULL;
    double operator()() {
        s ^= s << 13; s ^= s >> 7; s ^= s << 17;
        return static_cast<double>(s >> 11) / 9007199254740992.0;
    }
};

// Orders 2..6, weights 0.2..5, uneven knots, points up to 10^3 mm.
Nurbs random_curve(Unit& rnd) {
    const int order = 2 + static_cast<int>(rnd() * 5);
    const std::size_t n = static_cast<std::size_t>(order) + static_cast<std::size_t>(rnd() * 8);
    const double scale = std::pow(10.0, 3 * rnd());
    std::vector<Vector3d> p;
    std::vector<double> w;
    for (std::size_t i = 0; i < n; ++i) {
        p.emplace_back(scale * (rnd() - 0.5), scale * (rnd() - 0.5), 0);
        w.push_back(0.2 + 4.8 * rnd() * rnd());
    }
    std::vector<double> k(static_cast<std::size_t>(order), 0.0);
    double u = 0;
    for (std::size_t i = 0; i + static_cast<std::size_t>(order) < n; ++i) k.push_back(u += 0.05 + rnd());
    k.insert(k.end(), static_cast<std::size_t>(order), u + 0.05 + rnd());
    return Nurbs(order, p, w, k);
}

}  // namespace

TEST(Nurbs, PointIsEvalsPointExactly) {
    // point() is the cheap form chord sampling calls: the same number as
    // eval().c, to the bit, inside the domain, at its knots and beyond its ends.
    Unit rnd;
    for (int t = 0; t < 200; ++t) {
        const Nurbs c = random_curve(rnd);
        std::vector<double> us = c.breakpoints();
        const double lo = c.u_min(), hi = c.u_max(), pad = 0.1 * (hi - lo);
        for (int i = 0; i < 40; ++i) us.push_back(lo - pad + (hi - lo + 2 * pad) * rnd());
        for (const double u : us) {
            const Vector3d a = c.point(u), b = c.eval(u).c;
            for (int j = 0; j < 3; ++j) ASSERT_EQ(a[j], b[j]) << "curve " << t << " at u = " << u << ", axis " << j;
        }
    }
}

TEST(Nurbs, ChordParametersRefuseACurveTooLargeForDoublePrecision) {
    // A straight line 200 mm long at x = 10^20 mm: its points' x carries
    // rounding of up to 2^14 mm (the spacing of doubles there), so no chord,
    // however short, fits 0.001 mm. It is refused once a piece halved
    // kMaxDepth times still stands off, whatever the cap: not sampled into
    // chords that break the tolerance, nor halved towards the cap for ever.
    const Nurbs far(3, {Vector3d(1e20, 0, 0), Vector3d(1e20, 100, 0), Vector3d(1e20, 200, 0)}, {1, 3, 1},
                    {0, 0, 0, 1, 1, 1});
    // (The estimate sees only the rounding's curvature: far below a cap it refuses.)
    EXPECT_LT(far.chord_estimate(0.001), 1000);
    EXPECT_TRUE(far.chord_parameters(0.001, std::size_t{1} << 50).empty());
    // The same line near the origin samples as one chord a half span.
    const Nurbs near(3, {Vector3d(1, 0, 0), Vector3d(1, 100, 0), Vector3d(1, 200, 0)}, {1, 3, 1},
                     {0, 0, 0, 1, 1, 1});
    EXPECT_EQ(near.chord_parameters(0.001, std::size_t{1} << 50).size(), 3u);
}

TEST(Nurbs, ChordParametersKeepTheTolerance) {
    const Nurbs f = full_circle(10, 0, 0);
    const double tol = 0.002;
    const auto us = f.chord_parameters(tol);
    ASSERT_GE(us.size(), 2u);
    EXPECT_EQ(us.front(), 0.0);
    EXPECT_EQ(us.back(), 1.0);
    for (std::size_t i = 0; i + 1 < us.size(); ++i) {
        EXPECT_LT(us[i], us[i + 1]);
        EXPECT_LE(f.chord_error(us[i], us[i + 1]), tol);
    }
    // Equal chords of a circle with sagitta tol: 2 pi / (2 acos(1 - tol / r));
    // halving gives at most twice as many.
    const double need = 2 * std::numbers::pi / (2 * std::acos(1 - tol / 10));
    EXPECT_GE(static_cast<double>(us.size() - 1), need);
    EXPECT_LE(static_cast<double>(us.size() - 1), 2 * need + 8);
}

TEST(Nurbs, ChordEstimateIsTheCircleCountAndNeverAboveAFactorOfTheChords) {
    // A circle: the estimate is the equal-chord count 2 pi / (2 acos(1 - tol / r)) ~ 2 pi sqrt(r / (8 tol)).
    for (const double r : {1.0, 10.0, 250.0}) {
        for (const double tol : {0.1, 0.01, 0.0005}) {
            const double need = 2 * std::numbers::pi / (2 * std::acos(1 - tol / r));
            EXPECT_NEAR(full_circle(r, 3, -4).chord_estimate(tol), need, 0.02 * need + 8) << r << " mm at " << tol;
        }
    }
    // Random curves: the chords chord_parameters makes are never fewer than the
    // estimate over kEstimateMargin, so refusing by the estimate refuses nothing
    // sampling would take.
    Unit rnd;
    double worst = 0;
    for (int t = 0; t < 300; ++t) {
        const Nurbs c = random_curve(rnd);
        const double tol = std::pow(10.0, -1 - 3 * rnd());
        const auto us = c.chord_parameters(tol, 100'000'000);
        ASSERT_FALSE(us.empty());
        const double ratio = c.chord_estimate(tol) / static_cast<double>(us.size() - 1);
        worst = std::max(worst, ratio);
        EXPECT_LE(ratio, Nurbs::kEstimateMargin) << "curve " << t << ": estimate " << c.chord_estimate(tol)
                                                 << ", chords " << us.size() - 1;
    }
    EXPECT_LT(worst, 1.5);  // (so the margin is wide)
    // Past the margin the curve is refused from the estimate, before sampling;
    // just under it, sampling decides.
    const Nurbs big = full_circle(1000, 0, 0);
    const double est = big.chord_estimate(0.001);
    const auto cap = static_cast<std::size_t>(est / Nurbs::kEstimateMargin) - 1;
    EXPECT_GT(big.chord_estimate(0.001, Nurbs::kEstimateMargin * static_cast<double>(cap)),
              Nurbs::kEstimateMargin * static_cast<double>(cap));
    EXPECT_TRUE(big.chord_parameters(0.001, cap).empty());
    const auto all = big.chord_parameters(0.001);
    EXPECT_EQ(big.chord_parameters(0.001, all.size()), all);
}

// ---- G-code ----

namespace {

Result<Job> parse(const std::string& text) { return parse_gcode(text, "f.ngc"); }

const MotionBlock& only_curve(const Result<Job>& r) {
    static MotionBlock none;
    for (const auto& b : r->blocks)
        if (b.kind == MotionKind::nurbs) return b;
    ADD_FAILURE() << "no nurbs block";
    return none;
}

}  // namespace

TEST(GcodeNurbs, G52QuarterCircleIsExact) {
    auto r = parse("G21 G90 G17\nG0 X10 Y0 Z1\nF600\nG5.2 X10 Y10 P0.7071067811865476 L3\nX0 Y10 P1\nG5.3\nG1 X0 Y20\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    ASSERT_EQ(r->blocks.size(), 3u);
    const MotionBlock& b = r->blocks[1];
    ASSERT_EQ(b.kind, MotionKind::nurbs);
    EXPECT_EQ(b.loc, (SourceLoc{4, 1}));
    EXPECT_DOUBLE_EQ(b.feed, 10.0);
    EXPECT_EQ(b.start[0], 10);
    EXPECT_EQ(b.end[0], 0);
    EXPECT_EQ(b.end[1], 10);
    EXPECT_EQ(b.end[2], 1);
    ASSERT_TRUE(b.curve);
    EXPECT_EQ(b.curve->order(), 3);
    EXPECT_EQ(b.curve->knots(), (std::vector<double>{0, 0, 0, 1, 1, 1}));
    for (int i = 0; i <= 50; ++i) {
        const Vector3d p = b.curve->point(i / 50.0);
        EXPECT_NEAR(std::hypot(p[0], p[1]), 10, 1e-12);
        EXPECT_EQ(p[2], 1);
    }
    // The G1 after it starts where the curve ended.
    EXPECT_EQ(r->blocks[2].start[0], 0);
    EXPECT_EQ(r->blocks[2].start[1], 10);
}

TEST(GcodeNurbs, FirstWeightOnTheG52LineAndOffsets) {
    // G5.2 with P alone weights the first point (the start); G92 offsets and
    // G20 scale the control points as they scale the curve.
    auto r = parse("G20 G90\nG0 X1 Y0\nG92 X0\nF10\nG5.2 P2 L3\nX0 Y1 P1\nX-1 Y1 P3\nG5.3\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    const MotionBlock& b = only_curve(r);
    ASSERT_TRUE(b.curve);
    EXPECT_EQ(b.curve->weights(), (std::vector<double>{2, 1, 3}));
    EXPECT_NEAR(b.curve->points()[1][0], 25.4, 1e-12);  // X0 after G92 X0 at machine X 25.4
    EXPECT_NEAR(b.curve->points()[2][0], 0.0, 1e-12);
    EXPECT_NEAR(b.curve->points()[2][1], 25.4, 1e-12);
    EXPECT_NEAR(b.feed, 10 * 25.4 / 60, 1e-12);
}

TEST(GcodeNurbs, ExplicitKnots) {
    auto r = parse(
        "G21 G90\nG0 X0 Y0\nF600\nG5.2 X1 Y2 P1 L3 K0\nK0\nX3 Y2 P2 K0\nX4 Y0 P1 K0.25\nK1\nK1\nK1\nG5.3\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    const MotionBlock& b = only_curve(r);
    ASSERT_TRUE(b.curve);
    EXPECT_EQ(b.curve->knots(), (std::vector<double>{0, 0, 0, 0.25, 1, 1, 1}));
    EXPECT_EQ(b.curve->points().size(), 4u);
    EXPECT_LT((b.curve->point(1) - Vector3d(4, 0, 0)).norm(), 1e-12);
    // Against the basis sum at an interior knot-span point.
    EXPECT_LT((b.curve->point(0.6) - by_basis(*b.curve, 0.6)).norm(), 1e-12);
}

TEST(GcodeNurbs, G5AndG51AreTheBezierClosedForms) {
    auto r = parse("G21 G90\nG0 X10 Y10\nF1200\nG5 I2 J6 P-3 Q4 X20 Y12\nG5 P1 Q-2 X25 Y5\nG5.1 I4 J-3 X30 Y9\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    ASSERT_EQ(r->blocks.size(), 4u);
    auto cubic = [](Vector3d p0, Vector3d p1, Vector3d p2, Vector3d p3, double t) {
        const double s = 1 - t;
        return Vector3d(s * s * s * p0 + 3 * s * s * t * p1 + 3 * s * t * t * p2 + t * t * t * p3);
    };
    const Vector3d a0(10, 10, 0), a1(12, 16, 0), a3(20, 12, 0), a2(17, 16, 0);
    // The second G5 continues the first: its I J are the first's -P -Q.
    const Vector3d b0 = a3, b1 = a3 + Vector3d(3, -4, 0), b3(25, 5, 0), b2 = b3 + Vector3d(1, -2, 0);
    const Vector3d c0 = b3, c1 = b3 + Vector3d(4, -3, 0), c2(30, 9, 0);
    for (int i = 0; i <= 40; ++i) {
        const double t = i / 40.0, s = 1 - t;
        EXPECT_LT((r->blocks[1].curve->point(t) - cubic(a0, a1, a2, a3, t)).norm(), 1e-12) << t;
        EXPECT_LT((r->blocks[2].curve->point(t) - cubic(b0, b1, b2, b3, t)).norm(), 1e-12) << t;
        const Vector3d q = s * s * c0 + 2 * s * t * c1 + t * t * c2;
        EXPECT_LT((r->blocks[3].curve->point(t) - q).norm(), 1e-12) << t;
    }
    // Tangent continuity where the second G5 continues the first.
    const Vector3d ta = r->blocks[1].curve->eval(1).d1.normalized(), tb = r->blocks[2].curve->eval(0).d1.normalized();
    EXPECT_LT((ta - tb).norm(), 1e-12);
}

TEST(GcodeNurbs, ErrorsNameLineAndColumn) {
    auto errs = [](const std::string& text) { return join(parse_gcode(text, "f.ngc").errors); };
    const std::string head = "G21 G90\nG0 X1 Y1\nF600\n";
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1 L2\nX3 Y1 P1\nG5.3\n"),
              "f.ngc:4:15: G5.2 L (the order) must be a whole number from 3 to 16 (LinuxCNC reads L below 3 as 3)");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1\nX3 Y1 P0\nX4 Y1 P1\nG5.3\n"), "f.ngc:5:7: NURBS weight P must be > 0");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1\nX3 Y1\nX4 Y1 P1\nG5.3\n"),
              "f.ngc:5:1: G5.2 control point without a weight: give P > 0");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1\nX3 P1\nG5.3\n"), "f.ngc:5:1: G5.2 control points need both X and Y");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1 L4\nX3 Y1 P1\nG5.3\n"),
              "f.ngc:6:1: a NURBS of order 4 needs at least 4 control points (the start counts as the first); got 3 "
              "(G5.2 on line 4)");
    EXPECT_EQ(errs(head + "G5.3\n"), "f.ngc:4:1: G5.3 without an open G5.2 NURBS");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1\nX3 Y1 P1\nG1 X5\n"),
              "f.ngc:6:1: G1 inside a G5.2 NURBS (line 4): end it with G5.3 first");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1\nX3 Y1 P1\n"), "f.ngc:4:1: G5.2 NURBS not ended by G5.3");
    // Explicit knots: a decreasing K at its column, a wrong count at G5.3, an
    // unclamped vector at the first K.
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1 K0\nK0\nK0\nK0.5\nK0.4\nX3 Y1 P1\nG5.3\n"),
              "f.ngc:8:1: knots must not decrease: K0.4 after K0.5");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1 K0\nK0\nK0\nX3 Y1 P1 K1\nK1\nG5.3\n"),
              "f.ngc:9:1: a NURBS of order 3 with 3 control points (the start counts as the first) needs 6 knots, "
              "got 5 K words");
    EXPECT_EQ(errs(head + "G5.2 X2 Y2 P1 K0\nK0\nK0.5\nX3 Y1 P1 K1\nK1\nK1\nG5.3\n"),
              "f.ngc:4:15: knots must be clamped: the first 3 knots must be equal (the curve starts at the first "
              "control point)");
    EXPECT_EQ(errs(head + "G5.1 I1 X3 Y3\n"), "f.ngc:4:1: G5.1 needs both I and J (the control point, relative to the start)");
    EXPECT_EQ(errs(head + "G5 I1 J1 P1 X3 Y3\n"), "f.ngc:4:1: G5 needs both P and Q (the second control point, relative to the end)");
    EXPECT_EQ(errs(head + "G5 P1 Q1 X3 Y3\n"), "f.ngc:4:1: G5 without I and J continues a previous G5: give I and J on the first");
    EXPECT_EQ(errs(head + "G18 G5 I1 J1 P1 Q1 X3 Y3\n"), "f.ngc:4:5: G5: splines are supported in the XY plane (G17) only");
    EXPECT_EQ(errs(head + "G5 I1 J1 P1 Q1 X3 Y3 Z2\n"), "f.ngc:4:22: G5: splines move X and Y only");
    EXPECT_EQ(errs(head + "G91 G5.2 X2 Y2 P1\nX3 Y1 P1\nG5.3\n"),
              "f.ngc:4:5: G5.2 control points need absolute distance mode (G90)");
}

TEST(GcodeNurbs, SegmentsCarryTheTrueRadius) {
    // A G5.2 half circle of radius 20 (two quarter arcs: explicit knots, the
    // middle one doubled) becomes chords within the arc tolerance whose radius
    // is the curve's, not the chords' fit.
    auto r = parse("G21 G90\nG0 X120 Y100\nF1800\nG5.2 X120 Y120 P0.7071067811865476 L3 K0\nX100 Y120 P1 K0\n"
                   "X80 Y120 P0.7071067811865476 K0\nX80 Y100 P1 K1\nK1\nK2\nK2\nK2\nG5.3\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    Machine m;
    for (std::size_t a = 0; a < 2; ++a) {
        auto& ax = m.axes[a];
        ax.present = true;
        ax.steps_per_mm = 80;
        ax.travel_min_mm = 0;
        ax.travel_max_mm = 300;
        ax.max_velocity = 60;
        ax.max_accel = 500;
        ax.max_jerk = 2000;
    }
    m.planner.arc_tolerance_mm = 0.002;
    auto segs = make_step_segments(*r, m);
    ASSERT_TRUE(segs.ok()) << join(segs.errors);
    std::vector<const StepSegment*> curve;
    for (const StepSegment& s : *segs.value)
        if (s.kind == MotionKind::nurbs) curve.push_back(&s);
    ASSERT_GE(curve.size(), 3u);
    const std::size_t curve_segs = curve.size();
    for (std::size_t i = 0; i < curve.size(); ++i) {
        const StepSegment& s = *curve[i];
        // Every chord end on the circle (centre (100, 100), r = 20) ...
        EXPECT_NEAR(std::hypot(s.to_mm[0] - 100, s.to_mm[1] - 100), 20, 1e-9);
        // ... and the radius the planner gets is the circle's (the path's
        // first and last chords end on a corner and a stop: none there).
        if (i > 0 && i + 1 < curve.size()) {
            EXPECT_NEAR(s.radius_mm, 20, 1e-6) << i;
        }
    }
    // A half circle of r = 20 within 0.002 mm needs at least pi / (2 acos(1 - 1e-4)) chords.
    EXPECT_GE(static_cast<double>(curve_segs), std::numbers::pi / (2 * std::acos(1 - 0.002 / 20)) - 1);
}

TEST(Nurbs, CurveDistanceOfPointsAlongACircle) {
    // Points met in order around a full circle (r = 10), each off it radially
    // by a known amount: the distance is that amount (within the polyline's 1e-6 mm).
    const Nurbs f = full_circle(10, 50, 50);
    CurveDistance dist(f);
    for (int i = 0; i <= 3000; ++i) {
        const double a = 2 * std::numbers::pi * i / 3000;
        const double off = 0.01 * std::sin(7 * a);
        const Vector3d p(50 + (10 + off) * std::cos(a), 50 + (10 + off) * std::sin(a), 2.0);
        EXPECT_NEAR(dist(p), std::abs(off), 2e-6) << i;
    }
}

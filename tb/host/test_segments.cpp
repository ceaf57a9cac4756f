// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "plan/segments.h"

using namespace cpstep::plan;

namespace {

Machine machine(double spm = 80.3, double tmax = 2000) {
    const std::string text = fmt::format(R"([card]
clock_hz = 50e6
[planner]
arc_tolerance_mm = 0.01
[axes.x]
steps_per_mm = {0}
travel_min_mm = 0
travel_max_mm = {1}
max_velocity_mm_s = 100
max_accel_mm_s2 = 1000
max_jerk_mm_s3 = 10000
driver = "TMC2209"
[axes.y]
steps_per_mm = {0}
travel_min_mm = -50
travel_max_mm = 100
max_velocity_mm_s = 100
max_accel_mm_s2 = 1000
max_jerk_mm_s3 = 10000
driver = "TMC2209"
)", spm, tmax);
    auto r = parse_machine(text, "m.toml");
    EXPECT_TRUE(r.ok()) << join(r.errors);
    return *r;
}

Result<std::vector<StepSegment>> run(const std::string& gcode, const Machine& m) {
    auto job = parse_gcode(gcode, "job.ngc");
    EXPECT_TRUE(job.ok()) << join(job.errors);
    return make_step_segments(*job, m);
}

}  // namespace

TEST(Segments, MmToStepsRoundsHalfUp) {
    EXPECT_EQ(mm_to_steps(0.0, 80), 0);
    EXPECT_EQ(mm_to_steps(1.0, 80), 80);
    EXPECT_EQ(mm_to_steps(0.00625, 80), 1);    // exactly half a step
    EXPECT_EQ(mm_to_steps(-0.00625, 80), 0);   // ties go up
    EXPECT_EQ(mm_to_steps(-0.0063, 80), -1);
}

TEST(Segments, NoDriftOver100kSegments) {
    // 100,000 absolute moves of 0.0123 mm at a non-integer 80.3 steps/mm.
    const Machine m = machine(80.3);
    std::string g = "G1 F6000\n";
    for (int k = 1; k <= 100000; ++k) g += fmt::format("X{:.4f}\n", k * 0.0123);
    auto r = run(g, m);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    std::int64_t sum = 0;
    std::size_t k_seen = 0;
    for (const auto& s : *r.value) {
        sum += s.delta()[0];
        // Every end is the rounding of its own absolute target (line k+1 holds move k).
        const int k = s.loc.line - 1;
        const double target = std::stod(fmt::format("{:.4f}", k * 0.0123));
        EXPECT_EQ(s.end[0], static_cast<std::int64_t>(std::floor(target * 80.3 + 0.5))) << k;
        ++k_seen;
    }
    // 0.0123 mm is about 0.99 steps: some moves round to nothing and merge.
    EXPECT_GT(k_seen, 90000u);
    EXPECT_EQ(sum, static_cast<std::int64_t>(std::floor(1230.0 * 80.3 + 0.5)));
}

TEST(Segments, ArcChordsStayWithinTolerance) {
    MotionBlock b;
    b.kind = MotionKind::arc_ccw;
    b.start = {20, 10, 0, 0};
    b.end = {10, 20, 2, 0};  // quarter circle around (10,10), helical in Z
    b.center_x = 10;
    b.center_y = 10;
    for (double tol : {0.001, 0.01, 0.1}) {
        auto pts = arc_chord_points(b, tol);
        // Minimum chord count from the sagitta formula r(1 - cos(theta/2)) <= tol.
        const double max_theta = 2 * std::acos(1 - tol / 10);
        EXPECT_EQ(pts.size(), static_cast<std::size_t>(std::ceil((M_PI / 2) / max_theta)));
        PerAxis<double> prev = b.start;
        for (const auto& p : pts) {
            EXPECT_NEAR(std::hypot(p[0] - 10, p[1] - 10), 10, 1e-9);
            const double mx = (p[0] + prev[0]) / 2, my = (p[1] + prev[1]) / 2;
            EXPECT_LE(10 - std::hypot(mx - 10, my - 10), tol + 1e-12);
            // Z rises linearly with the angle.
            const double ang = std::atan2(p[1] - 10, p[0] - 10);
            EXPECT_NEAR(p[2], 2 * ang / (M_PI / 2), 1e-9);
            prev = p;
        }
        EXPECT_EQ(pts.back(), b.end);
    }
}

TEST(Segments, FullCircleAndDirection) {
    MotionBlock b;
    b.kind = MotionKind::arc_cw;
    b.start = b.end = {10, 0, 0, 0};
    auto pts = arc_chord_points(b, 0.01);
    ASSERT_GT(pts.size(), 8u);
    // Clockwise from angle 0: the first point is below the x axis.
    EXPECT_LT(pts.front()[1], 0);
    EXPECT_EQ(pts.back(), b.end);
}

TEST(Segments, ArcSegmentsFromGcode) {
    const Machine m = machine(100);
    auto r = run("G0 X20 Y10\nG3 X10 Y20 I-10 F600\nG4 P1\n", m);
    ASSERT_TRUE(r.ok());
    const auto& segs = *r.value;
    EXPECT_EQ(segs.front().kind, MotionKind::rapid);
    EXPECT_EQ(segs.front().start, (PerAxis<std::int64_t>{0, 0, 0, 0}));
    EXPECT_EQ(segs.front().end, (PerAxis<std::int64_t>{2000, 1000, 0, 0}));
    EXPECT_EQ(segs.back().kind, MotionKind::dwell);
    EXPECT_EQ(segs.back().dwell_s, 1.0);
    EXPECT_EQ(segs.back().start, segs.back().end);
    EXPECT_EQ(segs[segs.size() - 2].end, (PerAxis<std::int64_t>{1000, 2000, 0, 0}));
    for (std::size_t i = 1; i < segs.size(); ++i) EXPECT_EQ(segs[i].start, segs[i - 1].end);
    // Length of a step segment: hypot of its mm deltas.
    EXPECT_NEAR(segs.front().length_mm(m), std::hypot(20.0, 10.0), 1e-12);
}

TEST(Segments, TravelAndAxisErrors) {
    const Machine m = machine(100, 300);
    EXPECT_EQ(join(run("G0 X10\nG1 X301 F60\nG0 X0 Y-51\nG0 Y-50 X0\n", m).errors),
              "job.ngc:2:1: X 301.000 mm is outside the travel 0..300 mm of axis x\n"
              "job.ngc:3:1: Y -51.000 mm is outside the travel -50..100 mm of axis y");
    EXPECT_EQ(join(run("G0 Z1\n", m).errors), "job.ngc:1:1: axis Z is not on this machine (m.toml)");
    // An arc whose end points are inside but whose bulge leaves the travel.
    auto e = join(run("G0 X5 Y-47\nG3 X15 Y-47 I5 F60\n", m).errors);
    EXPECT_EQ(e.rfind("job.ngc:2:1: Y -5", 0), 0u) << e;
    EXPECT_NE(e.find(" mm is outside the travel -50..100 mm of axis y"), std::string::npos) << e;
}

// An arc is checked against the travel on the points that bound it (its ends
// and the axis-extreme points it sweeps) before any chord is made: a full
// circle of radius 10^12 mm (which would be 3e7 chords, about a gigabyte) is
// refused at its far x extreme, where no chord point lies, and an arc inside the
// travel that would need more than 10^6 chords is refused by its count.
TEST(Segments, HugeArcsAreRefusedBeforeTheirChords) {
    const Machine m = machine(100, 300);
    EXPECT_EQ(join(run("G0 X1 Y1\nG2 X1 Y1 I1000000000000 J0 F60\n", m).errors),
              "job.ngc:2:1: X 2000000000001.000 mm is outside the travel 0..300 mm of axis x");
    // Half circles whose ends are inside: the top at y = 100 is inside, at 110 not.
    EXPECT_EQ(join(run("G0 X250 Y0\nG3 X50 Y0 I-100 J0 F60\n", m).errors), "");
    EXPECT_EQ(join(run("G0 X260 Y0\nG3 X40 Y0 I-110 J0 F60\n", m).errors),
              "job.ngc:2:1: Y 110.000 mm is outside the travel -50..100 mm of axis y");
    Machine fine = m;
    fine.planner.arc_tolerance_mm = 1e-10;
    const std::string e = join(run("G0 X150 Y0\nG2 X150 Y0 I-50 J0 F60\n", fine).errors);
    EXPECT_EQ(e.rfind("job.ngc:2:1: an arc of radius 50 mm needs ", 0), 0u) << e;
    EXPECT_NE(e.find("chords within arc_tolerance_mm = 1e-10; at most 1000000 are made"), std::string::npos) << e;
    // A NURBS curve (G5.2/G5.3) inside the travel likewise: a parabola 280 mm
    // across sampled within 1e-12 mm would need some 6·10^6 chords; refused at
    // its block, without making them.
    Machine finer = m;
    finer.planner.arc_tolerance_mm = 1e-12;
    const std::string n =
        join(run("G0 X10 Y10\nG5.2 X10 Y10 P1 L3 F60\nX150 Y90 P1\nX290 Y10 P1\nG5.3\n", finer).errors);
    EXPECT_EQ(n.rfind("job.ngc:2:1: the curve needs more than 1000000 chords within arc_tolerance_mm = 1e-12", 0), 0u)
        << n;
}

// An arc's radius (which caps its speed) is measured in its own plane: a G18
// half circle of radius 10 mm in XZ, away from y = 0, is a 10 mm curve (it was
// measured from X and Y until 2026-11-26: 11.18 mm here, y being 5).
TEST(Segments, ArcRadiusIsMeasuredInTheArcsPlane) {
    Machine m = machine(100, 300);
    m.axes[2] = m.axes[0];
    m.axes[2].travel_min_mm = -50;
    m.axes[2].travel_max_mm = 50;
    auto r = run("G0 X40 Y5 Z0\nG18 G2 X20 Z0 I-10 K0 F60\n", m);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    int arcs = 0;
    for (const StepSegment& s : *r.value) {
        // The first and last chord join the arc to a line: no radius (the rule of
        // path_radii in every plane).
        if (s.kind != MotionKind::arc_cw || !std::isfinite(s.radius_mm)) continue;
        ++arcs;
        EXPECT_NEAR(s.radius_mm, 10, 0.01) << "segment at z " << s.to_mm[2];
    }
    EXPECT_GT(arcs, 10);
}

// The planner times a segment over its unrounded chord (so the planned speed
// is the speed along the G-code's geometry, with no chord-to-chord ripple from
// rounding), unless that chord is less than half the rounded one.
TEST(Segments, PlannedLengthIsTheUnroundedChord) {
    const Machine m = machine(80);
    auto job = parse_gcode("G1 F600 X0.33 Y0.21\nX0.335\n", "job.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto r = make_step_segments(*job, m);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    ASSERT_EQ(r->size(), 2u);
    // (0.33, 0.21) mm at 80 steps/mm rounds to (26, 17) steps.
    EXPECT_NEAR((*r)[0].length_mm(m), std::hypot(26.0, 17.0) / 80, 1e-12);
    EXPECT_NEAR((*r)[0].planned_length_mm(m), std::hypot(0.33, 0.21), 1e-12);
    // X 0.33 -> 0.335: 0.005 mm of geometry, one step (0.0125 mm) after
    // rounding (26.4 -> 26, 26.8 -> 27): the rounded length is used.
    EXPECT_EQ((*r)[1].delta()[0], 1);
    EXPECT_NEAR((*r)[1].planned_length_mm(m), 1.0 / 80, 1e-12);
}

// A straight block between two arcs is straight: the arcs' radii at its ends
// belong to the arcs (and to the junctions), not to the line; the arcs' own
// chords keep their radius.
TEST(Segments, LineBetweenTwoArcsIsStraight) {
    const Machine m = machine(80);
    // Tangent everywhere from line 2 on: up along x = 10, a quarter circle
    // (centre (16, 10)) onto y = 16, along it, a quarter circle (centre (40, 10))
    // down onto x = 46, down along it.
    auto job = parse_gcode("G1 F600 X10 Y4\nY10\nG2 X16 Y16 I6 J0\nG1 X40\nG2 X46 Y10 I0 J-6\nG1 Y4\n",
                           "job.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto r = make_step_segments(*job, m);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    std::size_t arcs = 0, lines = 0;
    for (const auto& s : *r) {
        if (s.kind == MotionKind::arc_cw) {
            ++arcs;
            EXPECT_NEAR(s.radius_mm, 6.0, 1e-9);
        } else if (s.loc.line == 4) {
            ++lines;
            EXPECT_TRUE(std::isinf(s.radius_mm)) << s.radius_mm;
            EXPECT_NEAR(s.radius_start_mm, 6.0, 1e-9);  // the junction still sees the arc's bend
        }
    }
    EXPECT_GT(arcs, 4u);
    EXPECT_EQ(lines, 1u);
}

// The step segments made block by block hold a window of the polyline, not the
// job, and their radii are those of path_radii() over the whole polyline: a
// spiral of 20,000 G1 points (radius 5 to 95 mm, each point 2 to 60 steps
// apart) with a corner every 1,000 points.
TEST(StepSegmenter, MakesTheSegmentsAsTheBlocksArriveWithTheWholePolylinesRadii) {
    const Machine m = machine(80, 2000);
    std::string g = "G1 F600 X1000 Y0\n";
    std::vector<PerAxis<double>> pts{{1000, 0, 0, 0}};
    const int n = 20000;
    for (int i = 1; i <= n; ++i) {
        const double a = i * 0.008, r = 5 + 90.0 * i / n;
        PerAxis<double> p{1000 + r * std::cos(a) - 5, r * std::sin(a) * 0.5, 0, 0};
        if (i % 1000 == 0) p[1] += 2;  // a corner
        // The G-code's coordinates are what the planner sees: round as it prints them.
        p[0] = std::round(p[0] * 1e6) / 1e6;
        p[1] = std::round(p[1] * 1e6) / 1e6;
        g += fmt::format("G1 X{:.6f} Y{:.6f}\n", p[0], p[1]);
        pts.push_back(p);
    }
    auto job = parse_gcode(g, "spiral.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    StepSegmenter segmenter(m, "spiral.ngc");
    std::vector<StepSegment> got;
    std::size_t first_out_at = 0;
    for (std::size_t b = 0; b < job->blocks.size(); ++b) {
        segmenter.push(job->blocks[b], b);
        while (auto s = segmenter.next()) {
            if (got.empty()) first_out_at = b + 1;
            got.push_back(*s);
        }
    }
    segmenter.finish();
    while (auto s = segmenter.next()) got.push_back(*s);
    ASSERT_TRUE(segmenter.done()) << join(segmenter.errors());
    // Every point is a step or more from the one before: a segment per G1 after the first.
    ASSERT_EQ(got.size(), std::size_t(n) + 1);
    const std::vector<double> arc(pts.size() + 1, std::numeric_limits<double>::infinity());
    std::vector<PerAxis<double>> poly{PerAxis<double>{}};  // the first G1 starts at the origin
    poly.insert(poly.end(), pts.begin(), pts.end());
    const auto r = path_radii(poly, arc);
    std::size_t curved = 0;
    for (std::size_t k = 0; k < got.size(); ++k) {
        const double r0 = r[k], r1 = r[k + 1];
        const double expect = r0 < INFINITY && r1 < INFINITY ? std::min(r0, r1) : INFINITY;
        ASSERT_EQ(got[k].radius_mm, expect) << "segment " << k;
        ASSERT_EQ(got[k].radius_start_mm, r0) << "segment " << k;
        ASSERT_EQ(got[k].radius_ends_max_mm, std::max(r0, r1)) << "segment " << k;
        curved += expect < INFINITY;
    }
    EXPECT_GT(curved, std::size_t(n) * 9 / 10);
    // The window: a segment waits for 65 points past its end, no more.
    EXPECT_LE(first_out_at, 70u);
    EXPECT_LE(segmenter.max_held_points(), 200u) << "of " << poly.size() << " points";
    std::printf("first out after %zu of %zu blocks, at most %zu points held\n", first_out_at, job->blocks.size(),
                segmenter.max_held_points());
}

// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "plan/pipeline.h"
#include "plan/chunks.h"
#include "plan/planner.h"

using namespace cpstep::plan;

namespace {

Machine machine(const std::string& on_limit = "refuse", double vmax = 60, const char* drv = "DM556") {
    auto r = parse_machine(fmt::format(R"([card]
clock_hz = 48e6
[planner]
junction_deviation_mm = 0.01
on_limit = "{}"
[axes.x]
steps_per_mm = 80
travel_min_mm = 0
travel_max_mm = 300
max_velocity_mm_s = {}
max_accel_mm_s2 = 500
max_jerk_mm_s3 = 2000
driver = "{}"
[axes.y]
steps_per_mm = 100
travel_min_mm = 0
travel_max_mm = 300
max_velocity_mm_s = 30
max_accel_mm_s2 = 250
max_jerk_mm_s3 = 1000
driver = "{}"
)", on_limit, vmax, drv, drv), "m.toml");
    EXPECT_TRUE(r.ok()) << join(r.errors);
    return *r;
}

Result<std::vector<PlannedSegment>> plan(const std::string& g, const Machine& m,
                                         std::vector<StepSegment>* segs_out = nullptr) {
    auto job = parse_gcode(g, "job.ngc");
    EXPECT_TRUE(job.ok()) << join(job.errors);
    auto segs = make_step_segments(*job, m);
    EXPECT_TRUE(segs.ok()) << join(segs.errors);
    if (segs_out) *segs_out = *segs.value;
    return plan_feeds(*segs.value, m, "job.ngc");
}

}  // namespace

TEST(Planner, ProjectedLimits) {
    const Machine m = machine();
    // 30 mm in x (2400 steps), 40 mm in y (4000 steps): direction (0.6, 0.8).
    auto l = project_limits({2400, 4000, 0, 0}, m);
    EXPECT_NEAR(l.v, std::min(60 / 0.6, 30 / 0.8), 1e-9);
    EXPECT_NEAR(l.a, std::min(500 / 0.6, 250 / 0.8), 1e-9);
    EXPECT_NEAR(l.j, std::min(2000 / 0.6, 1000 / 0.8), 1e-9);
    auto lx = project_limits({-80, 0, 0, 0}, m);
    EXPECT_EQ(lx.v, 60);
}

TEST(Planner, JunctionSpeedModel) {
    const PerAxis<double> x{1, 0, 0, 0}, y{0, 1, 0, 0}, mx{-1, 0, 0, 0};
    EXPECT_TRUE(std::isinf(junction_speed(x, x, 500, 0.01)));
    EXPECT_EQ(junction_speed(x, mx, 500, 0.01), 0);
    // 90 degrees: sin(theta/2) = sqrt(1/2).
    const double s = std::sqrt(0.5);
    EXPECT_NEAR(junction_speed(x, y, 500, 0.01), std::sqrt(500 * 0.01 * s / (1 - s)), 1e-12);
}

TEST(Planner, CardSpeedLimitFromPulseTiming) {
    const Machine m = machine();
    // DM556 at 48 MHz: 120 + 120 cycles, + 48 cycles of tolerance per step.
    EXPECT_NEAR(card_speed_limit({80, 0, 0, 0}, m), 48e6 / 288 / 80, 1e-9);
}

TEST(Planner, SquarePathIsContinuousAndWithinLimits) {
    const Machine m = machine();
    std::vector<StepSegment> segs;
    auto r = plan("G1 F3000 X50\nY50\nX0\nY0\nX50\nX100\n", m, &segs);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    const auto& p = *r.value;
    ASSERT_EQ(p.size(), 6u);
    EXPECT_EQ(p.front().profile.v_entry, 0);
    EXPECT_EQ(p.back().profile.v_exit, 0);
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto& s = p[i];
        EXPECT_NEAR(s.profile.length, s.length, 1e-12);
        EXPECT_LE(s.profile.v_peak, s.cruise + 1e-12);
        EXPECT_LE(s.cruise, 50 + 1e-12);  // F3000 = 50 mm/s
        if (i > 0) {
            EXPECT_EQ(s.profile.v_entry, p[i - 1].profile.v_exit);
            EXPECT_NEAR(s.t_start, p[i - 1].t_start + p[i - 1].duration, 1e-12);
        }
        for (int k = 0; k <= 400; ++k) {
            auto st = s.profile.at(s.duration * k / 400);
            EXPECT_LE(std::abs(st.a), s.limits.a * (1 + 1e-9));
            EXPECT_LE(std::abs(st.j), s.limits.j);
        }
    }
    // 90-degree corners: at most the junction-deviation speed for a = 250 (y's limit
    // projected is 250 on y moves; x moves 500; the corner uses the smaller).
    const double sh = std::sqrt(0.5);
    const double vj = std::sqrt(250 * 0.01 * sh / (1 - sh));
    for (int i = 1; i <= 3; ++i) { EXPECT_LE(p[static_cast<std::size_t>(i)].profile.v_entry, vj + 1e-9); }
    // Straight on (X50 -> X100): limited only by reachability, above the corner speed.
    EXPECT_GT(p[5].profile.v_entry, vj);
}

TEST(Planner, FeedAboveAxisLimitIsLoweredWithWarning) {
    const Machine m = machine();
    auto r = plan("G1 Y10 F6000\n", m);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(join(r.warnings), "job.ngc:1:1: feed 100 mm/s lowered to the axes' limit 30 mm/s");
    EXPECT_EQ(r.value->front().cruise, 30);
}

TEST(Planner, BeyondCardRateRefusedOrSlowed) {
    // TB6600: 5+5 us per step at 80 steps/mm allows 48e6/(240+240+48)/80 = 1136 mm/s; use a
    // machine limit above the card's rate to provoke it.
    const double card = 48e6 / (240 + 240 + 48) / 80.0;
    auto refuse = plan("G0 X200\n", machine("refuse", 2000, "TB6600"));
    EXPECT_FALSE(refuse.ok());
    EXPECT_EQ(join(refuse.errors),
              fmt::format("job.ngc:1:1: needs 2000 mm/s but the card's step timing allows {:.4g} "
                          "mm/s here (planner.on_limit = \"refuse\")",
                          card));
    auto slow = plan("G0 X200\n", machine("slow", 2000, "TB6600"));
    ASSERT_TRUE(slow.ok());
    EXPECT_EQ(join(slow.warnings),
              fmt::format("job.ngc:1:1: planned at {:.4g} mm/s instead of 2000 mm/s: the card's "
                          "step timing allows no more",
                          card));
    EXPECT_NEAR(slow.value->front().cruise, card, 1e-9);
}

TEST(Planner, DwellAndSpindleStopTheMotion) {
    const Machine m = machine();
    auto r = plan("G1 F3000 X10\nG4 P0.25\nX20\nM3\nX30\n", m);
    ASSERT_TRUE(r.ok());
    const auto& p = *r.value;
    ASSERT_EQ(p.size(), 4u);
    EXPECT_EQ(p[0].profile.v_exit, 0);
    EXPECT_EQ(p[1].duration, 0.25);
    EXPECT_EQ(p[2].profile.v_entry, 0);
    EXPECT_EQ(p[2].profile.v_exit, 0);  // the spindle switches between X20 and X30
    EXPECT_EQ(p[3].profile.v_entry, 0);
    EXPECT_NEAR(p[2].t_start, p[1].t_start + 0.25, 1e-12);
}

// A long line at full feed into a tangent quarter arc of radius 3 mm, and out
// of it on a tangent line: every junction is tangent, so junction deviation
// alone would let the feed (30 mm/s) run through the arc. On a circle of radius
// r the acceleration is a_t T + (v^2/r) N and the jerk (j_t - v^3/r^2) T +
// (3 v a_t / r) N (T, N orthogonal unit vectors); every axis is within its
// limits when those vectors are within the smallest axis limits (here y's:
// 250 mm/s^2, 1000 mm/s^3). Sampled along every arc chord's profile.
TEST(Planner, ArcsKeepCentripetalAndTangentialWithinTheAxes) {
    const Machine m = machine();
    const double r = 3.0, A = 250, J = 1000;
    std::vector<StepSegment> segs;
    auto res = plan("G1 F1800 X0 Y60\nG1 X60\nG2 X63 Y57 I0 J-3\nG1 Y0\n", m, &segs);
    ASSERT_TRUE(res.ok()) << join(res.errors);
    const auto& p = *res.value;
    size_t arc_chords = 0;
    double slowest = 1e9;
    for (size_t i = 0; i < p.size(); ++i) {
        if (segs[i].kind != MotionKind::arc_cw) continue;
        ++arc_chords;
        for (int k = 0; k <= 50; ++k) {
            const auto st = p[i].profile.at(p[i].duration * k / 50);
            const double an = st.v * st.v / r;
            EXPECT_LE(std::hypot(st.a, an), A * (1 + 1e-9)) << "chord " << i;
            EXPECT_LE(std::hypot(std::abs(st.j) + st.v * an / r, 3 * st.v * st.a / r), J * (1 + 1e-9))
                << "chord " << i;
            slowest = std::min(slowest, st.v);
        }
    }
    EXPECT_GT(arc_chords, 10u);
    EXPECT_GT(slowest, 5.0);  // slowed for the bend, not stopped
    // The lines before and after reach the feed.
    EXPECT_GT(p[1].profile.v_peak, 29.9);
    EXPECT_GT(p.back().profile.v_peak, 29.9);
}

// The same line into the tangent arc: at the tangent point the centripetal
// acceleration steps from 0 to v^2/r, all of it on Y (the arc's centre is
// straight below the point). Counted as a ramp over planner.curvature_step_s, the
// step may be at most Y's jerk times that time: v^2 / r <= 1000 * 0.02 mm/s^2
// (the planner's normal comes from the arc's chords, a chord's half-angle off:
// 0.1 % allowed). With the time relaxed, the junction is faster: the cap was
// binding, and it is the only thing that changed.
TEST(Planner, CurvatureStepIntoATangentArcIsARampWithinTheJerk) {
    const double r = 3.0, J_y = 1000;
    const std::string g = "G1 F1800 X0 Y60\nG1 X60\nG2 X63 Y57 I0 J-3\nG1 Y0\n";
    auto entry_speed = [&](const Machine& m) {
        std::vector<StepSegment> segs;
        auto res = plan(g, m, &segs);
        EXPECT_TRUE(res.ok()) << join(res.errors);
        for (size_t i = 0; i < segs.size(); ++i)
            if (segs[i].kind == MotionKind::arc_cw) return (*res.value)[i].profile.v_entry;
        ADD_FAILURE() << "no arc";
        return 0.0;
    };
    Machine m = machine();
    ASSERT_EQ(m.planner.curvature_step_s, 0.02);  // the default: 20 ms
    const double v = entry_speed(m);
    EXPECT_LE(v * v / r, J_y * 0.02 * 1.001);
    EXPECT_GT(v * v / r, J_y * 0.02 * 0.5);  // not stopped for it either
    m.planner.curvature_step_s = 0.2;
    EXPECT_GT(entry_speed(m), 1.5 * v);
}

// A G1 polyline of 400 chords around a circle of radius 40 mm (a CAM post's
// arc), from rest: the speed builds up across many chords, so the acceleration
// is carried through the junctions and is continuous there; at the square's
// corners it is zero.
TEST(Planner, AccelerationCarriesAcrossSmoothJunctionsOnly) {
    const Machine m = machine();
    std::string g = "G0 X140 Y100\nF3000\n";
    for (int i = 1; i <= 400; ++i) {
        const double th = 2 * M_PI * i / 400;
        g += fmt::format("G1 X{:.4f} Y{:.4f}\n", 100 + 40 * std::cos(th), 100 + 40 * std::sin(th));
    }
    std::vector<StepSegment> segs;
    auto res = plan(g, m, &segs);
    ASSERT_TRUE(res.ok()) << join(res.errors);
    const auto& p = *res.value;
    double carried = 0;
    for (size_t i = 2; i < p.size(); ++i) {
        const double a_end = p[i - 1].profile.at(p[i - 1].duration).a;
        const double a_start = p[i].profile.at(0).a;
        EXPECT_NEAR(a_end, a_start, 1e-6) << "junction " << i;
        EXPECT_NEAR(p[i - 1].profile.v_exit, p[i].profile.v_entry, 1e-9);
        carried = std::max(carried, std::abs(a_start));
    }
    EXPECT_GT(carried, 20.0);  // not zero at every junction as a per-segment S-curve has
    // Radius from the unrounded geometry: 40 mm within the fit's 10 % margin.
    for (size_t i = 5; i + 5 < segs.size(); ++i) {
        EXPECT_GT(segs[i].radius_mm, 36.0);
        EXPECT_LT(segs[i].radius_mm, 40.5);
    }
    auto sq = plan("G1 F3000 X50\nY50\nX0\nY0\n", m);
    ASSERT_TRUE(sq.ok());
    for (size_t i = 1; i < sq->size(); ++i) {
        EXPECT_NEAR((*sq)[i].profile.at(0).a, 0, 1e-9);
        EXPECT_NEAR((*sq)[i - 1].profile.at((*sq)[i - 1].duration).a, 0, 1e-9);
    }
}

TEST(Planner, PolylineRadiusOfEqualChords) {
    // Chords of a circle of radius 5 turning by 10 degrees: L = 2 r sin(5 deg).
    const double th = 10 * M_PI / 180, L = 2 * 5 * std::sin(th / 2);
    const PerAxis<double> in{1, 0, 0, 0}, out{std::cos(th), std::sin(th), 0, 0};
    EXPECT_NEAR(polyline_radius(in, out, L), 5.0, 1e-9);
    EXPECT_EQ(polyline_radius(in, in, L), std::numeric_limits<double>::infinity());
    EXPECT_NEAR(curvature_speed(8, 500, 2000), std::min(std::sqrt(4000.0), std::cbrt(128000.0)), 1e-9);
}

// A peck-drilling pattern in miniature (what a G83 cycle expands to): a rapid
// down to just above the bottom of the hole, then a slow feed on in the same
// direction (a smooth, collinear junction between caps of 60 and 1 mm/s), each
// starting and ending at a reversal (rest). A profile over both spans from rest
// to rest has nothing to ramp between; it once came out with zero duration over
// the 5 mm + 1 mm, and the chunk compressor then found the next move less than
// a cycle after the previous one. Every segment must take at least its length
// at its feed (and no axis can average more than its limit), and each must
// start where the previous one ends.
TEST(Planner, CollinearRapidIntoFeedFromRestToRestTakesTime) {
    const Machine m = machine();
    const std::string g = "G21 G90 G94\nG0 X10\nG0 X5\nG1 X4 F60\nG0 X10\nG0 X5\nG1 X3 F120\nG0 X10\n";
    std::vector<StepSegment> segs;
    auto res = plan(g, m, &segs);
    ASSERT_TRUE(res.ok()) << join(res.errors);
    const auto& p = *res.value;
    // Expected from the G-code alone: X 0 -> 10 -> 5 -> 4 -> 10 -> 5 -> 3 -> 10,
    // feeds F60 = 1 mm/s, F120 = 2 mm/s, rapids at most the x axis's 60 mm/s.
    const double lengths[] = {10, 5, 1, 6, 5, 2, 7};
    const double min_time[] = {10.0 / 60, 5.0 / 60, 1.0 / 1, 6.0 / 60, 5.0 / 60, 2.0 / 2, 7.0 / 60};
    ASSERT_EQ(p.size(), 7u);
    double t = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        EXPECT_NEAR(p[i].length, lengths[i], 1e-9) << i;
        EXPECT_GE(p[i].duration, min_time[i] * (1 - 1e-9)) << i;
        EXPECT_EQ(p[i].t_start, t) << i;
        EXPECT_NEAR(p[i].profile.time_at(p[i].length), p[i].duration, 1e-12) << i;
        t = p[i].t_start + p[i].duration;
    }
    // The whole job through the card's timing: the move times strictly increase.
    auto job = parse_gcode(g, "job.ngc");
    ASSERT_TRUE(job.ok());
    Machine bound = m;
    auto pj = plan_job(*job, bound);
    ASSERT_TRUE(pj.ok()) << join(pj.errors);
    const auto ideal = ideal_times(*pj.value, bound.card.clock_hz);
    ASSERT_EQ(ideal.size(), static_cast<std::size_t>((10 + 5 + 1 + 6 + 5 + 2 + 7) * 80));
    for (std::size_t i = 1; i < ideal.size(); ++i) ASSERT_GT(ideal[i], ideal[i - 1] + 1) << i;
}

// A job that would outlast the card's cycle count (2^62 cycles of its clock,
// 9.6e10 s at 48 MHz) is refused at the block where it would: a dwell of 10^99
// seconds (fuzz finding 15: the pause's count of intervals overflowed), or a
// move at a feed so slow that it would take as long. The rest of such a job,
// and a long but possible dwell, are planned.
TEST(Pipeline, AJobPastTheCardsCycleCountIsRefusedAtItsBlock) {
    const Machine m = machine();
    // (G-code numbers have no exponent.)
    for (const std::string& g : {"G1 X1 F600\nG4 P1" + std::string(99, '0') + "\nG1 X2\n",
                                 std::string("G1 X1 F600\nG4 P100000000000\nG1 X2\n"),
                                 std::string("G1 X1 F600\nG1 X2 F0.000000000001\nG1 X3 F600\n")}) {
        auto job = parse_gcode(g, "job.ngc");
        ASSERT_TRUE(job.ok()) << g << join(job.errors);
        auto pj = plan_job(*job, m);
        ASSERT_FALSE(pj.ok()) << g;
        ASSERT_EQ(pj.errors.size(), 1u) << g << join(pj.errors);
        EXPECT_EQ(pj.errors[0].loc.line, 2) << g;
        EXPECT_NE(pj.errors[0].message.find("the job would last past 9.61e+10 s here"), std::string::npos)
            << join(pj.errors);
    }
    // A dwell of 60 days is long, not impossible: pause moves of up to 2^32 - 1
    // cycles, at most 65,535 of them (one chunk's count; 67.9 days at 48 MHz).
    // Longer is refused before its moves are made (fuzz finding 16: a dwell of
    // 70 years made 2.5 10^7 pause moves, 57 s and 900 MB), alone or made of
    // dwells in a row, before a move or at the end.
    const double days60 = 60 * 86400.0;
    auto job = parse_gcode(fmt::format("G1 X1 F600\nG4 P{:.0f}\nG1 X2\n", days60), "job.ngc");
    ASSERT_TRUE(job.ok());
    auto pj = plan_job(*job, m);
    ASSERT_TRUE(pj.ok()) << join(pj.errors);
    EXPECT_GT(pj->stats.duration_s, days60);
    EXPECT_EQ(double(pj->stats.pause_moves), std::floor(days60 * 48e6 / double(kMaxMoveDelayCycles)));
    for (const std::string& g : {std::string("G1 X1 F600\nG4 P2226329287 X4\nG1 X2\n"),
                                 std::string("G1 X1 F600\nG4 P3000000\nG4 P3000000\nG1 X2\n"),
                                 std::string("G1 X1 F600\nG4 P3000000\nG4 P3000000\n")}) {
        auto long_job = parse_gcode(g, "job.ngc");
        ASSERT_TRUE(long_job.ok()) << join(long_job.errors);
        auto refused = plan_job(*long_job, m);
        ASSERT_FALSE(refused.ok()) << g;
        ASSERT_EQ(refused.errors.size(), 1u) << join(refused.errors);
        EXPECT_EQ(refused.errors[0].loc.line, 2) << g;
        EXPECT_NE(refused.errors[0].message.find("is longer than the card times: at most 65535 pause moves"),
                  std::string::npos)
            << join(refused.errors);
    }
}

// A pause is the next move's first interval on the card (32 bits of cycles): at
// 48 MHz, 89.478 s at most. A longer one, and one after the last move, is run as
// pause moves — moves that step no axis, a card segment of their own — each
// interval under 2^32 - 1 cycles, the move after them on its planned time; the
// pins never show them, so the job's moves and ideal times leave them out.
TEST(Pipeline, PausesLongerThanOneMoveIntervalAndTrailingDwellsArePauseMoves) {
    const Machine m = machine();
    const double longest = double(kMaxMoveDelayCycles) / 48e6;
    const std::string head = "G21 G90\nG1 X1 F600\n";
    // Every interval of the card's timer, pause moves included, fits 32 bits.
    const auto intervals_fit = [](const PlannedJob& pj) {
        std::int64_t prev = 0;
        for (const auto& c : pj.card)
            for (std::int64_t t : expand(c.chunks, prev)) {
                if (t - prev > kMaxMoveDelayCycles || t <= prev) return false;
                prev = t;
            }
        return true;
    };
    const auto pauses = [](const PlannedJob& pj) {
        std::uint64_t n = 0;
        for (const auto& c : pj.card) n += c.segment.pause ? 1 : 0;
        return n;
    };
    // The gap between the two moves' steps is the dwell plus their ramps to and
    // from rest (a few tens of ms here): under one interval, no pause moves.
    auto fits = parse_gcode(head + fmt::format("G4 P{:.3f}\nG1 X2\nM2\n", longest - 0.5), "job.ngc");
    ASSERT_TRUE(fits.ok());
    auto p = plan_job(*fits, m);
    ASSERT_TRUE(p.ok()) << join(p.errors);
    EXPECT_EQ(pauses(*p.value), 0u);
    EXPECT_EQ(p->stats.pause_moves, 0u);

    // Two dwells in a row add up to more than one interval, 1000 s to many: pause
    // moves in between, the second move where it was planned.
    for (const double second : {1.0, 1000.0}) {
        auto two = parse_gcode(head + fmt::format("G4 P{:.3f}\nG4 P{}\nG1 X2\nM2\n", longest - 0.5, second),
                               "job.ngc");
        ASSERT_TRUE(two.ok());
        auto q = plan_job(*two, m);
        ASSERT_TRUE(q.ok()) << join(q.errors);
        EXPECT_EQ(pauses(*q.value), 1u) << second;
        const double gap_cycles = (longest - 0.5 + second) * 48e6;
        EXPECT_GE(q->stats.pause_moves, std::uint64_t(gap_cycles / double(kMaxMoveDelayCycles))) << second;
        EXPECT_LE(q->stats.pause_moves, std::uint64_t(gap_cycles / double(kMaxMoveDelayCycles)) + 1) << second;
        EXPECT_TRUE(intervals_fit(*q.value)) << second;
        // The pause is at the dwell's line, between the two moves; the moves and
        // their ideal times are the 160 steps of X.
        ASSERT_EQ(q->card.size(), 3u);
        EXPECT_TRUE(q->card[1].segment.pause);
        EXPECT_EQ(q->card[1].segment.loc.line, 3);
        EXPECT_EQ(q->card[1].segment.delta, (PerAxis<std::int64_t>{}));
        EXPECT_EQ(q->stats.moves, 160u);
        const auto ideal = ideal_times(*q.value, 48e6);
        ASSERT_EQ(ideal.size(), 160u);
        // The second move's first step, timed across the pause moves, is on its
        // ideal time (within the chunk tolerance of a cycle or two).
        std::int64_t prev = 0, first_after = 0;
        for (std::size_t c = 0; c < q->card.size(); ++c) {
            const auto t = expand(q->card[c].chunks, prev);
            if (c == 2) first_after = t.front();
            prev = t.back();
        }
        EXPECT_NEAR(double(first_after), ideal[80], m.chunk_tolerance_cycles() + 1) << second;
        EXPECT_GT(ideal[80] - ideal[79], gap_cycles * 0.999) << second;
    }

    // A dwell after the last move: pause moves to its end, which is the job's end.
    auto trailing = parse_gcode(head + "G4 P30\nM2\n", "job.ngc");
    ASSERT_TRUE(trailing.ok());
    auto r = plan_job(*trailing, m);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    EXPECT_EQ(r.warnings.size(), 0u) << join(r.warnings);
    ASSERT_EQ(r->card.size(), 2u);
    EXPECT_TRUE(r->card[1].segment.pause);
    EXPECT_EQ(r->card[1].segment.moves, 1u);
    EXPECT_EQ(r->stats.pause_moves, 1u);
    const auto last_move = expand(r->card[0].chunks, 0).back();
    const auto end = expand(r->card[1].chunks, last_move).back();
    EXPECT_NEAR(double(end - last_move), 30 * 48e6, m.chunk_tolerance_cycles() + 1);
    EXPECT_NEAR(r->stats.duration_s, double(end) / 48e6, 1e-9);
    // 1 mm at 10 mm/s with its S-curve ends, then the 30 s.
    EXPECT_GT(r->stats.duration_s, 30.1);
    EXPECT_LT(r->stats.duration_s, 31.0);
    // After two moves that join (the polyline's last vertex repeated for the dwell
    // used to give the second a radius of 0: "internal: no feasible profile").
    auto two_moves = parse_gcode(head + "G1 X2\nG4 P3\nM2\n", "job.ngc");
    auto r3 = plan_job(*two_moves, m);
    ASSERT_TRUE(r3.ok()) << join(r3.errors);
    EXPECT_EQ(r3->stats.pause_moves, 1u);
    EXPECT_GT(r3->feeds[1].cruise, 9.9);
    // 200 s after the last move: three intervals of 66.7 s.
    auto longer = parse_gcode(head + "G4 P200\nM2\n", "job.ngc");
    auto r2 = plan_job(*longer, m);
    ASSERT_TRUE(r2.ok()) << join(r2.errors);
    EXPECT_EQ(r2->stats.pause_moves, 3u);
    EXPECT_TRUE(intervals_fit(*r2.value));
}

namespace {

// Each axis's steps in a planned job as the card would emit them: move times
// from the chunks (chunks.h expand), the steps of each move from SPEC §1's
// closed form of its card segment's (u, v) pattern. Times in card cycles.
struct AxisStep {
    std::int64_t t;
    int dir;
};
std::vector<std::vector<AxisStep>> steps_of(const PlannedJob& pj) {
    std::vector<std::vector<AxisStep>> out(kAxes);
    std::int64_t prev = 0;
    for (const auto& c : pj.card) {
        const auto times = expand(c.chunks, prev);
        const CardSegment& s = c.segment;
        for (std::size_t a = 0; a < kAxes; ++a) {
            std::int64_t before = 0;
            for (std::uint32_t mv = 1; mv <= s.moves; ++mv) {
                const std::int64_t u = s.u[a], v = s.v[a];
                const std::int64_t done = (mv / u) * v + (2 * v * (mv % u) + u) / (2 * u);
                if (done != before) out[a].push_back({times[mv - 1], s.dir_positive[a] ? 1 : -1});
                before = done;
            }
        }
        prev = times.back();
    }
    return out;
}

}  // namespace

// A zigzag whose corners the path takes at speed while y reverses, on drivers
// that need 40 us of DIR hold and 40 us of setup: across every reversal the
// card needs step_high + hold + setup cycles between the two leading edges
// (docs/PULSE.md), or it stretches the move (a LATE fault). The planner slows
// the corners so that it never has to; without that, the corners here run at
// the feed and y's first step back comes 1,697 cycles (35 us) after its last
// step forward, against the 3,936 it needs.
TEST(Planner, AnAxisReversingAtSpeedKeepsDirHoldAndSetup) {
    std::string text = "[card]\nclock_hz = 48e6\n[planner]\njunction_deviation_mm = 5\n";
    for (const char* axis : {"x", "y"}) {
        text += fmt::format(R"([axes.{}]
steps_per_mm = 400
travel_min_mm = 0
travel_max_mm = 300
max_velocity_mm_s = 100
max_accel_mm_s2 = 20000
max_jerk_mm_s3 = 2000000
step_high_ns = 2000
step_low_ns = 2000
dir_setup_ns = 40000
dir_hold_ns = 40000
)", axis);
    }
    auto parsed = parse_machine(text, "zigzag.toml");
    ASSERT_TRUE(parsed.ok()) << join(parsed.errors);
    const Machine m = *parsed;
    auto job = parse_gcode("G21 G90\nG1 X5 Y5 F6000\nX10 Y0\nX15 Y5\nX20 Y0\nX25 Y5\nM2\n", "zigzag.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto pj = plan_job(*job, m);
    ASSERT_TRUE(pj.ok()) << join(pj.errors);
    const auto steps = steps_of(*pj);
    const PulseTimingCycles& p = m.axes[1].pulse;
    ASSERT_EQ(p.dir_setup, 1920u);
    const std::int64_t reversal = p.step_high + std::max<std::int64_t>(p.dir_hold + p.dir_setup, p.step_low);
    int reversals = 0;
    for (std::size_t i = 1; i < steps[1].size(); ++i) {
        const auto& a = steps[1][i - 1];
        const auto& b = steps[1][i];
        ASSERT_GE(b.t - a.t, p.step_high + p.step_low) << "step " << i;
        if (a.dir != b.dir) {
            ++reversals;
            EXPECT_GE(b.t - a.t, reversal) << "y reverses at step " << i << ", cycle " << a.t;
        }
    }
    EXPECT_EQ(reversals, 4);
    // The corners are not stops: y's reversal costs only what the driver needs.
    EXPECT_GT(pj->feeds[1].profile.v_entry, 1.0);
}

namespace {

void expect_same_plan(const PlannedSegment& a, const PlannedSegment& b, std::size_t i) {
    // Bit for bit: the streaming planner is the whole-job plan, not an approximation of it.
    EXPECT_EQ(a.t_start, b.t_start) << "segment " << i;
    EXPECT_EQ(a.duration, b.duration) << "segment " << i;
    EXPECT_EQ(a.cruise, b.cruise) << "segment " << i;
    EXPECT_EQ(a.profile.v_entry, b.profile.v_entry) << "segment " << i;
    EXPECT_EQ(a.profile.v_exit, b.profile.v_exit) << "segment " << i;
    for (std::size_t p = 0; p < a.profile.phases.size(); ++p) {
        EXPECT_EQ(a.profile.phases[p].duration, b.profile.phases[p].duration) << "segment " << i << " phase " << p;
        EXPECT_EQ(a.profile.phases[p].jerk, b.profile.phases[p].jerk) << "segment " << i << " phase " << p;
    }
}

}  // namespace

TEST(FeedPlanner, PlansAsTheSegmentsArriveHoldingTheLookaheadNotTheJob) {
    // 20,000 segments: a zigzag whose corners slow the path, runs of short
    // collinear moves, an arc now and then and a dwell.
    const Machine m = machine();
    std::string g = "G1 F3000\n";
    double x = 10, y = 10;
    for (int i = 0; i < 2000; ++i) {
        for (int k = 0; k < 6; ++k) g += fmt::format("G1 X{:.3f} Y{:.3f}\n", x += 0.25, y);
        g += fmt::format("G1 X{:.3f} Y{:.3f}\n", x, y += (i % 2 ? -2.0 : 2.0));
        if (i % 50 == 7) g += fmt::format("G2 X{:.3f} Y{:.3f} I1 J0\n", x + 2, y), x += 2;
        if (i % 400 == 9) g += "G4 P0.1\n";
        if (x > 280) {
            g += "G0 X10\n";
            x = 10;
        }
    }
    auto job = parse_gcode(g, "zigzag.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto segs = make_step_segments(*job, m);
    ASSERT_TRUE(segs.ok()) << join(segs.errors);
    const std::size_t n = segs->size();
    ASSERT_GT(n, 15000u);

    FeedOptions whole;
    whole.window_stop_factor = std::numeric_limits<double>::infinity();
    whole.max_lookahead_s = std::numeric_limits<double>::infinity();
    auto reference = plan_feeds(*segs.value, m, "zigzag.ngc", whole);
    ASSERT_TRUE(reference.ok()) << join(reference.errors);

    FeedPlanner planner(m, "zigzag.ngc");
    std::vector<PlannedSegment> got;
    std::size_t first_out_at = 0;  // segments pushed when the first came out
    for (const StepSegment& s : *segs.value) {
        planner.push(s);
        while (auto p = planner.next()) {
            if (got.empty()) first_out_at = planner.pushed();
            got.push_back(*p);
        }
    }
    EXPECT_LT(planner.handed_out(), n) << "the last segments wait for the job's end";
    planner.finish();
    while (auto p = planner.next()) got.push_back(*p);
    EXPECT_TRUE(planner.done());
    EXPECT_TRUE(planner.errors().empty());
    ASSERT_EQ(got.size(), n);
    for (std::size_t i = 0; i < n; ++i) expect_same_plan(got[i], (*reference)[i], i);
    EXPECT_EQ(planner.warnings().size(), reference.warnings.size());

    // It held a window, not the job: the lookahead past the segment planned
    // (a few corners ahead) and what the forward pass's groups may cover (65
    // spans: 229 segments here before the first came out).
    const FeedStats& st = planner.stats();
    EXPECT_GT(st.windows, 100u);
    EXPECT_LT(first_out_at, 400u);
    std::printf("first out after %zu of %zu segments, at most %zu held\n", first_out_at, n, planner.max_held());
    EXPECT_LT(planner.max_held(), 1500u) << "of " << n << " segments";
}

// The lookahead is bounded by time (FeedOptions::max_lookahead_s): a window that
// reaches that far past the spans the forward pass needs without making their
// entries final makes them final as they stand, from rest at its end. A
// straight run of 0.025 mm moves whose feeds alternate 10 % apart (each its own
// span, all joined smoothly) from rest to rest: the backward pass climbs from
// rest span by span, so no entry is its own cap until far ahead. Bounded at
// 0.25 s the plan is cut, looks no farther than the bound and a span, stays
// feasible (speeds continuous across every junction, under every cap, every
// segment timed) and is no faster than the whole-job plan; with the default
// bound the same job is the whole-job plan bit for bit.
TEST(FeedPlanner, ALookaheadPastItsTimeBoundIsCutNoFasterThanTheWholeJob) {
    const Machine m = machine();
    std::string g = "G21 G90\nG0 X10\nG4 P0.01\n";  // at rest at X10
    for (int i = 1; i <= 3000; ++i) g += fmt::format("G1 X{:.3f} F{}\n", 10 + 0.025 * i, i % 2 ? 600 : 660);
    auto job = parse_gcode(g, "creep.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto segs = make_step_segments(*job, m);
    ASSERT_TRUE(segs.ok()) << join(segs.errors);

    FeedOptions whole_window;
    whole_window.window_stop_factor = std::numeric_limits<double>::infinity();
    whole_window.max_lookahead_s = std::numeric_limits<double>::infinity();
    FeedStats ws, ds, cs;
    auto whole = plan_feeds(*segs.value, m, "creep.ngc", whole_window, &ws);
    auto by_default = plan_feeds(*segs.value, m, "creep.ngc", {}, &ds);
    FeedOptions bounded;
    bounded.max_lookahead_s = 0.25;
    auto cut = plan_feeds(*segs.value, m, "creep.ngc", bounded, &cs);
    ASSERT_TRUE(whole.ok() && by_default.ok() && cut.ok()) << join(cut.errors);
    const std::size_t n = segs->size();
    ASSERT_EQ(whole->size(), n);
    ASSERT_EQ(cut->size(), n);

    // The default bound (10 s) is not reached here: the whole-job plan.
    EXPECT_EQ(ds.cut_windows, 0u);
    EXPECT_GT(ds.max_lookahead_s, 0.5) << "the job must need a long lookahead to test the bound";
    for (std::size_t i = 0; i < n; ++i) expect_same_plan((*by_default)[i], (*whole)[i], i);

    // Cut: it looks past the span being planned no farther than the bound (or
    // the spans a group may cover: 64 here, 0.16 s) and one growth step of the
    // window (which covers at least the stopping distance from its highest cap:
    // 0.8 mm from 11 mm/s here, 0.07 s at the caps).
    EXPECT_GT(cs.cut_windows, 0u);
    EXPECT_LE(cs.max_lookahead_s, 0.25 + 0.1);
    double t = 0, v = 0, cut_end = 0, whole_end = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const PlannedSegment& p = (*cut)[i];
        ASSERT_GT(p.duration, 0) << "segment " << i;
        EXPECT_NEAR(p.t_start, t, 1e-9) << "segment " << i;
        EXPECT_NEAR(p.profile.v_entry, v, 1e-9) << "segment " << i;
        EXPECT_LE(p.profile.v_exit, p.cruise * (1 + 1e-9)) << "segment " << i;
        EXPECT_LE(p.profile.v_exit, (*whole)[i].profile.v_exit * (1 + 1e-9) + 1e-9) << "segment " << i;
        t = p.t_start + p.duration;
        v = p.profile.v_exit;
        cut_end = t;
        whole_end = (*whole)[i].t_start + (*whole)[i].duration;
    }
    EXPECT_NEAR(v, 0, 1e-9);
    EXPECT_GE(cut_end, whole_end * (1 - 1e-12));
    std::printf("lookahead %.2f s whole, %.2f s bounded at 0.25 s (%zu windows cut); planned %.3f s against %.3f s\n",
                ws.max_lookahead_s, cs.max_lookahead_s, cs.cut_windows, cut_end, whole_end);
}

TEST(FeedPlanner, ARefusedMoveStopsItsOutputAndEveryRefusedBlockIsNamed) {
    // Two moves beyond the card's step rate (planner.on_limit = "refuse"), with
    // moves within it around them: nothing is handed out past the first error,
    // and the second is named too.
    const Machine m = machine("refuse", 2000, "TB6600");
    auto job = parse_gcode("G1 X10 F600\nG1 X20\nG0 X200\nG1 X210 F600\nG0 X20\nG1 X10 F600\n", "job.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto segs = make_step_segments(*job, m);
    ASSERT_TRUE(segs.ok()) << join(segs.errors);
    FeedPlanner planner(m, "job.ngc");
    std::size_t out = 0;
    for (const StepSegment& s : *segs.value) {
        planner.push(s);
        while (planner.next()) ++out;
    }
    planner.finish();
    while (planner.next()) ++out;
    EXPECT_FALSE(planner.done());
    ASSERT_EQ(planner.errors().size(), 2u) << join(planner.errors());
    EXPECT_EQ(planner.errors()[0].loc.line, 3);
    EXPECT_EQ(planner.errors()[1].loc.line, 5);
    EXPECT_LE(out, 2u) << "segments from the refused move on were handed out";
    auto whole = plan_feeds(*segs.value, m, "job.ngc");
    EXPECT_FALSE(whole.ok());
    EXPECT_EQ(join(whole.errors), join(planner.errors()));
}

// The whole plan made as the blocks arrive: a zigzag of 3,000 turns with a
// conic arc every 20, short dwells, a dwell longer than one move interval (pause
// moves) and a trailing dwell, on a card with a conic walker. What comes out
// is plan_job()'s, in order, each card segment after its step segment, while
// the stream holds a window of the job.
TEST(PlanStream, PlansTheJobAsItsBlocksArriveHoldingAWindow) {
    Machine m = machine();
    m.card.conic_width = 40;  // as bind_card() sets it for a card with a walker (HX8K)
    m.card.max_moves = 1048575;
    m.card.pattern_capacity = 1024;
    std::string g = "G1 F1200 X10 Y10\n";
    double x = 10, y = 10;
    for (int i = 0; i < 3000; ++i) {
        g += fmt::format("G1 X{:.3f} Y{:.3f}\n", x += 0.5, y);
        g += fmt::format("G1 X{:.3f} Y{:.3f}\n", x, y += (i % 2 ? -3.0 : 3.0));
        if (i % 20 == 5) {
            g += fmt::format("G2 X{:.3f} Y{:.3f} I1.5 J0\n", x + 3, y);
            x += 3;
        }
        if (i % 250 == 9) g += "G4 P0.05\n";
        if (i == 1500) g += "G4 P200\n";
        if (x > 280) {
            g += "G0 X10\n";
            x = 10;
        }
    }
    g += "G4 P1\n";
    auto job = parse_gcode(g, "job.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto whole = plan_job(*job, m);
    ASSERT_TRUE(whole.ok()) << join(whole.errors);
    const PlannedJob& pj = *whole;
    EXPECT_GT(pj.stats.conic_arcs, 100u);
    EXPECT_GT(pj.stats.pause_moves, 1u);
    ASSERT_GT(pj.step_segments.size(), 6000u);

    PlanStream stream(m, "job.ngc");
    std::vector<StreamedStep> steps;
    std::vector<PlannedCardSegment> cards;
    std::size_t first_card_at = 0, max_held = 0;
    const auto drain = [&](std::size_t pushed) {
        for (;;) {
            while (auto s = stream.next_step()) steps.push_back(std::move(*s));
            auto c = stream.next_card();
            if (!c) return;
            if (!c->segment.pause) {
                ASSERT_LT(c->segment.step_segment, steps.size()) << "card segment " << cards.size();
            }
            if (cards.empty()) first_card_at = pushed;
            cards.push_back(std::move(*c));
        }
    };
    for (std::size_t b = 0; b < job->blocks.size(); ++b) {
        stream.push(job->blocks[b], b);
        drain(b + 1);
        max_held = std::max(max_held, stream.held());
    }
    stream.finish();
    drain(job->blocks.size());
    ASSERT_TRUE(stream.done()) << join(stream.errors());
    EXPECT_EQ(join(stream.warnings()), join(whole.warnings));

    ASSERT_EQ(steps.size(), pj.step_segments.size());
    for (std::size_t i = 0; i < steps.size(); ++i) {
        ASSERT_EQ(steps[i].index, i);
        ASSERT_EQ(steps[i].segment.start, pj.step_segments[i].start) << "step segment " << i;
        ASSERT_EQ(steps[i].segment.end, pj.step_segments[i].end) << "step segment " << i;
        ASSERT_EQ(steps[i].segment.conic, pj.step_segments[i].conic) << "step segment " << i;
        ASSERT_EQ(steps[i].feed.t_start, pj.feeds[i].t_start) << "step segment " << i;
    }
    ASSERT_EQ(cards.size(), pj.card.size());
    for (std::size_t c = 0; c < cards.size(); ++c) {
        const PlannedCardSegment& a = cards[c];
        const PlannedCardSegment& b = pj.card[c];
        ASSERT_EQ(a.segment.step_segment, b.segment.step_segment) << "card segment " << c;
        ASSERT_EQ(a.segment.delta, b.segment.delta) << "card segment " << c;
        ASSERT_EQ(a.segment.moves, b.segment.moves) << "card segment " << c;
        ASSERT_EQ(a.segment.pause, b.segment.pause) << "card segment " << c;
        ASSERT_EQ(a.chunks, b.chunks) << "card segment " << c;
        ASSERT_EQ(a.prev_event, b.prev_event) << "card segment " << c;
        ASSERT_EQ(a.conic != nullptr, b.conic != nullptr) << "card segment " << c;
        if (a.conic) {
            ASSERT_EQ(a.conic->moves, b.conic->moves) << "card segment " << c;
        }
    }
    EXPECT_EQ(stream.stats().moves, pj.stats.moves);
    EXPECT_EQ(stream.stats().chunks, pj.stats.chunks);
    EXPECT_EQ(stream.stats().pause_moves, pj.stats.pause_moves);
    EXPECT_EQ(stream.stats().duration_s, pj.stats.duration_s);

    // A window, not the job: the first card segments before a hundred blocks
    // are in, and at most some hundreds of step segments, feeds and points held.
    EXPECT_LT(first_card_at, 100u);
    EXPECT_LT(max_held, 2000u) << "of " << pj.step_segments.size() << " step segments";
    std::printf("first card segment after %zu of %zu blocks; at most %zu held (%zu step segments, %zu card segments, "
                "%llu conic arcs, %llu pause moves)\n",
                first_card_at, job->blocks.size(), max_held, pj.step_segments.size(), pj.card.size(),
                static_cast<unsigned long long>(pj.stats.conic_arcs),
                static_cast<unsigned long long>(pj.stats.pause_moves));
}

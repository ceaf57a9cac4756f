// SPDX-License-Identifier: MIT
// Arcs as CONIC card segments (host/plan/conic_arc.h, docs/PLANNING.md "Arcs as
// conics"): the planner's walks, judged here against the G-code's own circles (the
// test's centre and radius, not the planner's integers), the positions the card
// segments chain through, the moves' ideal times against the walker's pace, the
// pieces against the card's limits, the fallbacks to chords with their reasons,
// and the wire form against the walker's own rule.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "card/job.h"
#include "model/cp_conic.h"
#include "model/conic_oracle.h"
#include "model/cp_conic_serial.h"
#include "plan/pipeline.h"

using namespace cpstep;
using namespace cpstep::plan;

namespace {

constexpr unsigned kCiw = 40;

// One of the X and Y axes' sections (they differ only in the name).
std::string xy_axis(const char* name, double spm) {
    return fmt::format("[axes.{}]\nsteps_per_mm = {}\ntravel_min_mm = -300\ntravel_max_mm = 300\n"
                       "max_velocity_mm_s = 150\nmax_accel_mm_s2 = 1000\nmax_jerk_mm_s3 = 20000\n"
                       "driver = \"DM860T\"\n",
                       name, spm);
}

Machine machine(double spm_xy = 320, double spm_z = 320, const std::string& arcs = "conic") {
    const std::string text = fmt::format(R"([card]
clock_hz = 40e6
[planner]
arc_tolerance_mm = 0.005
arcs = "{2}"
{3}{4}[axes.z]
steps_per_mm = {1}
travel_min_mm = -300
travel_max_mm = 300
max_velocity_mm_s = 50
max_accel_mm_s2 = 500
max_jerk_mm_s3 = 10000
driver = "DM556"
)", spm_xy, spm_z, arcs, xy_axis("x", spm_xy), xy_axis("y", spm_xy));
    auto r = parse_machine(text, "m.toml");
    EXPECT_TRUE(r.ok()) << join(r.errors);
    Machine m = *r;
    m.card.conic_width = kCiw;  // as bind_card() sets it for a card with a walker (HX8K)
    m.card.max_moves = 1048575;
    m.card.pattern_capacity = 1024;
    return m;
}

PlannedJob plan_of(const std::string& gcode, const Machine& m, std::vector<Diagnostic>* warnings = nullptr) {
    auto job = parse_gcode(gcode, "job.ngc");
    EXPECT_TRUE(job.ok()) << join(job.errors);
    PlanOptions o;
    o.chunk_limits = card::chunk_limits();  // the card's chunk form, as run::prepare_job plans
    auto r = plan_job(*job, m, o);
    EXPECT_TRUE(r.ok()) << join(r.errors);
    if (warnings) *warnings = r.warnings;
    return r.ok() ? *r.value : PlannedJob{};
}

struct Circle {
    int u = 0, v = 1;       // axis indices
    double cu = 0, cv = 0;  // centre, mm
    double r = 0;           // radius, mm
};

// Walks every card segment of the job from its start: the positions chain, each
// conic's moves sum to its delta, each conic node's distance from `circles[n]` (the
// n-th conic arc of the job, in steps) is at most `bound(start distance)`, and the
// job ends at `end` (steps). Returns the largest node distance seen.
double walk_job(const PlannedJob& pj, const Machine& m, const std::vector<Circle>& circles, PerAxis<std::int64_t> end) {
    PerAxis<std::int64_t> pos = pj.step_segments.front().start;
    double worst = 0;
    std::size_t arc = 0;
    std::size_t last_step_segment = SIZE_MAX;
    double start_off = 0;
    for (const PlannedCardSegment& c : pj.card) {
        if (c.conic) {
            const ConicWalk& w = *c.conic;
            EXPECT_EQ(w.u0, pos[w.axis_u]);
            EXPECT_EQ(w.v0, pos[w.axis_v]);
            EXPECT_EQ(w.moves.size(), c.segment.moves);
            EXPECT_EQ(w.ideal.size(), c.segment.moves);
            if (c.segment.step_segment != last_step_segment) {
                ++arc;
                last_step_segment = c.segment.step_segment;
            }
            EXPECT_LE(arc, circles.size());
            const Circle& k = circles.at(arc - 1);
            EXPECT_EQ(k.u, w.axis_u);
            EXPECT_EQ(k.v, w.axis_v);
            const double s = m.axes[std::size_t(k.u)].steps_per_mm;
            const auto dist = [&](std::int64_t x, std::int64_t y) {
                return std::abs(std::hypot(double(x) / s - k.cu, double(y) / s - k.cv) - k.r) * s;
            };
            if (c.segment.first_move == 0) start_off = dist(w.u0, w.v0);
            // The walker keeps its nodes within half a step of its own circle: the
            // G-code's (its centre on the 1/16-step grid: 0.045 step), or the one
            // through the start node when the rounded start is off the walker's test.
            const double bound = 0.5 + 0.05 + std::max(0.0, start_off - 0.45);  // (the planner moves the radius by start_off - 0.45 at most)
            std::int64_t x = w.u0, y = w.v0;
            for (std::uint8_t mv : w.moves) {
                x += ConicWalk::dx_of(mv);
                y += ConicWalk::dy_of(mv);
                const double d = dist(x, y);
                worst = std::max(worst, d);
                EXPECT_LE(d, bound) << "node (" << x << ", " << y << ") of the conic arc " << arc;
            }
            EXPECT_EQ(x - w.u0, c.segment.delta[w.axis_u]);
            EXPECT_EQ(y - w.v0, c.segment.delta[w.axis_v]);
            EXPECT_EQ(w.du, c.segment.delta[w.axis_u]);
            EXPECT_EQ(w.dv, c.segment.delta[w.axis_v]);
            EXPECT_LE(c.segment.moves, m.card.max_moves);
        }
        for (int a = 0; a < kAxes; ++a) pos[a] += c.segment.delta[a];
    }
    EXPECT_EQ(arc, circles.size()) << "arcs walked as conics";
    EXPECT_EQ(pos, end);
    return worst;
}

PerAxis<std::int64_t> steps(double x, double y, double z, double s = 320, double sz = 320) {
    return {mm_to_steps(x, s), mm_to_steps(y, s), mm_to_steps(z, sz), 0};
}

}  // namespace

TEST(ConicArcs, QuarterArcsOfARoundedRectangleAreWalkedOnTheirCircles) {
    const Machine m = machine();
    const std::string g = "G21 G90 G17\nG0 X2 Y1\nG1 X6 F1800\nG3 X7 Y2 I0 J1\nG1 Y4\nG3 X6 Y5 I-1 J0\n"
                          "G1 X2\nG3 X1 Y4 I0 J-1\nG1 Y2\nG3 X2 Y1 I1 J0\n";
    std::vector<Diagnostic> warnings;
    const PlannedJob pj = plan_of(g, m, &warnings);
    EXPECT_EQ(pj.stats.conic_arcs, 4u);
    EXPECT_EQ(pj.stats.chord_arcs, 0u);
    EXPECT_TRUE(warnings.empty()) << join(warnings);
    const std::vector<Circle> circles = {{0, 1, 6, 2, 1}, {0, 1, 6, 4, 1}, {0, 1, 2, 4, 1}, {0, 1, 2, 2, 1}};
    const double worst = walk_job(pj, m, circles, steps(2, 1, 0));
    EXPECT_LE(worst, 0.55);
    // Each quarter of radius 320 steps: about 320 (2 - sqrt 2/2) ... 320 * sqrt 2 moves, half
    // of them combined; far fewer card segments than its chords.
    std::size_t conics = 0;
    for (const PlannedCardSegment& c : pj.card) conics += c.conic != nullptr;
    EXPECT_EQ(conics, 4u);
}

TEST(ConicArcs, MovesAreTimedOnTheFeedAndNeverFasterThanTheWalker) {
    const Machine m = machine();
    const PlannedJob pj = plan_of("G21 G90 G17\nG0 X10 Y0\nG3 X-10 Y0 I-10 J0 F6000\nG2 X-30 Y0 I-10 J0\n", m);
    ASSERT_EQ(pj.stats.conic_arcs, 2u);
    const double gap = double(conic_gap_cycles(kCiw));
    const double tol = m.chunk_tolerance_cycles();
    double last_conic = -1e300;
    const std::vector<double> ideal = ideal_times(pj, m.card.clock_hz);
    std::size_t k = 0;
    std::int64_t prev = 0;
    for (const PlannedCardSegment& c : pj.card) {
        const std::vector<std::int64_t> real = expand(c.chunks, prev);
        if (!real.empty()) prev = real.back();
        if (c.segment.pause) continue;
        if (c.conic) {
            const auto& t = c.conic->ideal;
            EXPECT_GE(t.front() - tol - last_conic, gap);
            for (std::size_t j = 1; j < t.size(); ++j) EXPECT_GE(t[j] - t[j - 1], gap) << "move " << j;
            // The chunks realize the ideal times: never late, at most the tolerance early.
            ASSERT_EQ(real.size(), t.size());
            for (std::size_t j = 0; j < t.size(); ++j) {
                EXPECT_LE(double(real[j]), t[j] + 1e-6);
                EXPECT_GE(double(real[j]), t[j] - tol - 1e-6);
            }
            last_conic = t.back();
        }
        for (std::size_t j = 0; j < c.segment.moves; ++j, ++k)
            if (c.conic) {
                EXPECT_EQ(ideal[k], c.conic->ideal[j]);
            }
    }
    // The arcs' last moves are their last chords' ends: the feed plan's times.
    for (std::size_t c = 0; c + 1 < pj.card.size() + 1; ++c) {
        if (!pj.card[c].conic || (c + 1 < pj.card.size() && pj.card[c + 1].segment.step_segment == pj.card[c].segment.step_segment))
            continue;
        std::size_t e = pj.card[c].segment.step_segment;
        while (e + 1 < pj.step_segments.size() && pj.step_segments[e + 1].block == pj.step_segments[e].block) ++e;
        EXPECT_NEAR(pj.card[c].conic->ideal.back(), (pj.feeds[e].t_start + pj.feeds[e].duration) * m.card.clock_hz, 1e-3);
    }
    EXPECT_EQ(k, ideal.size());
    // Two half circles of 3,200 steps: the speed along the arc is the feed's, 6,000
    // mm/min = 100 mm/s (v^2/r = 1000 mm/s^2: the planner's cap), so the duration is
    // at least the length over the speed.
    EXPECT_GE(pj.stats.duration_s, 2 * std::numbers::pi * 10 / 100);
}

TEST(ConicArcs, AFullCircleEndsWhereItStarts) {
    const Machine m = machine();
    const PlannedJob pj = plan_of("G21 G90 G17\nG0 X25 Y0\nG2 X25 Y0 I-12.5 J0 F3000\n", m);
    ASSERT_EQ(pj.stats.conic_arcs, 1u);
    walk_job(pj, m, {{0, 1, 12.5, 0, 12.5}}, steps(25, 0, 0));
    std::uint64_t moves = 0;
    for (const PlannedCardSegment& c : pj.card)
        if (c.conic) moves += c.segment.moves;
    // A circle of radius r steps in max-norm moves: 4 r sqrt 2 nodes, give or take.
    const double r = 12.5 * 320;
    EXPECT_NEAR(double(moves), 4 * r * std::sqrt(2.0), 8);
}

// The length rule a phase-timer card applies to time a conic's moves by their path
// (plan::conic_rule_divisors, docs/CONIC.md §10): each move's divisor is the walker's
// gradient's larger component at the node it leaves, here 2A times the node's larger
// coordinate from the centre (the test's circle, centred on the origin); the
// moves' lengths on the path are K 2^S / m_n; along each octant they follow the arc
// where it passes each node on the axis the octant steps every move, within the
// left-point sum's error: half the change of 1 / m over the octant, r (√2 − 1) / 2
// = 0.21 steps (the ratio of the last node's to the first's 1 / m is at most √2).
TEST(ConicArcs, TheLengthRuleFollowsTheArcWithinEachOctant) {
    const Machine m = machine();
    auto job = parse_gcode("G21 G90 G17\nG0 X3.125 Y0\nG3 X0 Y3.125 I-3.125 J0 F600\n", "job.ngc");
    ASSERT_TRUE(job.ok()) << join(job.errors);
    PlanOptions o;
    o.chunk_limits = card::chunk_limits();
    o.conic_length_rule = true;
    std::vector<std::vector<double>> batches;
    o.on_move_times = [&](std::span<const double>, std::span<const double> lengths, double, std::span<const PlanJerk>) {
        batches.emplace_back(lengths.begin(), lengths.end());
    };
    auto r = plan_job(*job, m, o);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    const PlannedJob& pj = *r;
    ASSERT_EQ(pj.stats.conic_arcs, 1u);
    ASSERT_EQ(batches.size(), pj.card.size());
    const double radius = 1000;   // steps
    double k = 0, rule = 0;       // lengths * D (mm), the rule's path in steps (unscaled)
    double octant_start_rule = -1, octant_start_arc = 0, worst_in_octant = 0;
    std::int64_t x = 1000, y = 0;
    const auto big = [](std::int64_t px, std::int64_t py) { return std::max(std::abs(px), std::abs(py)); };
    std::uint64_t moves = 0;
    for (std::size_t c = 0; c < pj.card.size(); ++c) {
        if (!pj.card[c].conic) continue;
        const ConicWalk& w = *pj.card[c].conic;
        ASSERT_EQ(w.a, w.c);
        ASSERT_EQ(w.b, 0);
        const std::vector<std::uint64_t> d = conic_rule_divisors(w);
        ASSERT_EQ(d.size(), w.moves.size());
        ASSERT_EQ(batches[c].size(), w.moves.size());
        EXPECT_EQ(w.u0, x);
        EXPECT_EQ(w.v0, y);
        for (std::size_t n = 0; n < w.moves.size(); ++n, ++moves) {
            const std::int64_t x1 = x + ConicWalk::dx_of(w.moves[n]), y1 = y + ConicWalk::dy_of(w.moves[n]);
            const std::int64_t expect = 2 * w.a * big(x, y);
            ASSERT_EQ(d[n], std::uint64_t(expect)) << "move " << moves;
            // The hook's lengths are the rule's: length * D the same for every move.
            const double kn = batches[c][n] * double(expect);
            if (k == 0) k = kn;
            EXPECT_NEAR(kn / k, 1.0, 1e-9) << "move " << moves;
            // Unscaled: ds/d(major) = r / (the larger coordinate), at the node left.
            rule += 2.0 * double(w.a) * radius / double(expect);
            // Where the arc passes the node on the axis the octant steps every move.
            const bool y_major = std::abs(x1) > std::abs(y1) + 1, x_major = std::abs(y1) > std::abs(x1) + 1;
            const double arc = y_major ? radius * std::asin(double(y1) / radius)
                                       : radius * std::acos(std::clamp(double(x1) / radius, -1.0, 1.0));
            if (y_major) worst_in_octant = std::max(worst_in_octant, std::abs(rule - arc));
            if (x_major) {
                if (octant_start_rule < 0) octant_start_rule = rule, octant_start_arc = arc;
                worst_in_octant =
                    std::max(worst_in_octant, std::abs((rule - octant_start_rule) - (arc - octant_start_arc)));
            }
            x = x1;
            y = y1;
        }
    }
    EXPECT_EQ(x, 0);
    EXPECT_EQ(y, 1000);
    std::printf("quarter circle r = 1000 steps: %llu moves, the rule within each octant within %.4f steps, "
                "its whole %.4f steps from r pi / 2; moves shifted by up to %.4f steps of path\n",
                static_cast<unsigned long long>(moves), worst_in_octant, rule - radius * std::numbers::pi / 2,
                pj.stats.conic_rule_shift_steps);
    EXPECT_LT(worst_in_octant, 0.5 * (std::sqrt(2.0) - 1) + 0.05);
    EXPECT_NEAR(rule, radius * std::numbers::pi / 2, 0.6);
    // Against the planner's own timing, which measures each octant on its own axis
    // and so jumps where the octant changes (a node off the circle by d passes on
    // the two axes up to d sqrt 2 apart): within that.
    EXPECT_LT(pj.stats.conic_rule_shift_steps, 0.5 * std::sqrt(2.0));
    EXPECT_GT(pj.stats.conic_rule_shift_steps, 0.0);
}

TEST(ConicArcs, TheRFormIsTheSameCircle) {
    // G2 with R 5 from (0, 0) to (10, 0): the half circle about (5, 0); then G3 R 5 to
    // (20, 0): the half circle about (15, 0).
    const Machine m = machine();
    const PlannedJob pj = plan_of("G21 G90 G17\nG0 X0 Y0\nG2 X10 Y0 R5 F2000\nG3 X20 Y0 R5\n", m);
    EXPECT_EQ(pj.stats.conic_arcs, 2u);
    walk_job(pj, m, {{0, 1, 5, 0, 5}, {0, 1, 15, 0, 5}}, steps(20, 0, 0));
}

TEST(ConicArcs, ArcsInEveryPlaneAndBothSenses) {
    const Machine m = machine();
    const std::string g = "G21 G90\nG0 X0 Y0 Z0\nG17 G2 X10 Y10 I10 J0 F2000\nG3 X20 Y0 I0 J-10\n"
                          "G18 G2 X30 Z10 I5 K5\nG3 X40 Z0 I5 K-5\nG19 G2 Y10 Z10 J5 K5\nG3 Y20 Z0 J5 K-5\n";
    std::vector<Diagnostic> warnings;
    const PlannedJob pj = plan_of(g, m, &warnings);
    EXPECT_EQ(pj.stats.conic_arcs, 6u);
    EXPECT_TRUE(warnings.empty()) << join(warnings);
    // G18's arc frame is (Z, X), G19's (Y, Z) (RS274NGC: counter-clockwise seen from +Y, +X).
    const std::vector<Circle> circles = {{0, 1, 10, 0, 10},  {0, 1, 10, 0, 10}, {2, 0, 5, 25, std::hypot(5.0, 5.0)},
                                         {2, 0, 5, 35, std::hypot(5.0, 5.0)}, {1, 2, 5, 5, std::hypot(5.0, 5.0)},
                                         {1, 2, 15, 5, std::hypot(5.0, 5.0)}};
    walk_job(pj, m, circles, steps(40, 20, 0));
}

TEST(ConicArcs, AHelixStepsItsThirdAxisWithinHalfAStepInPiecesTheCardsPatternsHold) {
    const Machine m = machine();
    std::vector<Diagnostic> warnings;
    const PlannedJob pj = plan_of("G21 G90 G17\nG0 X20 Y0 Z0\nG3 X20 Y0 Z3 I-20 J0 F1200\n", m, &warnings);
    ASSERT_EQ(pj.stats.conic_arcs, 1u) << join(warnings);
    walk_job(pj, m, {{0, 1, 0, 0, 20}}, steps(20, 0, 3));
    // The test's own helix: z rises with the angle swept, 3 mm over the turn.
    std::size_t pieces = 0, last = 0;
    for (std::size_t c = 0; c < pj.card.size(); ++c)
        if (pj.card[c].conic) last = c;
    double worst = 0;
    std::int64_t z = 0;
    for (std::size_t ci = 0; ci < pj.card.size(); ++ci) {
        const PlannedCardSegment& c = pj.card[ci];
        if (!c.conic) continue;
        ++pieces;
        EXPECT_LE(c.segment.moves, m.card.pattern_capacity);
        const ConicWalk& w = *c.conic;
        std::int64_t x = w.u0, y = w.v0;
        const std::int64_t dz = c.segment.delta[2];
        ASSERT_GE(dz, 0);
        ASSERT_LE(std::uint64_t(dz), c.segment.moves);
        EXPECT_EQ(c.segment.v[2], std::uint32_t(dz));
        for (std::size_t j = 1; j <= w.moves.size(); ++j) {
            x += ConicWalk::dx_of(w.moves[j - 1]);
            y += ConicWalk::dy_of(w.moves[j - 1]);
            // The card's z after move j of T: floor((2 v j + T) / (2 T)) (docs/CORE.md).
            const std::int64_t zc = z + std::int64_t((2 * std::uint64_t(dz) * j + c.segment.moves) / (2 * c.segment.moves));
            double ang = std::atan2(double(y), double(x));
            if (ang < 0) ang += 2 * std::numbers::pi;
            if (j == w.moves.size() && ci == last) ang = 2 * std::numbers::pi;
            worst = std::max(worst, std::abs(double(zc) - 960.0 * ang / (2 * std::numbers::pi)));
        }
        z += dz;
    }
    EXPECT_GT(pieces, 1u) << "a turn of radius 6,400 steps is longer than W = 1024 moves";
    // The planner's own figure is the worst it measured, and the split it chose keeps
    // Z within 0.55 step of the helix (0.522 measured; a GCD split of a line allows up
    // to a step where no closer lattice points exist).
    EXPECT_NEAR(worst, pj.stats.conic.max_other_deviation, 1e-6);
    EXPECT_LE(worst, 0.55);
}

TEST(ConicArcs, ChordsWhenAskedWhenTheCardHasNoWalkerOrTheArcDoesNotQualify) {
    const std::string g = "G21 G90 G17\nG0 X10 Y0\nG3 X-10 Y0 I-10 J0 F3000\n";
    // planner.arcs = "chords": no conics, no warning.
    std::vector<Diagnostic> w;
    PlannedJob pj = plan_of(g, machine(320, 320, "chords"), &w);
    EXPECT_EQ(pj.stats.conic_arcs, 0u);
    EXPECT_TRUE(w.empty()) << join(w);
    // A card without a walker: chords, counted, no warning.
    Machine m = machine();
    m.card.conic_width = 0;
    pj = plan_of(g, m, &w);
    EXPECT_EQ(pj.stats.conic_arcs, 0u);
    EXPECT_EQ(pj.stats.chord_arcs, 1u);
    EXPECT_TRUE(w.empty()) << join(w);
    // Steps/mm whose squares' ratio no 16-bit coefficients hold: chords, with the reason.
    Machine uneq = machine();
    uneq.axes[0].steps_per_mm = 400;
    uneq.axes[1].steps_per_mm = 2;  // (400 / 2)^2 = 40000: above 16 bits
    pj = plan_of("G21 G90 G17\nG0 X10 Y0\nG3 X-10 Y0 I-10 J0 F300\n", uneq, &w);
    EXPECT_EQ(pj.stats.conic_arcs, 0u);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_NE(w[0].message.find("ratio"), std::string::npos) << w[0].message;
    EXPECT_EQ(w[0].loc.line, 3);
    // A radius of a step or two: chords.
    pj = plan_of("G21 G90 G17\nG0 X0.01 Y0\nG3 X-0.01 Y0 I-0.01 J0 F300\n", machine(), &w);
    EXPECT_EQ(pj.stats.conic_arcs, 0u);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_NE(w[0].message.find("radius"), std::string::npos) << w[0].message;
    // Each way the job ends at the same steps.
    for (const PlannedJob& j : {plan_of(g, machine()), plan_of(g, machine(320, 320, "chords"))}) {
        PerAxis<std::int64_t> pos = j.step_segments.front().start;
        for (const PlannedCardSegment& c : j.card)
            for (int a = 0; a < kAxes; ++a) pos[a] += c.segment.delta[a];
        EXPECT_EQ(pos, steps(-10, 0, 0));
    }
}

// Unequal steps/mm in the plane (seed002.toml's 80 on X and 400 on Z): the G-code's
// circle is an ellipse in steps, walked as one (C / A = 1/25 exactly). Every node's
// distance from that ellipse in steps, by the untimed oracle's nearest point (not the
// planner's first-order figure), within 0.55 step; the walk ends where the G-code does.
TEST(ConicArcs, UnequalStepsPerMmAreEllipsesInSteps) {
    const Machine m = machine(80, 400);
    std::vector<Diagnostic> warnings;
    const PlannedJob pj = plan_of("G21 G90\nG0 X3 Y0 Z0\nG18 G2 X3 Z0 I-3 K0 F1200\nG2 X-3 Z0 I-3 K0\n"
                                  "G17 G3 X3 Y0 I3 J0\nG0 X0\n", m, &warnings);
    EXPECT_EQ(pj.stats.conic_arcs, 3u) << join(warnings);
    double worst = 0;
    std::size_t ellipses = 0;
    PerAxis<std::int64_t> pos = pj.step_segments.front().start;
    for (const PlannedCardSegment& c : pj.card) {
        if (c.conic) {
            const ConicWalk& w = *c.conic;
            const double su = m.axes[std::size_t(w.axis_u)].steps_per_mm, sv = m.axes[std::size_t(w.axis_v)].steps_per_mm;
            EXPECT_EQ(w.u0, pos[w.axis_u]);
            EXPECT_EQ(w.v0, pos[w.axis_v]);
            // The G-code circle about (0, 0) mm, radius 3, in steps: (x/su)^2 + (y/sv)^2 = 9.
            const oracle::Conic curve{1.0L / (su * su), 0, 1.0L / (sv * sv), 0, 0, -9};
            if (su != sv) {
                ++ellipses;
                EXPECT_EQ(double(w.c) * sv * sv, double(w.a) * su * su) << "C / A = (su / sv)^2, exactly";
            }
            std::int64_t x = w.u0, y = w.v0;
            for (std::uint8_t mv : w.moves) {
                x += ConicWalk::dx_of(mv);
                y += ConicWalk::dy_of(mv);
                const double d = double(oracle::nearest(curve, x, y).distance);
                worst = std::max(worst, d);
                EXPECT_LE(d, 0.55) << "node (" << x << ", " << y << ")";
            }
        }
        for (int a = 0; a < kAxes; ++a) pos[a] += c.segment.delta[a];
    }
    EXPECT_EQ(ellipses, 2u) << "the G18 arcs (Z, X): ellipses; the G17 arc a circle";
    EXPECT_EQ(pos, (PerAxis<std::int64_t>{0, 0, 0, 0}));
    std::printf("ellipse and circle nodes: within %.4f step of the G-code's curves in steps\n", worst);
}

TEST(ConicArcs, MachineFileArcsKeyIsCheckedWithItsPlace) {
    const auto r = parse_machine("[planner]\narcs = \"splines\"\n[axes.x]\nsteps_per_mm = 80\ntravel_min_mm = 0\n"
                                 "travel_max_mm = 100\nmax_velocity_mm_s = 10\nmax_accel_mm_s2 = 100\n"
                                 "max_jerk_mm_s3 = 1000\ndriver = \"TMC2209\"\n",
                                 "m.toml");
    ASSERT_FALSE(r.ok());
    ASSERT_EQ(r.errors.size(), 1u);
    EXPECT_EQ(r.errors[0].loc.line, 2);
    EXPECT_NE(r.errors[0].message.find("planner.arcs"), std::string::npos) << r.errors[0].message;
}

// The wire: each CONIC's seven words, loaded into the walker's rule (the model's, as
// the card runs it), walk exactly the planned moves and end on the last; a conic
// whose chunks outnumber the card's queue is cut into conics that restart at the node
// where the cut falls.
TEST(ConicArcs, WireWordsWalkThePlannedMovesAndCutsRestartAtTheirNode) {
    const Machine m = machine();
    const PlannedJob pj = plan_of("G21 G90 G17\nG0 X30 Y0\nG3 X-30 Y0 I-30 J0 F1800\nG3 X30 Y0 I30 J0\n", m);
    ASSERT_EQ(pj.stats.conic_arcs, 2u);
    std::size_t conics_at_64 = 0;
    for (unsigned queue : {64u, 4u}) {
        card::CardLimits lim;
        lim.chunk_queue = queue;
        const auto wire = card::to_wire(pj, "job.ngc", lim);
        ASSERT_TRUE(wire.ok()) << join(wire.errors);
        std::size_t conics = 0;
        std::vector<std::uint8_t> walked, planned;
        for (const PlannedCardSegment& c : pj.card)
            if (c.conic) planned.insert(planned.end(), c.conic->moves.begin(), c.conic->moves.end());
        const card::WireSegment* prev = nullptr;
        for (const card::WireSegment& w : wire->segments) {
            // A cut piece continues the walk of the one before it (H0[18]): that one is
            // a CONIC on the same axes, the same way; each arc's first piece is not.
            if (w.conic && w.conic->cont) {
                ASSERT_TRUE(prev && prev->conic) << "a continuation after no CONIC";
                EXPECT_EQ(prev->conic->axis_u, w.conic->axis_u);
                EXPECT_EQ(prev->conic->axis_v, w.conic->axis_v);
                EXPECT_EQ(prev->conic->cw, w.conic->cw);
            }
            prev = &w;
            if (!w.conic) continue;
            ++conics;
            EXPECT_LE(w.chunks.size(), queue);
            const auto& k = w.conic->words;
            // K0 = B, A; K1 = C; K2..K4 = G, Gx, Gy (32 bits); K5, K6 = du, dv (24 bits).
            const model::CpConic::Coeffs co{std::int16_t(k[0] & 0xFFFF), std::int16_t(k[0] >> 16),
                                            std::int16_t(k[1] & 0xFFFF), 0, 0, 0};
            model::CpConic::Node n{std::int32_t(k[2]), std::int32_t(k[3]), std::int32_t(k[4])};
            const auto s24 = [](std::uint32_t x) { return std::int32_t(x << 8) >> 8; };
            std::int64_t du = s24(k[5]), dv = s24(k[6]);
            for (std::uint32_t j = 0; j < w.u; ++j) {
                int dx = 0, dy = 0;
                model::CpConicSerial::rule(co, n, w.conic->cw, kCiw, dx, dy);
                n = model::CpConic::advance(co, n, dx, dy);
                du -= dx;
                dv -= dy;
                walked.push_back(ConicWalk::pack(dx, dy));
                EXPECT_EQ(du == 0 && dv == 0, j + 1 == w.u) << "the walk's end mark at move " << j + 1 << " of " << w.u;
            }
        }
        EXPECT_EQ(walked, planned) << "chunk queue " << queue;
        // Two arcs: two whole CONICs, the rest continuations (5 words shorter each).
        std::size_t whole = 0;
        for (const card::WireSegment& w : wire->segments) whole += w.conic && !w.conic->cont;
        EXPECT_EQ(whole, 2u) << "chunk queue " << queue;
        const auto words = card::encode_job(m, *wire);
        std::size_t k_words = 0;
        for (std::size_t i = 0; i < words.size(); i += card::command_words(words[i], kAxes))
            if (words[i] >> 28 == 0x5) k_words += (words[i] >> 18 & 1) ? 2 : 7;
        EXPECT_EQ(k_words, 2 * 7 + (conics - 2) * 2) << "chunk queue " << queue;
        EXPECT_GE(conics, 2u);
        if (queue == 64) conics_at_64 = conics;
        else EXPECT_GT(conics, conics_at_64) << "cut at the chunk queue";
    }
}

// Random arcs (centre, radius, sweep, sense, plane offsets) on a machine of 80 and of
// 320 steps/mm: every one walked as a conic within the bound, the job ending where the
// G-code does.
TEST(ConicArcs, RandomArcsStayOnTheirCircles) {
    std::mt19937 rng(20261127);
    std::uniform_real_distribution<double> uni(0, 1);
    for (double spm : {80.0, 320.0}) {
        const Machine m = machine(spm, spm);
        for (int t = 0; t < 40; ++t) {
            const double r = 0.5 + 40 * uni(rng), cx = -100 + 200 * uni(rng), cy = -100 + 200 * uni(rng);
            const double a0 = 2 * std::numbers::pi * uni(rng), sweep = 0.2 + 6 * uni(rng);
            const bool cw = uni(rng) < 0.5;
            const double a1 = a0 + (cw ? -sweep : sweep);
            const double x0 = cx + r * std::cos(a0), y0 = cy + r * std::sin(a0);
            const double x1 = cx + r * std::cos(a1), y1 = cy + r * std::sin(a1);
            // (A rapid after it: an arc the job ends on must end on its rounded end step,
            // which the walk passes 9 times in 10; otherwise it is chords.)
            const std::string g = fmt::format("G21 G90 G17\nG0 X{:.6f} Y{:.6f}\n{} X{:.6f} Y{:.6f} I{:.6f} J{:.6f} F2400\nG0 X0 Y0\n",
                                              x0, y0, cw ? "G2" : "G3", x1, y1, cx - x0, cy - y0);
            SCOPED_TRACE(g);
            std::vector<Diagnostic> w;
            const PlannedJob pj = plan_of(g, m, &w);
            EXPECT_EQ(pj.stats.conic_arcs, 1u) << join(w);
            if (pj.stats.conic_arcs != 1) continue;
            walk_job(pj, m, {{0, 1, cx, cy, r}}, steps(0, 0, 0, spm, spm));
        }
    }
}

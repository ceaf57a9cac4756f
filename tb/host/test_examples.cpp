// SPDX-License-Identifier: MIT
// The whole pipeline on the shipped examples: every job plans on every
// machine whose travel holds it, and the output keeps the card's rules.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <limits>
#include <regex>
#include <string>

#include "cpstep/builds.h"
#include "plan/pipeline.h"
#include "plan/steptime.h"

using namespace cpstep::plan;

namespace {

const std::string kDir = CPSTEP_EXAMPLES_DIR;

void check_plan(const PlannedJob& pj, const Machine& m) {
    const double tol = m.chunk_tolerance_cycles();
    std::int64_t prev = 0;
    PerAxis<std::int64_t> pos = pj.step_segments.empty() ? PerAxis<std::int64_t>{}
                                                          : pj.step_segments.front().start;
    std::size_t last_seg = SIZE_MAX;
    std::uint64_t total = 0;
    std::vector<double> all_ideal;  // every move's ideal time, from each step segment's own T
    for (const auto& c : pj.card) {
        const auto& seg = pj.step_segments[c.segment.step_segment];
        const auto& feed = pj.feeds[c.segment.step_segment];
        std::uint64_t T = 0;
        for (auto d : seg.delta()) T = std::max<std::uint64_t>(T, static_cast<std::uint64_t>(std::llabs(d)));
        std::uint64_t sum = 0;
        for (const auto& ch : c.chunks) sum += ch.count;
        ASSERT_EQ(sum, c.segment.moves);
        const auto ideal = ideal_move_times(feed, T, c.segment.first_move, c.segment.moves, m.card.clock_hz);
        for (double x : ideal) {
            // Ideal move times strictly increase through the job.
            if (!all_ideal.empty()) { ASSERT_GT(x, all_ideal.back()); }
            all_ideal.push_back(x);
        }
        const auto real = expand(c.chunks, prev);
        for (std::size_t i = 0; i < real.size(); ++i) {
            ASSERT_GT(real[i], i ? real[i - 1] : prev);
            ASSERT_LE(static_cast<double>(real[i]), ideal[i]);
            ASSERT_GE(static_cast<double>(real[i]), ideal[i] - tol);
        }
        prev = real.back();
        for (std::size_t a = 0; a < kAxes; ++a) {
            ASSERT_LE(c.segment.u[a], m.card.pattern_capacity);
            pos[a] += c.segment.delta[a];
        }
        if (c.segment.step_segment != last_seg) {
            // A new step segment starts exactly where the card stands.
            PerAxis<std::int64_t> before = pos;
            for (std::size_t a = 0; a < kAxes; ++a) before[a] -= c.segment.delta[a];
            ASSERT_EQ(seg.start, before);
        }
        last_seg = c.segment.step_segment;
        total += c.segment.moves;
    }
    EXPECT_EQ(total, pj.stats.moves);
    EXPECT_EQ(ideal_times(pj, m.card.clock_hz), all_ideal);
    if (!pj.step_segments.empty()) { EXPECT_EQ(pos, pj.step_segments.back().end); }
}

// The feed plan's timeline: each segment starts where the previous one ends
// (t_start = previous t_start + duration, exactly as the pipeline adds them),
// every segment with length takes time, and no axis averages more than its
// own velocity limit over a segment (from the G-code's unrounded geometry and
// the machine file's limits, not from the planner's projections).
void check_timeline(const std::vector<StepSegment>& segs, const std::vector<PlannedSegment>& feeds,
                    const Machine& m) {
    ASSERT_EQ(segs.size(), feeds.size());
    double t = 0;
    for (std::size_t i = 0; i < feeds.size(); ++i) {
        const auto& f = feeds[i];
        ASSERT_EQ(f.t_start, t) << "segment " << i << " at " << segs[i].loc.line;
        ASSERT_GE(f.duration, 0) << i;
        if (segs[i].kind == MotionKind::dwell) {
            ASSERT_EQ(f.duration, segs[i].dwell_s) << i;
        } else {
            ASSERT_GT(f.duration, 0) << "segment " << i << " at line " << segs[i].loc.line;
            for (std::size_t a = 0; a < kAxes; ++a) {
                if (!m.axes[a].present) continue;
                const double d_mm = std::abs(static_cast<double>(segs[i].delta()[a])) / m.axes[a].steps_per_mm;
                ASSERT_LE(d_mm / f.duration, m.axes[a].max_velocity * (1 + 1e-9))
                    << "segment " << i << " axis " << a << " at line " << segs[i].loc.line;
            }
        }
        t = f.t_start + f.duration;
    }
}

// The ideal move times of consecutive step segments: strictly increasing
// across every segment boundary, by at least one card cycle between the last
// move of a segment and the first of the next that moves (what the chunk
// compressor needs: a delay of at least one cycle).
void check_boundaries(const PlannedJob& pj, const Machine& m) {
    double last = -1;
    std::size_t last_seg = SIZE_MAX;
    for (std::size_t i = 0; i < pj.step_segments.size(); ++i) {
        const auto& s = pj.step_segments[i];
        if (s.kind == MotionKind::dwell) continue;
        std::uint64_t T = 0;
        for (auto d : s.delta()) T = std::max<std::uint64_t>(T, static_cast<std::uint64_t>(std::llabs(d)));
        if (T == 0) continue;
        const auto first = ideal_move_times(pj.feeds[i], T, 0, 1, m.card.clock_hz);
        const auto end = ideal_move_times(pj.feeds[i], T, T - 1, 1, m.card.clock_hz);
        if (last >= 0) {
            ASSERT_GT(first[0], last + 1) << "segment " << i << " (line " << s.loc.line
                                          << ") after segment " << last_seg;
        }
        ASSERT_GE(end[0], first[0]) << i;
        last = end[0];
        last_seg = i;
    }
}

}  // namespace


Machine bound_machine(const std::string& file) {
    auto loaded = load_machine(kDir + "/machines/" + file);
    EXPECT_TRUE(loaded.ok()) << join(loaded.errors);
    const cpstep::builds::Build& b = *cpstep::builds::find(cpstep::builds::kDefaultBoard);
    Machine m = *loaded;
    const auto errs = bind_card(m, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw});
    EXPECT_TRUE(errs.empty()) << join(errs);
    return m;
}

// Every example job with the machine it runs on.
const auto kExampleJobs =
    ::testing::Values(std::pair{"seed002.toml", "bracket.ngc"}, std::pair{"seed002.toml", "plasma.ngc"},
                      std::pair{"seed002.toml", "dense.ngc"}, std::pair{"router.toml", "bracket.ngc"},
                      std::pair{"plotter.toml", "plasma.ngc"}, std::pair{"plotter.toml", "bracket.ngc"},
                      std::pair{"seed002.toml", "tab.ngc"}, std::pair{"seed002.toml", "tight_arcs.ngc"},
                      std::pair{"seed002.toml", "naca0025.ngc"});

std::string example_name(const ::testing::TestParamInfo<std::pair<const char*, const char*>>& p) {
    std::string n = std::string(p.param.first) + "_" + p.param.second;
    for (auto& ch : n) if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return n;
}

class Examples : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(Examples, PlansWithinTheCardsRules) {
    auto loaded = load_machine(kDir + "/machines/" + GetParam().first);
    ASSERT_TRUE(loaded.ok()) << join(loaded.errors);
    // Planned for the default board's card (rtl/builds.json), as `cpstep plan` does.
    const cpstep::builds::Build& b = *cpstep::builds::find(cpstep::builds::kDefaultBoard);
    Machine bound = *loaded;
    const auto bind_errors = bind_card(bound, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw});
    ASSERT_TRUE(bind_errors.empty()) << join(bind_errors);
    const Machine* m = &bound;
    auto job = load_gcode(kDir + "/jobs/" + GetParam().second);
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto plan = plan_job(*job, *m);
    ASSERT_TRUE(plan.ok()) << join(plan.errors);
    EXPECT_GT(plan->stats.moves, 1000u);
    check_plan(*plan.value, *m);
    check_timeline(plan->step_segments, plan->feeds, *m);
    check_boundaries(*plan.value, *m);
}

INSTANTIATE_TEST_SUITE_P(All, Examples, kExampleJobs, example_name);

class ExampleFeeds : public ::testing::TestWithParam<std::pair<const char*, const char*>> {
protected:
    void SetUp() override {
        m = bound_machine(GetParam().first);
        auto job = load_gcode(kDir + "/jobs/" + GetParam().second);
        ASSERT_TRUE(job.ok()) << join(job.errors);
        auto s = make_step_segments(*job, m);
        ASSERT_TRUE(s.ok()) << join(s.errors);
        segs = *s.value;
        auto f = plan_feeds(segs, m, "job");
        ASSERT_TRUE(f.ok()) << join(f.errors);
        feeds = *f.value;
    }
    Machine m;
    std::vector<StepSegment> segs;
    std::vector<PlannedSegment> feeds;
    void PerAxisKinematicsWithinLimitsAlongThePath_Body();
};

// No plan is faster than the bound from the limits along its path.
TEST_P(ExampleFeeds, PlannedTimeIsAtLeastTheLowerBound) {
    const double planned = feeds.back().t_start + feeds.back().duration;
    EXPECT_GE(planned, time_lower_bound(segs, m));
}

// The lookahead window changes nothing: the same job planned in one window. No
// example job's lookahead reaches its time bound (FeedOptions::max_lookahead_s).
TEST_P(ExampleFeeds, StreamingWindowGivesTheWholeJobPlan) {
    FeedStats st;
    ASSERT_TRUE(plan_feeds(segs, m, "job", {}, &st).ok());
    EXPECT_EQ(st.cut_windows, 0u);
    EXPECT_LT(st.max_lookahead_s, FeedOptions::kDefaultMaxLookaheadS);
    FeedOptions whole;
    whole.window_stop_factor = std::numeric_limits<double>::infinity();
    whole.max_lookahead_s = std::numeric_limits<double>::infinity();
    auto w = plan_feeds(segs, m, "job", whole);
    ASSERT_TRUE(w.ok());
    ASSERT_EQ(w->size(), feeds.size());
    for (std::size_t i = 0; i < feeds.size(); ++i) {
        ASSERT_EQ((*w)[i].t_start, feeds[i].t_start) << i;
        ASSERT_EQ((*w)[i].duration, feeds[i].duration) << i;
    }
}

// Acceleration is continuous at every junction (carried where the path is
// smooth, zero at corners) and the jerk within each segment's tangential limit,
// which is within its projected axis limit.
TEST_P(ExampleFeeds, AccelerationContinuousJerkWithinLimits) {
    double a_prev = 0;
    for (std::size_t i = 0; i < feeds.size(); ++i) {
        const auto& f = feeds[i];
        if (segs[i].kind == MotionKind::dwell) { a_prev = 0; continue; }
        const SegmentLimits proj = project_limits(segs[i].delta(), f.length, m);
        // Along the segment each axis moves |delta| / length of its mm per mm of
        // path: the tangential limits keep every axis within its own.
        for (std::size_t a = 0; a < kAxes; ++a) {
            if (!m.axes[a].present) continue;
            const double c = std::abs(static_cast<double>(segs[i].delta()[a])) / m.axes[a].steps_per_mm / f.length;
            ASSERT_LE(c * f.limits.j, m.axes[a].max_jerk * (1 + 1e-12)) << i;
            ASSERT_LE(c * f.limits.a, m.axes[a].max_accel * (1 + 1e-12)) << i;
        }
        ASSERT_NEAR(f.profile.at(0).a, a_prev, 1e-6 * proj.a) << "junction " << i;
        for (int k = 0; k <= 8; ++k) {
            const auto st = f.profile.at(f.duration * k / 8);
            ASSERT_LE(std::abs(st.j), f.limits.j * (1 + 1e-9)) << i;
            ASSERT_LE(std::abs(st.a), f.limits.a * (1 + 1e-9)) << i;
        }
        a_prev = f.profile.at(f.duration).a;
    }
    EXPECT_NEAR(a_prev, 0, 1e-9);
}

// Per-axis velocity, acceleration and jerk along the planned motion of the
// unrounded path (positions from each segment's end points and its profile),
// sampled every 0.5 ms and differenced over h = 20 ms, away from corners
// (turns > kSmoothTurnRad, where junction deviation lets the direction jump by
// design) and dwells: within each axis's limits, curvature steps included (see
// below). The sampling and the
// polyline standing in for the curve add a little; 3 % is allowed.
void ExampleFeeds::PerAxisKinematicsWithinLimitsAlongThePath_Body() {
    const double dt = 0.5e-3, h = 20e-3;
    const double total = feeds.back().t_start + feeds.back().duration;
    const auto n = static_cast<std::size_t>(total / dt) + 1;
    std::vector<PerAxis<double>> pos(n);
    std::vector<char> bad(n, 0);  // a corner or a dwell happens at or before this sample since the previous
    std::vector<char> jump(n, 0);  // a curvature step likewise
    std::size_t i = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const double t = std::min(total, static_cast<double>(k) * dt);
        while (i + 1 < feeds.size() && feeds[i].t_start + feeds[i].duration < t) {
            ++i;
            // The junction at the start of i: a corner?
            if (segs[i].kind == MotionKind::dwell || segs[i - 1].kind == MotionKind::dwell) { bad[k] = 1; continue; }
            const PerAxis<double> u0 = path_direction(segs[i - 1], m), u1 = path_direction(segs[i], m);
            double c = 0;
            for (std::size_t a = 0; a < kAxes; ++a) c += u0[a] * u1[a];
            if (std::acos(std::clamp(c, -1.0, 1.0)) > kSmoothTurnRad) bad[k] = 1;
            // Where the curvature itself jumps (a line meeting an arc tangentially,
            // two arcs of different radii), the centripetal acceleration steps:
            // the planner keeps each axis's share of the step within its jerk
            // times planner.curvature_step_s (20 ms), which this measure, over
            // h = 20 ms, sees as at most half the jerk limit on its own. Checked
            // with the rest, and the worst there printed apart.
            const double r0 = feeds[i - 1].radius, r1 = feeds[i].radius;
            const double k0 = std::isfinite(r0) ? 1 / r0 : 0, k1 = std::isfinite(r1) ? 1 / r1 : 0;
            if (std::abs(k1 - k0) > 0.25 * std::max(k0, k1)) jump[k] = 1;
        }
        const auto& s = segs[i];
        const auto& f = feeds[i];
        const double frac = s.kind == MotionKind::dwell || f.length == 0 ? 0 : f.profile.at(t - f.t_start).s / f.length;
        for (std::size_t a = 0; a < kAxes; ++a) pos[k][a] = s.from_mm[a] + (s.to_mm[a] - s.from_mm[a]) * frac;
    }
    const auto w = static_cast<std::size_t>(std::lround(h / dt));
    std::vector<std::size_t> last_bad(n, 0);  // index of the latest bad sample at or before k
    std::vector<std::size_t> last_jump(n, 0);
    for (std::size_t k = 1; k < n; ++k) last_bad[k] = bad[k] ? k : last_bad[k - 1];
    for (std::size_t k = 1; k < n; ++k) last_jump[k] = jump[k] ? k : last_jump[k - 1];
    double worst[3] = {0, 0, 0};
    double worst_j_at_steps = 0;
    for (std::size_t k = 2 * w; k + 2 * w < n; ++k) {
        if (last_bad[k + 2 * w] + 0 > k - 2 * w) continue;  // a corner inside the stencil
        for (std::size_t a = 0; a < kAxes; ++a) {
            const auto& ax = m.axes[a];
            if (!ax.present) continue;
            auto p = [&](int o) { return pos[static_cast<std::size_t>(static_cast<long>(k) + o * static_cast<long>(w))][a]; };
            const double v = (p(1) - p(-1)) / (2 * h);
            const double acc = (p(1) - 2 * p(0) + p(-1)) / (h * h);
            const double jerk = (p(2) - 2 * p(1) + 2 * p(-1) - p(-2)) / (2 * h * h * h);
            worst[0] = std::max(worst[0], std::abs(v) / ax.max_velocity);
            worst[1] = std::max(worst[1], std::abs(acc) / ax.max_accel);
            worst[2] = std::max(worst[2], std::abs(jerk) / ax.max_jerk);
            if (last_jump[k + 2 * w] > k - 2 * w)
                worst_j_at_steps = std::max(worst_j_at_steps, std::abs(jerk) / ax.max_jerk);
        }
    }
    RecordProperty("worst_v_share", std::to_string(worst[0]));
    RecordProperty("worst_a_share", std::to_string(worst[1]));
    RecordProperty("worst_j_share", std::to_string(worst[2]));
    std::printf("worst shares of the limits: v %.3f a %.3f j %.3f (j at curvature steps %.3f)\n", worst[0],
                worst[1], worst[2], worst_j_at_steps);
    EXPECT_LE(worst[0], 1.03);
    EXPECT_LE(worst[1], 1.03);
    EXPECT_LE(worst[2], 1.03);
}

TEST_P(ExampleFeeds, PerAxisVelocityAccelerationAndJerkWithinLimitsAlongThePath) {
    PerAxisKinematicsWithinLimitsAlongThePath_Body();
}

INSTANTIATE_TEST_SUITE_P(All, ExampleFeeds, kExampleJobs, example_name);

// Every program of the G-code corpus (examples/gcode/, each on the machine its
// README names) through the whole pipeline: the timeline and the move times as
// for the example jobs. The list must name every program there.
struct CorpusProgram {
    const char* file;
    const char* machine;
};
const CorpusProgram kCorpus[] = {
    {"linuxcnc_params.ngc", "router.toml"}, {"linuxcnc_inch.ngc", "router.toml"},
    {"fusion360_router.nc", "router.toml"}, {"fusion360_grbl.nc", "router.toml"},
    {"freecad_path.ngc", "router.toml"},    {"gcodetools_inkscape.ngc", "plotter.toml"},
    {"pcb2gcode_drill.ngc", "router.toml"}, {"dxf2gcode_contour.ngc", "router.toml"},
    {"sheetcam_plasma.tap", "router.toml"}, {"plotter_pen.ngc", "plotter.toml"},
};

TEST(CorpusTimeline, ListNamesEveryProgram) {
    std::set<std::string> listed;
    for (const auto& p : kCorpus) listed.insert(p.file);
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(kDir + "/gcode")) {
        if (!e.is_regular_file() || e.path().extension() == ".md") continue;
        ++files;
        EXPECT_TRUE(listed.count(e.path().filename().string())) << e.path();
    }
    EXPECT_EQ(files, listed.size());
}

class CorpusTimeline : public ::testing::TestWithParam<CorpusProgram> {};

TEST_P(CorpusTimeline, SegmentsFollowEachOtherAndMovesStrictlyIncrease) {
    const Machine m = bound_machine(GetParam().machine);
    auto job = load_gcode(kDir + "/gcode/" + GetParam().file, gcode_options(m));
    ASSERT_TRUE(job.ok()) << join(job.errors);
    auto plan = plan_job(*job, m);
    ASSERT_TRUE(plan.ok()) << join(plan.errors);
    check_timeline(plan->step_segments, plan->feeds, m);
    check_boundaries(*plan.value, m);
    check_plan(*plan.value, m);
}

INSTANTIATE_TEST_SUITE_P(All, CorpusTimeline, ::testing::ValuesIn(kCorpus), [](const auto& p) {
    std::string n = p.param.file;
    for (auto& ch : n) if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return n;
});

// The dense job's spiral (its G1 moves, first to last) within 5 % of its own
// lower bound, computed here from the G-code alone: each chord at the
// slowest of the feed (F3000 = 50 mm/s) and the curvature speeds
// min(sqrt(A rho), cbrt(J rho^2)) of seed 002's limits (A 500, J 2000) with
// rho the Archimedean spiral's radius of curvature at the chord's outer end,
// (r^2 + b^2)^1.5 / (r^2 + 2 b^2), b = 44 mm / (21 turns * 2 pi); speed changes
// cost nothing in this bound.
TEST(DenseJob, SpiralWithinFivePercentOfItsBound) {
    const Machine m = bound_machine("seed002.toml");
    std::ifstream f(kDir + "/jobs/dense.ngc");
    const std::regex g1(R"(G1 X([0-9.]+) Y([0-9.]+))");
    double px = 51, py = 50, bound = 0;  // the G0 before the spiral ends at (51, 50); centre (50, 50)
    const double b = 44 / (21 * 2 * M_PI);
    int chords = 0;
    for (std::string line; std::getline(f, line);) {
        std::smatch mt;
        if (!std::regex_search(line, mt, g1)) continue;
        const double x = std::stod(mt[1]), y = std::stod(mt[2]);
        const double r = std::max(std::hypot(px - 50, py - 50), std::hypot(x - 50, y - 50));
        const double rho = std::pow(r * r + b * b, 1.5) / (r * r + 2 * b * b);
        const double v = std::min({50.0, std::sqrt(500 * rho), std::cbrt(2000 * rho * rho)});
        bound += std::hypot(x - px, y - py) / v;
        px = x;
        py = y;
        ++chords;
    }
    ASSERT_EQ(chords, 12000);
    auto job = load_gcode(kDir + "/jobs/dense.ngc");
    ASSERT_TRUE(job.ok());
    auto segs = make_step_segments(*job, m);
    ASSERT_TRUE(segs.ok());
    auto feeds = plan_feeds(*segs.value, m, "dense.ngc");
    ASSERT_TRUE(feeds.ok());
    std::size_t first = SIZE_MAX, last = 0;
    for (std::size_t i = 0; i < segs->size(); ++i) {
        if ((*segs.value)[i].kind != MotionKind::linear) continue;
        first = std::min(first, i);
        last = i;
    }
    const auto& fd = *feeds.value;
    const double spiral = fd[last].t_start + fd[last].duration - fd[first].t_start;
    std::printf("spiral planned %.3f s, bound %.3f s, ratio %.4f\n", spiral, bound, spiral / bound);
    EXPECT_GE(spiral, bound);
    EXPECT_LE(spiral, 1.05 * bound);

    // Planned as the segments arrive, the planner holds seconds of the spiral,
    // not the spiral (its outer turns, all at the feed, were one span and so one
    // window of 8,647 segments before spans were cut at kSpanMaxS): the spans a
    // group may cover (kGroupMaxS), the lookahead past them, and the span being
    // made (2,534 segments, about 8 s of motion).
    FeedPlanner planner(m, "dense.ngc");
    for (const StepSegment& s : *segs.value) {
        planner.push(s);
        while (planner.next()) {
        }
    }
    planner.finish();
    while (planner.next()) {
    }
    ASSERT_TRUE(planner.done());
    std::printf("dense.ngc: at most %zu of %zu segments held, lookahead %.1f mm / %.2f s\n", planner.max_held(),
                segs->size(), planner.stats().max_lookahead_mm, planner.stats().max_lookahead_s);
    EXPECT_LT(planner.max_held(), 3000u);
    EXPECT_LT(planner.stats().max_lookahead_s, FeedOptions::kDefaultMaxLookaheadS);
    EXPECT_EQ(planner.stats().cut_windows, 0u);
}

// SPDX-License-Identifier: MIT
// Moves timed by phases of constant jerk (plan/phases.h, a measurement toward
// the compact wire): the fitter's claimed fire clocks are the card
// arithmetic's, simulated clock by clock, and every move fires within its
// window (never late, at most the tolerance early).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "cpstep/builds.h"
#include "plan/phases.h"
#include "plan/pipeline.h"
#include "plan/profile.h"

using namespace cpstep::plan;

namespace {

const std::string kDir = CPSTEP_EXAMPLES_DIR;

void check_fires(const std::vector<double>& ideal, const std::vector<i128>& lengths, const PhaseFitter& f,
                 const PhaseFormat& fmt, double tol) {
    ASSERT_TRUE(f.error().empty()) << f.error();
    const auto sim = simulate_phases(f.phases(), fmt, lengths);
    ASSERT_EQ(sim.size(), ideal.size());
    ASSERT_EQ(f.fire_clocks().size(), ideal.size());
    for (std::size_t n = 0; n < ideal.size(); ++n) {
        ASSERT_EQ(sim[n], f.fire_clocks()[n]) << "move " << n;
        ASSERT_LE(double(sim[n]), ideal[n]) << "move " << n << " late";
        ASSERT_GE(double(sim[n]), ideal[n] - tol) << "move " << n << " early";
    }
}

// An S-curve from rest to rest over L moves, by the profile's own inverse.
std::vector<double> s_curve_times(double L, double vmax, double A, double J, double clock_hz, double start_s) {
    const auto p = make_profile(L, 0, 0, vmax, A, J);
    EXPECT_TRUE(p.has_value());
    std::vector<double> t;
    for (int n = 1; n <= int(L); ++n)
        t.push_back((start_s + (n == int(L) ? p->duration : p->time_at(double(n)))) * clock_hz);
    return t;
}

TEST(Phases, AnSCurveInMovesFiresEveryMoveInItsWindow) {
    const PhaseFormat fmt{6, 60, true, true, 0.0};
    const double tol = 40, hz = 40e6;
    PhaseFitter f(fmt, tol);
    // Two motions with a stop between (moves/s, /s^2, /s^3 of a 80 steps/mm axis).
    auto a = s_curve_times(2000, 8000, 40000, 160000, hz, 0.0);
    auto b = s_curve_times(700, 3000, 40000, 160000, hz, 1.0);
    const double b_start = 1.0 * hz;
    ASSERT_TRUE(f.push(a, {}, 0.0));
    ASSERT_TRUE(f.push(b, {}, b_start));
    ASSERT_TRUE(f.finish());
    std::vector<double> all = a;
    all.insert(all.end(), b.begin(), b.end());
    check_fires(all, {}, f, fmt, tol);
    EXPECT_EQ(f.stats().moves, all.size());
    // The phases are the profiles' (7 each, a few more where a phase boundary
    // falls between ticks), far fewer than the moves.
    EXPECT_LT(f.phases().size(), 40u);
}

TEST(Phases, PathLengthsPerMoveChangeBetweenBatches) {
    // Path domain: batches of moves of different lengths along one S-curve.
    const PhaseFormat fmt{5, 60, true, true, 0.0125};
    const double tol = 40, hz = 40e6;
    const auto p = make_profile(50.0, 0, 0, 60.0, 500.0, 2000.0);   // mm, mm/s, mm/s^2, mm/s^3
    ASSERT_TRUE(p.has_value());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> len(0.0125, 0.0125 * std::sqrt(2.0));
    PhaseFitter f(fmt, tol);
    std::vector<double> ideal;
    std::vector<i128> lengths;
    double s = 0;
    bool first = true;
    while (true) {
        const double l = len(rng);   // one batch's move length (a card segment)
        std::vector<double> t, lm;
        for (int n = 0; n < 37 && s + l < 50.0; ++n) {
            s += l;
            t.push_back(p->time_at(s) * hz);
            lm.push_back(l);
            lengths.push_back(move_length(l, fmt));
        }
        if (t.empty()) break;
        ideal.insert(ideal.end(), t.begin(), t.end());
        ASSERT_TRUE(f.push(t, lm, first ? 0.0 : -1.0)) << f.error();
        first = false;
    }
    ASSERT_TRUE(f.finish());
    check_fires(ideal, lengths, f, fmt, tol);
    EXPECT_LT(f.phases().size(), 60u) << "moves " << ideal.size();
}

// Every move of a job, as the card loop times it, through the fitter (path
// domain, the default board); every fire checked.
struct JobPhases {
    std::vector<double> ideal;
    std::vector<i128> lengths;
    std::uint64_t chunks = 0;
    double tol = 0;   // cycles, the bound machine's
    double rule_shift_steps = 0;   // PlanStats::conic_rule_shift_steps
    double rule_min_gap_cycles = 0, walker_gap_cycles = 0;
    std::uint64_t conic_segments = 0;
    std::unique_ptr<PhaseFitter> fitter;
};

void fit_job(const char* job_file, PhaseFormat& fmt, JobPhases& out, bool conic_rule = false,
             std::string_view board = cpstep::builds::kDefaultBoard) {
    auto loaded = load_machine(kDir + "/machines/seed002.toml");
    ASSERT_TRUE(loaded.ok()) << join(loaded.errors);
    const cpstep::builds::Build& b = *cpstep::builds::find(board);
    Machine m = *loaded;
    CardFacts facts{std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw};
    if (b.conic) facts.conic_width = 40;   // the walker's width (READ 0x26)
    ASSERT_TRUE(bind_card(m, facts).empty());
    auto job = load_gcode(kDir + "/jobs/" + job_file);
    ASSERT_TRUE(job.ok()) << join(job.errors);
    out.tol = m.chunk_tolerance_cycles();
    fmt.clock_hz = m.card.clock_hz;   // the plan's phases in the timer's units
    out.fitter = std::make_unique<PhaseFitter>(fmt, out.tol);
    PlanOptions o;
    o.conic_length_rule = conic_rule;
    o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                          std::span<const PlanJerk> changes) {
        out.ideal.insert(out.ideal.end(), ideal.begin(), ideal.end());
        for (double l : lengths_mm) out.lengths.push_back(move_length(l, fmt));
        ASSERT_TRUE(out.fitter->push(ideal, lengths_mm, rest_at, changes)) << out.fitter->error();
    };
    auto plan = plan_job(*job, m, o);
    ASSERT_TRUE(plan.ok()) << join(plan.errors);
    ASSERT_TRUE(out.fitter->finish()) << out.fitter->error();
    out.chunks = plan->stats.chunks;
    out.rule_shift_steps = plan->stats.conic_rule_shift_steps;
    out.rule_min_gap_cycles = plan->stats.conic_rule_min_gap_cycles;
    out.walker_gap_cycles = double(conic_gap_cycles(m.card.conic_width));
    out.conic_segments = plan->stats.conic_segments;
    check_fires(out.ideal, out.lengths, *out.fitter, fmt, out.tol);
    const PhaseStats& st = out.fitter->stats();
    std::printf("%s: %zu moves, %llu chunks, %llu phases (%llu the plan's, %llu adjusted, %llu reloads, %llu timed)\n",
                job_file, out.ideal.size(), static_cast<unsigned long long>(out.chunks),
                static_cast<unsigned long long>(st.phases), static_cast<unsigned long long>(st.plan_phases),
                static_cast<unsigned long long>(st.adjusts), static_cast<unsigned long long>(st.reloads),
                static_cast<unsigned long long>(st.timed));
}

class ExamplePhases : public ::testing::TestWithParam<const char*> {};

// The greedy fit alone (the plan's phases not given), and the plan's own
// phases first, corrected where needed, without reloads.
TEST_P(ExamplePhases, GreedyFitFiresEveryMoveInItsWindow) {
    PhaseFormat fmt{6, 60, true, false, 0.0125};
    fmt.plan_jerk = false;
    JobPhases jp;
    ASSERT_NO_FATAL_FAILURE(fit_job(GetParam(), fmt, jp));
    // What the measurement in docs/BENCHMARKS.md rests on: fewer phases than chunks.
    EXPECT_LT(jp.fitter->phases().size(), jp.chunks);
}

TEST_P(ExamplePhases, ThePlansPhasesWithoutReloadsFireEveryMoveInItsWindow) {
    PhaseFormat fmt{6, 60, false, false, 0.0125};
    JobPhases jp;
    ASSERT_NO_FATAL_FAILURE(fit_job(GetParam(), fmt, jp));
    const PhaseStats& st = jp.fitter->stats();
    EXPECT_EQ(st.reloads, 0u);
    EXPECT_GT(st.plan_phases, st.phases / 3) << "the plan's own phases should carry most of the job";
    EXPECT_LT(st.phases, jp.chunks);
}

// Conics timed by the card's length rule (plan::conic_rule_divisors) on the HX8K
// (the board with the walker): every move in its window, and about as few phases
// as with each move's exact length along the arc.
TEST(Phases, ConicMovesTimedByTheCardsLengthRule) {
    PhaseFormat exact_fmt{6, 60, false, false, 0.0125};
    JobPhases exact;
    ASSERT_NO_FATAL_FAILURE(fit_job("tight_arcs.ngc", exact_fmt, exact, false, "hx8k"));
    PhaseFormat fmt{6, 60, false, false, 0.0125};
    JobPhases jp;
    ASSERT_NO_FATAL_FAILURE(fit_job("tight_arcs.ngc", fmt, jp, true, "hx8k"));
    EXPECT_EQ(jp.ideal.size(), exact.ideal.size());
    EXPECT_EQ(jp.conic_segments, 4u);
    EXPECT_GT(jp.rule_shift_steps, 0.0);
    EXPECT_LT(jp.rule_shift_steps, 0.5);
    EXPECT_GE(jp.rule_min_gap_cycles, jp.walker_gap_cycles) << "the walker's pace";
    EXPECT_LT(double(jp.fitter->stats().phases), 1.25 * double(exact.fitter->stats().phases));
    EXPECT_EQ(jp.fitter->stats().reloads, 0u);
}

INSTANTIATE_TEST_SUITE_P(Jobs, ExamplePhases, ::testing::Values("tab.ngc", "tight_arcs.ngc", "naca0025.ngc"),
                         [](const auto& p) {
                             std::string n = p.param;
                             for (auto& ch : n) if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return n;
                         });

}  // namespace

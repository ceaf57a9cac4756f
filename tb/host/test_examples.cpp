// The whole pipeline on the shipped examples: every job plans on every
// machine whose travel holds it, and the output keeps the card's rules.
#include <gtest/gtest.h>

#include <cmath>
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
        all_ideal.insert(all_ideal.end(), ideal.begin(), ideal.end());
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

}  // namespace


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
}

INSTANTIATE_TEST_SUITE_P(
    All, Examples,
    ::testing::Values(std::pair{"seed002.toml", "bracket.ngc"}, std::pair{"seed002.toml", "plasma.ngc"},
                      std::pair{"seed002.toml", "dense.ngc"}, std::pair{"router.toml", "bracket.ngc"},
                      std::pair{"plotter.toml", "plasma.ngc"}, std::pair{"plotter.toml", "bracket.ngc"},
                      std::pair{"seed002.toml", "tab.ngc"}, std::pair{"seed002.toml", "tight_arcs.ngc"}),
    [](const auto& p) {
        std::string n = std::string(p.param.first) + "_" + p.param.second;
        for (auto& ch : n) if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
        return n;
    });

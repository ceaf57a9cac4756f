#include <gtest/gtest.h>

#include <cmath>

#include <fmt/format.h>

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

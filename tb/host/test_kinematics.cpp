// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plan/kinematics.h"

using namespace cpstep::plan;

// Step events of x(t) = c t^3 / 6 (constant jerk c) at 100 steps/mm: step k
// happens when x reaches k/100 mm. Expected peaks over [0, 1 s]: v = c/2,
// a = c, j = c; quantization bounds from the header's formulas.
TEST(Kinematics, ConstantJerkMotion) {
    const double spm = 100, c = 60, h = 0.02;
    std::vector<double> t;
    std::vector<int> dir;
    const int steps = static_cast<int>(std::floor(c / 6 * spm));
    for (int k = 1; k <= steps; ++k) {
        t.push_back(std::cbrt(6.0 * k / spm / c));
        dir.push_back(1);
    }
    auto pk = realized_peaks(t, dir, spm, h);
    EXPECT_NEAR(pk.v, c / 2, 1.0 / (h * spm) + c * h);
    EXPECT_NEAR(pk.a, c, 4.0 / (h * h * spm) + c * h);
    EXPECT_LE(pk.j, c + 6.0 / (h * h * h * spm));
    EXPECT_GE(pk.j, c * 0.5);
}

TEST(Kinematics, ConstantVelocityBothDirections) {
    const double spm = 80;
    std::vector<double> t;
    std::vector<int> dir;
    for (int k = 1; k <= 8000; ++k) {
        t.push_back(k / (50.0 * spm));  // 50 mm/s
        dir.push_back(-1);
    }
    auto pk = realized_peaks(t, dir, spm, 0.01);
    EXPECT_NEAR(pk.v, 50, 1e-9);
    EXPECT_NEAR(pk.a, 0, 1e-6);
    EXPECT_NEAR(pk.j, 0, 1e-3);
}

// A velocity step from 10 to 30 mm/s at t = 1 s, half a window from the
// nearest point of the grid that starts at the first event (t = 0.05 s, h =
// 0.1 s). The acceleration estimate centred on the kink is dv/h = 200 mm/s^2;
// a stencil centred d away sees dv (h - d) / h^2, so the grid of spacing h
// finds only half of it and 8 evaluations per window nearly all of it.
TEST(Kinematics, MoreEvaluationsPerWindowFindPeaksBetweenGridPoints) {
    const double spm = 100, h = 0.1, dv = 20;
    std::vector<double> t;
    std::vector<int> dir;
    for (int k = 0; k <= 950; ++k) t.push_back(0.05 + k * 0.001);       // 10 mm/s up to t = 1
    for (int k = 1; k <= 3000; ++k) t.push_back(1.0 + k / 3000.0);      // then 30 mm/s
    dir.assign(t.size(), 1);
    const double quant = 4.0 / (h * h * spm);
    const auto coarse = realized_peaks(t, dir, spm, h);
    const auto fine = realized_peaks(t, dir, spm, h, 8);
    EXPECT_NEAR(coarse.a, dv / (2 * h), quant);
    EXPECT_NEAR(fine.a, dv / h, dv / h / 16 + quant);
    // The fine grid holds every point of the coarse one: it never finds less.
    EXPECT_GE(fine.v + 1e-9, coarse.v);
    EXPECT_GE(fine.a + 1e-9, coarse.a);
    EXPECT_GE(fine.j + 1e-9, coarse.j);
}

// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <string>
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

// PeakMeter: realized_peaks fed one event at a time must give the same
// doubles, bit for bit, for the whole train and for every prefix along it
// (finish() mid-stream).
namespace {

struct Train {
    std::vector<double> t;
    std::vector<int> dir;
};

void expect_same_peaks(const AxisPeaks& streamed, const AxisPeaks& reference) {
    EXPECT_EQ(streamed.v, reference.v);
    EXPECT_EQ(streamed.a, reference.a);
    EXPECT_EQ(streamed.j, reference.j);
}

// Feeds `train` to a meter, comparing finish() with realized_peaks on the
// prefix after each of the first events and at about `checkpoints` points
// spread over the rest, then on the whole train.
void expect_streaming_matches(const Train& train, double spm, double h, int m,
                              std::size_t checkpoints = 16) {
    PeakMeter meter(spm, h, m);
    const std::size_t n = train.t.size();
    const std::size_t every = std::max<std::size_t>(1, n / checkpoints);
    for (std::size_t k = 0; k < n; ++k) {
        meter.add(train.t[k], train.dir[k]);
        if (k < 8 || (k + 1) % every == 0) {
            SCOPED_TRACE("after event " + std::to_string(k));
            expect_same_peaks(meter.finish(),
                              realized_peaks(std::span(train.t).first(k + 1),
                                             std::span(train.dir).first(k + 1), spm, h, m));
        }
    }
    SCOPED_TRACE("whole train of " + std::to_string(n));
    expect_same_peaks(meter.finish(), realized_peaks(train.t, train.dir, spm, h, m));
}

// Step edges as measure_run sees them, double(cycles since start) / clock_hz,
// from random intervals around `mean` cycles: runs of equal times (several
// edges in one cycle), one-cycle intervals, ordinary ones and now and then a
// gap of 20 to 100 means; the direction reverses now and then.
Train random_train(std::uint64_t seed, std::size_t events, std::int64_t mean, double clock_hz) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    std::int64_t cycle = std::uniform_int_distribution<std::int64_t>(0, 10 * mean)(rng);
    int dir = 1;
    Train train;
    for (std::size_t k = 0; k < events; ++k) {
        const double r = u(rng);
        if (r < 0.15) {
            // same cycle as the previous edge
        } else if (r < 0.20) {
            cycle += 1;
        } else if (r < 0.98) {
            cycle += std::uniform_int_distribution<std::int64_t>(1, 2 * mean)(rng);
        } else {
            cycle += std::uniform_int_distribution<std::int64_t>(20 * mean, 100 * mean)(rng);
        }
        if (u(rng) < 0.05) dir = -dir;
        train.t.push_back(static_cast<double>(cycle) / clock_hz);
        train.dir.push_back(dir);
    }
    return train;
}

// Windows from far below the mean interval (many samples between two edges)
// to far above the whole train (a grid of a few samples, or too short for
// any difference); powers of two, so that with a clock of 1024 Hz the grid
// lands exactly on edge times.
const double kWindowFactors[] = {1.0 / 16, 0.5, 1, 4, 32, 1024, 8192};
const int kEvaluations[] = {1, 2, 8};

void expect_random_trains_match(double clock_hz, std::int64_t mean, std::uint64_t seed) {
    const Train train = random_train(seed, 3000, mean, clock_hz);
    const double mean_s = static_cast<double>(mean) / clock_hz;
    for (const double factor : kWindowFactors) {
        for (const int m : kEvaluations) {
            SCOPED_TRACE("h = " + std::to_string(factor) + " mean, m = " + std::to_string(m));
            expect_streaming_matches(train, 80, factor * mean_s, m);
        }
    }
}

}  // namespace

TEST(PeakMeter, RandomTrainsAtACardClock) {
    expect_random_trains_match(50e6, 5000, 1);
    expect_random_trains_match(50e6, 5000, 2);
}

// Edge times and grid times exact binary fractions: samples fall exactly on
// edges (and on runs of equal edges), where the curve takes the position
// after the last of them.
TEST(PeakMeter, RandomTrainsOnAnExactGrid) {
    expect_random_trains_match(1024, 8, 3);
    expect_random_trains_match(1024, 8, 4);
}

TEST(PeakMeter, ConstantJerkMotion) {
    const double spm = 100, c = 60;
    Train train;
    const int steps = static_cast<int>(std::floor(c / 6 * spm));
    for (int k = 1; k <= steps; ++k) {
        train.t.push_back(std::cbrt(6.0 * k / spm / c));
        train.dir.push_back(1);
    }
    for (const double h : {0.001, 0.02, 0.3}) {
        for (const int m : kEvaluations) {
            SCOPED_TRACE("h = " + std::to_string(h) + ", m = " + std::to_string(m));
            expect_streaming_matches(train, spm, h, m);
        }
    }
}

// The last grid sample lands on the last edge time, where five edges arrive
// at once: only that sample sees them, and it sets the peaks.
TEST(PeakMeter, BurstOnTheLastGridSample) {
    Train train;
    for (int k = 0; k <= 40; ++k) train.t.push_back(k * 0.125);
    for (int k = 0; k < 5; ++k) train.t.push_back(5.0);
    train.dir.assign(train.t.size(), 1);
    Train without_burst = train;
    without_burst.t.resize(41);
    without_burst.dir.resize(41);
    for (const int m : kEvaluations) {
        SCOPED_TRACE("m = " + std::to_string(m));
        const double h = 0.125 * m;  // grid spacing 0.125 s: the edge times
        EXPECT_GT(realized_peaks(train.t, train.dir, 1, h, m).v,
                  realized_peaks(without_burst.t, without_burst.dir, 1, h, m).v);
        expect_streaming_matches(train, 1, h, m);
    }
}

// Rounding can put a grid time t0 + i dt below an event time T while the
// grid that T ends, floor((T - t0) / dt) + 1 samples long, stops short of i.
// The meter computes that sample (it lies before T) but may fold it into the
// peaks only once a later event has lengthened the grid past it. Three
// events: at t0, just below t_i and just above it, so that sample i sits
// halfway up the last step, where it would raise v.
TEST(PeakMeter, SampleRoundedPastTheGridsEnd) {
    const double t0 = 0.0091, h = 0.00083, spm = 80;
    for (const int m : kEvaluations) {
        SCOPED_TRACE("m = " + std::to_string(m));
        const double dt = h / m;
        std::size_t i = 2 * m;
        double ti = 0, after = 0;
        for (; i < 100000; ++i) {
            ti = t0 + static_cast<double>(i) * dt;
            after = std::nextafter(ti, 1.0);
            if (static_cast<std::size_t>(std::floor((after - t0) / dt)) < i) break;
        }
        ASSERT_LT(i, 100000u) << "no grid time rounded past the grid's end";
        Train train{{t0, std::nextafter(ti, 0.0), after}, {1, 1, 1}};
        expect_streaming_matches(train, spm, h, m);
        train.t.push_back(after + h);  // now the grid holds sample i
        train.dir.push_back(1);
        expect_streaming_matches(train, spm, h, m);
    }
}

TEST(PeakMeter, FewEvents) {
    const AxisPeaks zero;
    PeakMeter none(80, 0.01, 8);
    expect_same_peaks(none.finish(), zero);
    PeakMeter one(80, 0.01, 8);
    one.add(0.5, 1);
    expect_same_peaks(one.finish(), zero);
    const Train trains[] = {
        {{0.1, 0.35}, {1, 1}},
        {{0.1, 0.35, 0.4}, {1, -1, -1}},
        {{0.25, 0.25, 0.5}, {1, 1, 1}},  // equal times, on a grid of spacing 1/32
        {{0.25, 0.5, 0.5}, {-1, 1, 1}},
    };
    for (const Train& train : trains) {
        for (const double h : {0.001, 0.03125, 0.1, 0.125, 1.0}) {
            for (const int m : kEvaluations) {
                SCOPED_TRACE("h = " + std::to_string(h) + ", m = " + std::to_string(m) +
                             ", events " + std::to_string(train.t.size()));
                expect_streaming_matches(train, 80, h, m);
            }
        }
    }
}

// A window of zero or less gives zeros, as realized_peaks does.
TEST(PeakMeter, NoWindowNoPeaks) {
    const Train train = random_train(5, 100, 5000, 50e6);
    for (const double h : {0.0, -0.01}) {
        PeakMeter meter(80, h, 8);
        for (std::size_t k = 0; k < train.t.size(); ++k) meter.add(train.t[k], train.dir[k]);
        expect_same_peaks(meter.finish(), AxisPeaks{});
        expect_same_peaks(meter.finish(), realized_peaks(train.t, train.dir, 80, h, 8));
    }
}

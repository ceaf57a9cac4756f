// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <random>

#include "plan/reduce.h"

using namespace cpstep::plan;

namespace {

// Independent card model: per part and axis, an incremental Bresenham
// accumulator (ties rounded up), not the closed form used by max_deviation.
struct Check {
    double worst_dev = 0;       // max |card - ideal|, steps
    double endpoint_err = 0;    // max |ideal - lattice| at part boundaries
    PerAxis<std::int64_t> landed{};
};

Check simulate(const PerAxis<std::int64_t>& d, const std::vector<CardSegment>& parts) {
    Check c;
    std::int64_t T = 0;
    for (auto x : d) T = std::max<std::int64_t>(T, std::llabs(x));
    PerAxis<std::int64_t> pos{};
    std::int64_t i = 0;
    for (const auto& p : parts) {
        PerAxis<std::int64_t> acc{}, cnt{};
        for (std::size_t a = 0; a < kAxes; ++a) acc[a] = p.u[a];
        for (std::uint32_t m = 0; m < p.moves; ++m) {
            ++i;
            for (std::size_t a = 0; a < kAxes; ++a) {
                acc[a] += 2 * static_cast<std::int64_t>(p.v[a]);
                while (acc[a] >= 2 * static_cast<std::int64_t>(p.u[a])) {
                    acc[a] -= 2 * static_cast<std::int64_t>(p.u[a]);
                    pos[a] += p.dir_positive[a] ? 1 : -1;
                    ++cnt[a];
                }
                const long double ideal = static_cast<long double>(d[a]) * i / T;
                c.worst_dev = std::max(c.worst_dev, static_cast<double>(std::fabs(pos[a] - ideal)));
            }
        }
        for (std::size_t a = 0; a < kAxes; ++a) {
            const long double ideal = static_cast<long double>(d[a]) * i / T;
            c.endpoint_err = std::max(c.endpoint_err, static_cast<double>(std::fabs(pos[a] - ideal)));
            EXPECT_EQ(cnt[a], std::llabs(p.delta[a]));
        }
    }
    EXPECT_EQ(i, T);
    c.landed = pos;
    return c;
}

// All structural rules of a card segment list for delta d and capacity W.
void check_parts(const PerAxis<std::int64_t>& d, const SplitResult& r, std::uint32_t W) {
    std::int64_t T = 0;
    int major = 0;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (std::llabs(d[a]) > T) { T = std::llabs(d[a]); major = static_cast<int>(a); }
    }
    std::int64_t sum = 0;
    for (const auto& p : r.parts) {
        EXPECT_EQ(p.major, major);
        EXPECT_EQ(p.first_move, sum);
        ASSERT_GT(p.moves, 0u);
        sum += p.moves;
        for (std::size_t a = 0; a < kAxes; ++a) {
            EXPECT_LE(p.u[a], W);
            EXPECT_LE(p.v[a], p.u[a]);
            EXPECT_EQ(std::gcd(p.u[a], p.v[a]), 1u) << "not reduced";
            EXPECT_EQ(p.moves % p.u[a], 0u);
            EXPECT_EQ(p.dir_positive[a], d[a] >= 0);
            if (static_cast<int>(a) == major) { EXPECT_EQ(p.u[a], 1u); EXPECT_EQ(p.v[a], 1u); }
        }
    }
    EXPECT_EQ(sum, T);
}

}  // namespace

TEST(Reduce, PaperExampleFitsWhole) {
    auto r = reduce_segment({51, 11, 0, 0}, 1024, 0.02);
    ASSERT_EQ(r.parts.size(), 1u);
    EXPECT_EQ(r.parts[0].moves, 51u);
    EXPECT_EQ(r.parts[0].u, (PerAxis<std::uint32_t>{1, 51, 1, 1}));
    EXPECT_EQ(r.parts[0].v, (PerAxis<std::uint32_t>{1, 11, 0, 0}));
    // Doubled: the same reduced pattern, twice the moves.
    auto r2 = reduce_segment({102, -22, 0, 0}, 1024, 0.02);
    ASSERT_EQ(r2.parts.size(), 1u);
    EXPECT_EQ(r2.parts[0].moves, 102u);
    EXPECT_EQ(r2.parts[0].u[1], 51u);
    EXPECT_EQ(r2.parts[0].v[1], 11u);
    EXPECT_FALSE(r2.parts[0].dir_positive[1]);
    EXPECT_EQ(r2.endpoint_error, 0.0);
}

TEST(Reduce, MajorIsFirstOfMaxAndZeroAxes) {
    auto r = reduce_segment({-5, 5, 0, 3}, 1024, 0.02);
    ASSERT_EQ(r.parts.size(), 1u);
    EXPECT_EQ(r.parts[0].major, 0);
    EXPECT_EQ(r.parts[0].u, (PerAxis<std::uint32_t>{1, 1, 1, 5}));
    EXPECT_EQ(r.parts[0].v, (PerAxis<std::uint32_t>{1, 1, 0, 3}));
    auto r2 = reduce_segment({0, 0, -7, 0}, 1024, 0.02);
    ASSERT_EQ(r2.parts.size(), 1u);
    EXPECT_EQ(r2.parts[0].major, 2);
    EXPECT_EQ(reduce_segment({0, 0, 0, 0}, 1024, 0.02).parts.size(), 0u);
}

TEST(Reduce, CapacityBoundary) {
    // u/g = W fits, W + 1 must split.
    EXPECT_EQ(reduce_segment({1024, 1, 0, 0}, 1024, 0.02).parts.size(), 1u);
    auto r = reduce_segment({1025, 1, 0, 0}, 1024, 0.02);
    EXPECT_GT(r.parts.size(), 1u);
    check_parts({1025, 1, 0, 0}, r, 1024);
}

TEST(Reduce, SplitStaysNearTheLine) {
    const PerAxis<std::int64_t> d{51, 11, 0, 0};
    auto r = reduce_segment(d, 8, 0.02);
    check_parts(d, r, 8);
    auto c = simulate(d, r.parts);
    EXPECT_EQ(c.landed, d);
    EXPECT_DOUBLE_EQ(c.endpoint_err, r.endpoint_error);
    EXPECT_LE(c.worst_dev, 0.5 + r.endpoint_error + 1e-12);
    EXPECT_LE(c.worst_dev, r.deviation_bound + 1e-12);
    EXPECT_NEAR(max_deviation(d, r.parts), c.worst_dev, 1e-12);
}

TEST(Reduce, ExhaustiveSmallTwoAxis) {
    // Every (T, D) with T <= 80 against small capacities.
    for (std::uint32_t W : {2u, 3u, 5u, 8u, 16u}) {
        for (std::int64_t T = 1; T <= 80; ++T) {
            for (std::int64_t D = 0; D <= T; ++D) {
                const PerAxis<std::int64_t> d{T, -D, 0, 0};
                auto r = reduce_segment(d, W, 0.02);
                check_parts(d, r, W);
                auto c = simulate(d, r.parts);
                ASSERT_EQ(c.landed, d);
                ASSERT_LE(c.worst_dev, 0.5 + r.endpoint_error + 1e-12) << T << "," << D;
                ASSERT_LE(c.worst_dev, r.deviation_bound + 1e-12) << T << "," << D << " W=" << W;
                ASSERT_LE(r.deviation_bound, 1.0) << T << "," << D << " W=" << W;
                ASSERT_NEAR(max_deviation(d, r.parts), c.worst_dev, 1e-12);
                if (T / std::gcd(T, D) <= W) { ASSERT_EQ(r.parts.size(), 1u); }
            }
        }
    }
}

TEST(Reduce, RandomFourAxis) {
    std::mt19937_64 rng(2);
    for (int k = 0; k < 200; ++k) {
        PerAxis<std::int64_t> d{};
        for (auto& x : d) x = static_cast<std::int64_t>(rng() % 20001) - 10000;
        auto r = reduce_segment(d, 64, 0.02);
        check_parts(d, r, 64);
        auto c = simulate(d, r.parts);
        ASSERT_EQ(c.landed, d);
        ASSERT_LE(c.worst_dev, 0.5 + r.endpoint_error + 1e-12);
        ASSERT_LE(c.worst_dev, r.deviation_bound + 1e-12);
        ASSERT_NEAR(max_deviation(d, r.parts), c.worst_dev, 1e-9);
    }
}

// Parts of at least min(32, W/4) moves on average over every prefix (4 parts of
// slack), the rule that keeps a run of short segments from outpacing the link.
void expect_long_parts(const SplitResult& r, std::uint32_t W) {
    const std::int64_t min_avg = std::max<std::int64_t>(1, std::min<std::int64_t>(32, W / 4));
    std::int64_t moves = 0, k = 0;
    for (const auto& p : r.parts) {
        moves += p.moves;
        ++k;
        if (k == static_cast<std::int64_t>(r.parts.size())) break;  // the last may be short
        ASSERT_LE(k, moves / min_avg + 4) << "part " << k << " ends at move " << moves;
    }
}

// pcb2gcode's drill rapids: lines one step off the diagonal (and off an axis).
// Every reduced pattern over a long stretch is 1/1 (or 0/1); the chord is
// exact there, so a part may end where the line is half a step off the lattice
// and still stay within half a step. Splitting only at points of small error
// cut these into single moves (1,433 card segments for one rapid), faster
// than the link could send them.
TEST(Reduce, NearDiagonalAndNearAxisLinesSplitIntoFewParts) {
    for (const PerAxis<std::int64_t> d :
         {PerAxis<std::int64_t>{1754, 1753, 0, 0}, PerAxis<std::int64_t>{-533, 534, 0, 0},
          PerAxis<std::int64_t>{5000, 4997, 0, 0}, PerAxis<std::int64_t>{5000, 3, 0, 0},
          PerAxis<std::int64_t>{20000, -19999, 19998, 0}, PerAxis<std::int64_t>{0, 7, 12001, 0}}) {
        for (std::uint32_t W : {256u, 1024u}) {
            auto r = reduce_segment(d, W, 0.02);
            check_parts(d, r, W);
            auto c = simulate(d, r.parts);
            ASSERT_EQ(c.landed, d);
            std::int64_t T = 0;
            for (auto x : d) T = std::max<std::int64_t>(T, std::llabs(x));
            // Along these lines every minor axis runs 1/1 or 0/1 except where
            // it changes by one step against the run: min(|d|, T - |d|) places
            // per axis. A part spans at most the window of 4W moves, and each
            // such place may cost two more parts (the run ends there, one
            // move bridges to the next run).
            std::int64_t changes = 0;
            bool major_seen = false;
            for (auto x : d) {
                const std::int64_t m = std::llabs(x);
                if (m == T && !major_seen) { major_seen = true; continue; }
                changes += std::min(m, T - m);
            }
            const auto most = static_cast<std::size_t>((T + 4 * W - 1) / (4 * W) + 2 * changes);
            EXPECT_LE(r.parts.size(), most) << d[0] << "," << d[1] << "," << d[2] << " W=" << W;
            EXPECT_LE(c.worst_dev, 0.52 + 1e-12) << d[0] << "," << d[1] << " W=" << W;
            EXPECT_LE(c.worst_dev, r.deviation_bound + 1e-12);
            expect_long_parts(r, W);
        }
    }
}

// Lines whose slopes are close to short fractions on several axes at once:
// few points lie near the lattice on every axis, so the split raises its bound
// above 1/2 + epsilon rather than emit short parts; it stays proved and below 1.
TEST(Reduce, SeveralMinorAxesKeepTheBudgetOfParts) {
    std::mt19937_64 rng(7);
    for (int k = 0; k < 60; ++k) {
        PerAxis<std::int64_t> d{};
        for (auto& x : d) x = static_cast<std::int64_t>(rng() % 60001) - 30000;
        const std::uint32_t W = (k % 2) ? 64u : 256u;
        auto r = reduce_segment(d, W, 0.02);
        check_parts(d, r, W);
        auto c = simulate(d, r.parts);
        ASSERT_EQ(c.landed, d);
        ASSERT_LE(c.worst_dev, r.deviation_bound + 1e-12);
        ASSERT_LT(r.deviation_bound, 1.0);
        expect_long_parts(r, W);
    }
}

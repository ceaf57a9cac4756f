// SPDX-License-Identifier: MIT
// Slow property sweeps (ctest label `long`).
#include <gtest/gtest.h>

#include <random>

#include "plan/chunks.h"
#include "plan/profile.h"
#include "plan/reduce.h"

using namespace cpstep::plan;

TEST(LongSweep, SplitExhaustiveTwoAxis) {
    for (std::uint32_t W : {4u, 16u, 64u}) {
        for (std::int64_t T = 1; T <= 300; ++T) {
            for (std::int64_t D = 0; D <= T; ++D) {
                const PerAxis<std::int64_t> d{T, D, 0, 0};
                auto r = reduce_segment(d, W, 0.02);
                std::int64_t sum = 0;
                PerAxis<std::int64_t> landed{};
                for (const auto& p : r.parts) {
                    sum += p.moves;
                    for (std::size_t a = 0; a < kAxes; ++a) {
                        ASSERT_LE(p.u[a], W);
                        landed[a] += p.delta[a];
                    }
                }
                ASSERT_EQ(sum, T);
                ASSERT_EQ(landed, d);
                ASSERT_LE(max_deviation(d, r.parts), 0.5 + r.endpoint_error + 1e-12);
                ASSERT_LE(max_deviation(d, r.parts), r.deviation_bound + 1e-12);
            }
        }
    }
}

TEST(LongSweep, SplitRandomFourAxisLarge) {
    std::mt19937_64 rng(5);
    for (int k = 0; k < 100; ++k) {
        PerAxis<std::int64_t> d{};
        for (auto& x : d) x = static_cast<std::int64_t>(rng() % (1 << 18)) - (1 << 17);
        auto r = reduce_segment(d, 1024, 0.02);
        PerAxis<std::int64_t> landed{};
        for (const auto& p : r.parts) {
            for (std::size_t a = 0; a < kAxes; ++a) landed[a] += p.delta[a];
        }
        ASSERT_EQ(landed, d);
        ASSERT_LE(max_deviation(d, r.parts), 0.5 + r.endpoint_error + 1e-12);
        ASSERT_LE(max_deviation(d, r.parts), r.deviation_bound + 1e-12);
        ASSERT_LT(r.deviation_bound, 1.0);
    }
}

TEST(LongSweep, ChunksOverManyProfiles) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> U(0, 1);
    for (int k = 0; k < 400; ++k) {
        auto p = make_profile(0.1 + 100 * U(rng), 0, 0, 1 + 150 * U(rng), 100 + 3000 * U(rng),
                              500 + 50000 * U(rng));
        ASSERT_TRUE(p);
        const int T = 10 + static_cast<int>(20000 * U(rng));
        std::vector<double> ideal;
        for (int i = 1; i <= T; ++i) ideal.push_back(48e6 * p->time_at(p->length * i / T));
        ChunkLimits lim;
        lim.enable_add2 = k % 2 == 0;
        auto r = compress(ideal, 0, 48, lim);
        ASSERT_TRUE(r.ok()) << r.error;
        const auto t = expand(r.chunks, 0);
        ASSERT_EQ(t.size(), ideal.size());
        for (std::size_t i = 0; i < t.size(); ++i) {
            ASSERT_GT(t[i], i ? t[i - 1] : 0);
            ASSERT_LE(static_cast<double>(t[i]), ideal[i]);
            ASSERT_GE(static_cast<double>(t[i]), ideal[i] - 48);
        }
    }
}

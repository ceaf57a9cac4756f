// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plan/chunks.h"
#include "plan/profile.h"

using namespace cpstep::plan;

namespace {

// Every rule of the card's chunk form against the ideal times.
void check_chunks(const std::vector<double>& ideal, const ChunkResult& r, std::int64_t prev,
                  double tol, const ChunkLimits& lim) {
    ASSERT_TRUE(r.ok()) << r.error;
    std::uint64_t total = 0;
    for (const auto& c : r.chunks) {
        EXPECT_GE(c.count, 1u);
        EXPECT_LE(c.count, lim.max_count);
        EXPECT_GE(c.interval, 1u);
        EXPECT_GE(c.add2, lim.add2_min);
        EXPECT_LE(c.add2, lim.add2_max);
        if (!lim.enable_add2) { EXPECT_EQ(c.add2, 0); }
        // Each delay in [1, 2^32), evaluated the card's way (with F fractional
        // bits: at least one cycle, and below 2^32 - 1 so the whole cycles are).
        const std::int64_t S = std::int64_t{1} << lim.frac_bits;
        for (std::uint32_t j = 0; j < c.count; ++j) {
            const std::int64_t d = std::int64_t{c.interval} * S + std::int64_t{j} * c.add +
                                   std::int64_t{c.add2} * j * (std::int64_t{j} - 1) / 2;
            ASSERT_GE(d, S);
            ASSERT_LT(d, ((std::int64_t{1} << 32) - 1) * S);
        }
        if (lim.monotone && c.count > 2) {
            const std::int64_t last = std::int64_t{c.add} + std::int64_t{c.count - 2} * c.add2;
            EXPECT_FALSE((c.add > 0 && last < 0) || (c.add < 0 && last > 0));
            EXPECT_GE(last, lim.add_min);
            EXPECT_LE(last, lim.add_max);
        }
        total += c.count;
    }
    ASSERT_EQ(total, ideal.size());
    const auto t = expand(r.chunks, prev, lim.frac_bits);
    ASSERT_EQ(t.size(), ideal.size());
    std::int64_t last = prev;
    for (std::size_t i = 0; i < t.size(); ++i) {
        ASSERT_GT(t[i], last) << i;
        ASSERT_LE(static_cast<double>(t[i]), ideal[i]) << "late at " << i;
        ASSERT_GE(static_cast<double>(t[i]), ideal[i] - tol) << "too early at " << i;
        last = t[i];
    }
    EXPECT_EQ(r.last_event, last);
}

// Ideal move times of a profile at clock `clk` for T equal-distance moves.
std::vector<double> profile_times(const Profile& p, int T, double clk, double t0) {
    std::vector<double> v;
    for (int i = 1; i <= T; ++i) v.push_back((t0 + p.time_at(p.length * i / T)) * clk);
    return v;
}

// A fractional chunk form (F = 16, plan_figures' measurement): add Q15.16, add2
// Q9.16 (26 bits), counts of 12 bits, increments of one sign.
ChunkLimits frac_limits() {
    ChunkLimits lim;
    lim.frac_bits = 16;
    lim.max_count = 4095;
    lim.add_min = std::int64_t{INT16_MIN} << 16;
    lim.add_max = std::int64_t{INT16_MAX} << 16;
    lim.add2_min = -(1 << 25);
    lim.add2_max = (1 << 25) - 1;
    lim.monotone = true;
    return lim;
}

}  // namespace

TEST(Chunks, FractionalExpandSumsExactly) {
    // interval 10, add 0.5 cycle (512/1024, F = 10): delays 10, 10.5, 11, 11.5
    // summed exactly (10, 20.5, 31.5, 43) and each event at the whole cycle below.
    const std::vector<Chunk> c{{10, 4, 512, 0}};
    EXPECT_EQ(expand(c, 100, 10), (std::vector<std::int64_t>{110, 120, 131, 143}));
    // add2 of a quarter cycle (256): delays 7, 7, 7.25, 7.75, 8.5: sums 7, 14,
    // 21.25, 29, 37.5. The next chunk starts from the last event's whole cycle.
    const std::vector<Chunk> d{{7, 5, 0, 256}, {3, 2, -512, 0}};
    EXPECT_EQ(expand(d, 0, 10), (std::vector<std::int64_t>{7, 14, 21, 29, 37, 40, 42}));
}

TEST(Chunks, FractionalAdd2FollowsSlowCurvature) {
    // A conic's intervals (docs/BENCHMARKS.md): second difference 0.02 cycle/move^2,
    // below what a whole-number add2 can say. 600 moves at 40 cycles tolerance.
    std::vector<double> ideal;
    double t = 0;
    for (int j = 0; j < 600; ++j) ideal.push_back(t += 12493 + 0.3 * j + 0.02 * j * (j - 1) / 2.0);
    ChunkLimits whole = frac_limits();
    whole.frac_bits = 0;
    whole.add_min = INT16_MIN;
    whole.add_max = INT16_MAX;
    whole.add2_min = INT16_MIN;
    whole.add2_max = INT16_MAX;
    const auto w = compress(ideal, 0, 40, whole);
    check_chunks(ideal, w, 0, 40, whole);
    const auto f = compress(ideal, 0, 40, frac_limits());
    check_chunks(ideal, f, 0, 40, frac_limits());
    EXPECT_GE(w.chunks.size(), 6u);
    EXPECT_EQ(f.chunks.size(), 1u);
}

TEST(Chunks, FractionalRandomProfilesWithinTolerance) {
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> U(0, 1);
    const double clk = 40e6, tol = 40;
    for (int k = 0; k < 40; ++k) {
        auto p = make_profile(1 + 50 * U(rng), 0, 0, 5 + 100 * U(rng), 200 + 2000 * U(rng), 1000 + 30000 * U(rng));
        ASSERT_TRUE(p);
        const int T = 50 + static_cast<int>(3000 * U(rng));
        const auto ideal = profile_times(*p, T, clk, 0.25 * U(rng));
        const std::int64_t prev = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor(ideal[0])) - 100000);
        check_chunks(ideal, compress(ideal, prev, tol, frac_limits()), prev, tol, frac_limits());
    }
}

TEST(Chunks, ConstantRateIsOneChunk) {
    std::vector<double> ideal;
    for (int i = 1; i <= 1000; ++i) ideal.push_back(500 + 1000.0 * i);
    ChunkLimits lim;
    auto r = compress(ideal, 500, 48, lim);
    ASSERT_TRUE(r.ok());
    ASSERT_EQ(r.chunks.size(), 1u);
    EXPECT_EQ(r.chunks[0], (Chunk{1000, 1000, 0, 0}));
    check_chunks(ideal, r, 500, 48, lim);
}

TEST(Chunks, CountLimitSplits) {
    std::vector<double> ideal;
    for (int i = 1; i <= 70000; ++i) ideal.push_back(10.0 * i);
    ChunkLimits lim;
    auto r = compress(ideal, 0, 4, lim);
    ASSERT_EQ(r.chunks.size(), 2u);
    EXPECT_EQ(r.chunks[0].count, 65535u);
    EXPECT_EQ(r.chunks[1].count, 70000u - 65535u);
    check_chunks(ideal, r, 0, 4, lim);
}

TEST(Chunks, LinearDelaysUseAdd) {
    // delay_j = 2000 + 3j exactly.
    std::vector<double> ideal;
    double t = 0;
    for (int j = 0; j < 500; ++j) ideal.push_back(t += 2000 + 3 * j);
    ChunkLimits lim;
    lim.enable_add2 = false;
    auto r = compress(ideal, 0, 0.5, lim);
    ASSERT_EQ(r.chunks.size(), 1u);
    EXPECT_EQ(r.chunks[0], (Chunk{2000, 500, 3, 0}));
}

TEST(Chunks, QuadraticDelaysUseAdd2) {
    // delay_j = 90000 - 40j + j(j-1)/2: exactly the add2 form.
    std::vector<double> ideal;
    double t = 0;
    for (int j = 0; j < 300; ++j) ideal.push_back(t += 90000 - 40 * j + j * (j - 1) / 2.0);
    ChunkLimits lim;
    auto with = compress(ideal, 0, 0.5, lim);
    ASSERT_EQ(with.chunks.size(), 1u);
    EXPECT_EQ(with.chunks[0], (Chunk{90000, 300, -40, 1}));
    lim.enable_add2 = false;
    auto without = compress(ideal, 0, 0.5, lim);
    EXPECT_GT(without.chunks.size(), 10u);
    check_chunks(ideal, without, 0, 0.5, lim);
}

TEST(Chunks, TooDenseIsAnError) {
    const std::vector<double> ideal{100.2, 100.4};
    auto r = compress(ideal, 0, 0.5, ChunkLimits{});
    EXPECT_EQ(r.error, "move 1 cannot follow the previous event at cycle 100: its window is [100, 100]");
    const std::vector<double> gap{100.2};
    EXPECT_EQ(compress(gap, 0, 0.1, ChunkLimits{}).error,
              "no whole cycle within the tolerance of move 0 (ideal 100.200)");
}

TEST(Chunks, RandomProfilesWithinTolerance) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(0, 1);
    const double clk = 48e6, tol = 48;
    for (int k = 0; k < 40; ++k) {
        const double vmax = 5 + 100 * U(rng);
        auto p = make_profile(1 + 50 * U(rng), 0, 0, vmax, 200 + 2000 * U(rng), 1000 + 30000 * U(rng));
        ASSERT_TRUE(p);
        const int T = 50 + static_cast<int>(3000 * U(rng));
        const auto ideal = profile_times(*p, T, clk, 0.25 * U(rng));
        for (bool add2 : {false, true}) {
            ChunkLimits lim;
            lim.enable_add2 = add2;
            const std::int64_t prev = static_cast<std::int64_t>(std::floor(ideal[0])) - 100000;
            auto r = compress(ideal, std::max<std::int64_t>(0, prev), tol, lim);
            check_chunks(ideal, r, std::max<std::int64_t>(0, prev), tol, lim);
        }
    }
}

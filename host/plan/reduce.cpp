// SPDX-License-Identifier: MIT
#include "plan/reduce.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

namespace cpstep::plan {

namespace {

__extension__ typedef __int128 i128;

struct Line {
    PerAxis<std::int64_t> mag{};  // |delta|
    std::int64_t T = 0;           // |delta[major]|
    int major = 0;

    // Lattice point of axis a after i moves: floor((2 D i + T) / (2 T)).
    std::int64_t q(std::size_t a, std::int64_t i) const {
        const i128 num = i128{2} * mag[a] * i + T;
        return static_cast<std::int64_t>(num / (i128{2} * T));
    }
    // |D i / T - q(i)| in steps.
    double err(std::size_t a, std::int64_t i) const {
        const i128 num = i128{2} * mag[a] * i - i128{2} * T * q(a, i);
        return std::abs(static_cast<double>(num)) / (2.0 * static_cast<double>(T));
    }
};

bool fits(const Line& L, std::int64_t i0, std::int64_t i1, std::uint32_t W) {
    const std::int64_t n = i1 - i0;
    if (n <= 0 || n > std::numeric_limits<std::uint32_t>::max()) return false;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (static_cast<int>(a) == L.major) continue;
        const std::int64_t dp = L.q(a, i1) - L.q(a, i0);
        if (n / std::gcd(n, dp) > static_cast<std::int64_t>(W)) return false;
    }
    return true;
}

double worst_err(const Line& L, std::int64_t i) {
    double e = 0;
    for (std::size_t a = 0; a < kAxes; ++a) e = std::max(e, L.err(a, i));
    return e;
}

}  // namespace

SplitResult reduce_segment(const PerAxis<std::int64_t>& delta, std::uint32_t W, double epsilon) {
    Line L;
    for (std::size_t a = 0; a < kAxes; ++a) {
        L.mag[a] = delta[a] < 0 ? -delta[a] : delta[a];
        if (L.mag[a] > L.T) {
            L.T = L.mag[a];
            L.major = static_cast<int>(a);
        }
    }
    SplitResult out;
    if (L.T == 0) return out;

    auto emit = [&](std::int64_t i0, std::int64_t i1) {
        CardSegment c;
        c.major = L.major;
        const std::int64_t n = i1 - i0;
        c.moves = static_cast<std::uint32_t>(n);
        c.first_move = static_cast<std::uint32_t>(i0);
        for (std::size_t a = 0; a < kAxes; ++a) {
            c.dir_positive[a] = delta[a] >= 0;
            const std::int64_t dp = L.q(a, i1) - L.q(a, i0);
            const std::int64_t g = std::gcd(n, dp);
            c.u[a] = static_cast<std::uint32_t>(n / g);
            c.v[a] = static_cast<std::uint32_t>(dp / g);
            c.delta[a] = delta[a] < 0 ? -dp : dp;
        }
        out.parts.push_back(c);
    };

    // Greedy: from i0, look at the split candidates in a window; find the
    // smallest achievable split-point error there, then take the farthest
    // candidate whose error is within max(that, epsilon). Candidates beyond W
    // moves only fit when the reduced patterns happen to be short; they are
    // looked at too, up to 4W, because near-rational slopes give long parts.
    const std::int64_t window = 4 * static_cast<std::int64_t>(W);
    std::int64_t i0 = 0;
    while (i0 < L.T) {
        if (fits(L, i0, L.T, W)) {
            emit(i0, L.T);
            break;
        }
        const std::int64_t last = std::min(L.T - 1, i0 + window);
        // One pass: remember the error of every fitting candidate.
        std::vector<std::pair<std::int64_t, double>> cand;
        double best = std::numeric_limits<double>::infinity();
        for (std::int64_t i = i0 + 1; i <= last; ++i) {
            if (!fits(L, i0, i, W)) continue;
            const double e = worst_err(L, i);
            best = std::min(best, e);
            cand.emplace_back(i, e);
        }
        const double threshold = std::max(best, epsilon) + 1e-12;
        std::int64_t pick = i0 + 1;
        for (auto it = cand.rbegin(); it != cand.rend(); ++it) {
            if (it->second <= threshold) {
                pick = it->first;
                break;
            }
        }
        out.endpoint_error = std::max(out.endpoint_error, worst_err(L, pick));
        emit(i0, pick);
        i0 = pick;
    }
    return out;
}

double max_deviation(const PerAxis<std::int64_t>& delta, std::span<const CardSegment> parts) {
    std::int64_t T = 0;
    for (auto d : delta) T = std::max<std::int64_t>(T, d < 0 ? -d : d);
    if (T == 0) return 0;
    double worst = 0;
    PerAxis<std::int64_t> base{};
    std::int64_t i = 0;
    for (const auto& p : parts) {
        for (std::uint32_t m = 1; m <= p.moves; ++m) {
            for (std::size_t a = 0; a < kAxes; ++a) {
                const i128 u = p.u[a], v = p.v[a];
                const auto step = static_cast<std::int64_t>((2 * v * m + u) / (2 * u));
                const std::int64_t pos = base[a] + (p.dir_positive[a] ? step : -step);
                // |pos - delta * (i + m) / T| as an exact fraction over T.
                const i128 num = i128{pos} * T - i128{delta[a]} * (i + m);
                const double dev = std::abs(static_cast<double>(num)) / static_cast<double>(T);
                worst = std::max(worst, dev);
            }
        }
        for (std::size_t a = 0; a < kAxes; ++a) {
            const std::int64_t full = static_cast<std::int64_t>(p.moves) / p.u[a] * p.v[a];
            base[a] += p.dir_positive[a] ? full : -full;
        }
        i += p.moves;
    }
    return worst;
}

}  // namespace cpstep::plan

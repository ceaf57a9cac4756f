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

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// A lattice point of the line after i moves, per axis: q(i) and the signed
// error s(i) = 2T q(i) - 2 D i, in (-T, T] (2T times q(i) - D i / T).
struct Point {
    std::int64_t i = 0;
    PerAxis<std::int64_t> q{}, s{};
};

Point point_at(const Line& L, std::int64_t i) {
    Point p;
    p.i = i;
    for (std::size_t a = 0; a < kAxes; ++a) {
        p.q[a] = L.q(a, i);
        p.s[a] = static_cast<std::int64_t>(i128{2} * L.T * p.q[a] - i128{2} * L.mag[a] * i);
    }
    return p;
}

// The point one move earlier: s grows by 2D; past T, q drops by one.
void step_back(const Line& L, Point& p) {
    --p.i;
    for (std::size_t a = 0; a < kAxes; ++a) {
        p.s[a] += 2 * L.mag[a];
        if (p.s[a] > L.T) {
            p.s[a] -= 2 * L.T;
            --p.q[a];
        }
    }
}

// The part from p0 to p1 and its proved bound on |card - ideal| (steps), over
// every move of the part and every axis, or +inf if some reduced pattern is
// longer than W; parts whose bound exceeds `cut` may report any value above it
// (the gcd is skipped when the bound without it already exceeds `cut`). Per
// minor axis: the card's chord position minus the ideal line is a linear term,
// which over moves 1..n lies between its value after the first move and the
// end's error s1, plus the chord's own rounding r, a multiple of 1/u in
// [-(ceil(u/2) - 1)/u, floor(u/2)/u] (ties round up). With u = 1
// (the part's slope is 0 or 1) the chord is exact and the part stays within
// its end errors.
double part_bound(const Line& L, const Point& p0, const Point& p1, std::uint32_t W,
                  double cut = kInf) {
    const std::int64_t n = p1.i - p0.i;
    if (n <= 0 || n > std::numeric_limits<std::uint32_t>::max()) return kInf;
    double b = 0;
    const double twoT = 2.0 * static_cast<double>(L.T);
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (static_cast<int>(a) == L.major || L.mag[a] == 0) continue;
        const std::int64_t dp = p1.q[a] - p0.q[a];
        const auto s0 = static_cast<double>(p0.s[a]), s1 = static_cast<double>(p1.s[a]);
        const double first = s0 + (s1 - s0) / static_cast<double>(n);
        const double top = std::max(first, s1) / twoT, bottom = std::min(first, s1) / twoT;
        double hi = top, lo = bottom;
        if (dp != 0 && dp != n) {
            // u >= 2 adds at least 1/3 on top; skip the gcd when that is too much.
            if (top + 1.0 / 3.0 > cut) return top + 1.0 / 3.0;
            const std::int64_t u = n / std::gcd(n, dp);
            if (u > static_cast<std::int64_t>(W)) return kInf;
            hi += static_cast<double>(u / 2) / static_cast<double>(u);
            lo -= static_cast<double>((u + 1) / 2 - 1) / static_cast<double>(u);
        }
        b = std::max({b, std::abs(hi), std::abs(lo)});
        if (b > cut) return b;
    }
    return b;
}

// The farthest point in (p0, last] whose part from p0 has a bound of at most
// D, and that bound. A single move always qualifies when D >= 1/2: its bound
// is its end's lattice error.
std::pair<Point, double> farthest_within(const Line& L, const Point& p0, std::int64_t last,
                                         std::uint32_t W, double D) {
    Point p = point_at(L, last);
    double b = part_bound(L, p0, p, W, D);
    while (b > D && p.i > p0.i + 1) {
        step_back(L, p);
        b = part_bound(L, p0, p, W, D);
    }
    return {p, b};
}

struct Split {
    std::vector<std::pair<std::int64_t, std::int64_t>> parts;  // [i0, i1) in moves
    double bound = 0;                                          // max part bound
    bool kept_budget = true;
};

// Greedy at bound D: from each split point the farthest part in the window
// whose bound is at most D. With `budget`, gives up (kept_budget false) as
// soon as some prefix has more than its budget of parts: moves / min_avg +
// slack, so no run of short parts anywhere outpaces the link.
Split greedy(const Line& L, std::uint32_t W, double D, std::int64_t min_avg, bool budget) {
    constexpr std::int64_t kSlack = 4;
    const std::int64_t window = 4 * static_cast<std::int64_t>(W);
    Split out;
    Point p0 = point_at(L, 0);
    while (p0.i < L.T) {
        auto [p, b] = farthest_within(L, p0, std::min(L.T, p0.i + window), W, D);
        out.parts.emplace_back(p0.i, p.i);
        out.bound = std::max(out.bound, b);
        const auto k = static_cast<std::int64_t>(out.parts.size());
        if (budget && p.i < L.T && k > p.i / min_avg + kSlack) {
            out.kept_budget = false;
            return out;
        }
        p0 = p;
    }
    return out;
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

    const double whole = part_bound(L, point_at(L, 0), point_at(L, L.T), W);
    if (whole < kInf) {  // fits whole: the exact reduced pattern (bound <= 1/2)
        emit(0, L.T);
        out.deviation_bound = whole;
        return out;
    }
    // The split's bound D: the target 1/2 + epsilon when the greedy at that
    // bound keeps the budget of parts (every prefix averages at least
    // min(32, W/4) moves, 4 parts of slack, so a short part may bridge two long
    // ones); otherwise the smallest D in (target, 1] that keeps it, by
    // bisection (6 halvings); and D = 1 when none does.
    const std::int64_t min_avg = std::max<std::int64_t>(1, std::min<std::int64_t>(32, W / 4));
    const double target = 0.5 + epsilon;
    Split best = greedy(L, W, target, min_avg, true);
    if (!best.kept_budget) {
        double lo = target, hi = 1.0;
        best = greedy(L, W, hi, min_avg, true);
        if (!best.kept_budget) {
            best = greedy(L, W, hi, min_avg, false);
        } else {
            for (int it = 0; it < 6; ++it) {
                const double mid = 0.5 * (lo + hi);
                Split g = greedy(L, W, mid, min_avg, true);
                if (g.kept_budget) {
                    hi = mid;
                    best = std::move(g);
                } else {
                    lo = mid;
                }
            }
        }
    }
    const auto& chosen = best.parts;
    out.deviation_bound = best.bound;
    for (const auto& [i0, i1] : chosen) {
        if (i0 > 0) {
            double e = 0;
            for (std::size_t a = 0; a < kAxes; ++a) e = std::max(e, L.err(a, i0));
            out.endpoint_error = std::max(out.endpoint_error, e);
        }
        emit(i0, i1);
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

// SPDX-License-Identifier: MIT
#include "plan/chunks.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

namespace cpstep::plan {

namespace {

constexpr std::int64_t kMaxDelay = kMaxMoveDelayCycles;

std::int64_t floor_div(std::int64_t a, std::int64_t b) {  // b > 0
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}
std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

// The same through a double quotient corrected to the exact integer result
// (|a| < 2^53): the division is the inner loop's cost. The quotient is truncated
// (a conversion, not a call to floor(), which baseline x86-64 cannot inline) and
// the loops below correct it by one where truncation and floor differ.
std::int64_t floor_div_fast(std::int64_t a, std::int64_t b) {  // b > 0
    auto q = static_cast<std::int64_t>(static_cast<double>(a) / static_cast<double>(b));
    while (q * b > a) --q;
    while ((q + 1) * b <= a) ++q;
    return q;
}
std::int64_t ceil_div_fast(std::int64_t a, std::int64_t b) { return -floor_div_fast(-a, b); }

struct Best {
    std::uint32_t count = 0;
    std::int64_t interval = 0, add = 0, add2 = 0, last = 0;
};

// Narrow [a_lo, a_hi], the adds A still possible, by move j's window and
// delay (both formulas below, at j).
[[gnu::always_inline]] inline void narrow_at(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t P,
               std::int64_t I, std::int64_t B, std::size_t j, std::int64_t& a_lo, std::int64_t& a_hi) {
    const auto jj = static_cast<std::int64_t>(j);
    const std::int64_t tri = jj * (jj + 1) / 2;
    const std::int64_t base = P + (jj + 1) * I + B * (jj + 1) * jj * (jj - 1) / 6;
    a_lo = std::max(a_lo, ceil_div_fast(lo[j] - base, tri));
    a_hi = std::min(a_hi, floor_div_fast(hi[j] - base, tri));
    const std::int64_t dbase = I + B * jj * (jj - 1) / 2;
    // delay_j = dbase + j A in [1, kMaxDelay]; divide only when the bound bites.
    if (a_lo * jj + dbase < 1) a_lo = std::max(a_lo, ceil_div(1 - dbase, jj));
    if (a_hi * jj + dbase > kMaxDelay) a_hi = std::min(a_hi, floor_div(kMaxDelay - dbase, jj));
}

// Whether (I, B) can possibly give a chunk of `need` moves: move need-1's
// constraints alone (a necessary condition; extend() applies all of them).
// Lets compress() skip candidates that cannot replace the best so far without
// changing which chunk it picks.
bool may_reach(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t P,
               std::int64_t I, std::int64_t B, const ChunkLimits& lim, std::uint32_t need) {
    if (need <= 1) return true;
    if (need > std::min<std::size_t>(lo.size(), lim.max_count)) return false;
    std::int64_t a_lo = lim.add_min, a_hi = lim.add_max;
    narrow_at(lo, hi, P, I, B, need - 1, a_lo, a_hi);
    return a_lo <= a_hi;
}

// For a fixed interval I and add2 B, extend the count while some integer add
// keeps every event in its window and every delay in [1, 2^32).
//   r_j = P + (j+1) I + A j(j+1)/2 + B (j+1) j (j-1)/6
//   delay_j = I + j A + B j(j-1)/2
// With lim.monotone and B != 0, `sign` (+1 or -1) is the sign every increment
// A + i B (i = 0..count-2) must have or be 0, each also within [add_min, add_max];
// the two signs are tried separately (each keeps the feasible adds an interval).
void extend(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t P,
            std::int64_t I, std::int64_t B, const ChunkLimits& lim, Best& best, int sign = 0) {
    std::int64_t a_lo = lim.add_min, a_hi = lim.add_max;
    const std::size_t n = std::min<std::size_t>(lo.size(), lim.max_count);
    std::uint32_t count = 1;
    for (std::size_t j = 1; j < n; ++j) {
        const auto jj = static_cast<std::int64_t>(j);
        std::int64_t new_lo = a_lo, new_hi = a_hi;
        narrow_at(lo, hi, P, I, B, j, new_lo, new_hi);
        if (sign != 0) {
            // The last increment A + (j-1) B, and the sign of all of them.
            const std::int64_t shift = (jj - 1) * B;
            new_lo = std::max(new_lo, lim.add_min - shift);
            new_hi = std::min(new_hi, lim.add_max - shift);
            if (sign > 0) new_lo = std::max({new_lo, std::int64_t{0}, -shift});
            else new_hi = std::min({new_hi, std::int64_t{0}, -shift});
        }
        if (new_lo > new_hi) break;
        a_lo = new_lo;
        a_hi = new_hi;
        count = static_cast<std::uint32_t>(j + 1);
    }
    if (count > best.count || (count == best.count && B == 0 && best.add2 != 0)) {
        const auto c = static_cast<std::int64_t>(count);
        // The latest feasible add keeps the moves closest to their ideal times.
        const std::int64_t A = count == 1 ? 0 : a_hi;
        best = {count, I, A, B,
                P + c * I + A * (c - 1) * c / 2 + B * c * (c - 1) * (c - 2) / 6};
    }
}

}  // namespace

ChunkResult compress(std::span<const double> ideal, std::int64_t prev_event, double tolerance,
                     const ChunkLimits& limits) {
    ChunkResult out;
    std::vector<std::int64_t> lo(ideal.size()), hi(ideal.size());
    for (std::size_t i = 0; i < ideal.size(); ++i) {
        hi[i] = static_cast<std::int64_t>(std::floor(ideal[i]));
        lo[i] = static_cast<std::int64_t>(std::ceil(ideal[i] - tolerance));
        if (lo[i] > hi[i]) {
            out.error = fmt::format("no whole cycle within the tolerance of move {} (ideal {:.3f})",
                                    i, ideal[i]);
            return out;
        }
    }
    std::int64_t P = prev_event;
    std::size_t i = 0;
    while (i < ideal.size()) {
        const std::span<const std::int64_t> L(lo.data() + i, lo.size() - i);
        const std::span<const std::int64_t> H(hi.data() + i, hi.size() - i);
        const std::int64_t i_lo = std::max<std::int64_t>(1, L[0] - P);
        const std::int64_t i_hi = std::min<std::int64_t>(kMaxDelay, H[0] - P);
        if (i_lo > i_hi) {
            out.error = fmt::format("move {} cannot follow the previous event at cycle {}: "
                                    "its window is [{}, {}]",
                                    i, P, L[0], H[0]);
            return out;
        }
        // Third difference of the ideal times estimates add2.
        std::array<std::int64_t, 4> b_store{0};
        std::size_t nb = 1;
        if (limits.enable_add2 && L.size() >= 4) {
            const double d3 = ideal[i + 3] - 3 * ideal[i + 2] + 3 * ideal[i + 1] - ideal[i];
            const auto b0 = static_cast<std::int64_t>(std::llround(d3));
            for (std::int64_t b = b0 - 1; b <= b0 + 1; ++b) {
                if (b != 0 && b >= limits.add2_min && b <= limits.add2_max) b_store[nb++] = b;
            }
        }
        const std::span<const std::int64_t> b_candidates(b_store.data(), nb);
        Best best;
        // A chunk of every remaining move with add2 = 0 cannot be bettered (later
        // candidates replace it only when longer): stop the search there.
        const auto all = static_cast<std::uint32_t>(std::min<std::size_t>(L.size(), limits.max_count));
        for (std::int64_t I = i_hi; I >= i_lo; --I) {
            for (std::int64_t B : b_candidates) {
                // extend() replaces the best only with a longer chunk, or an equal one
                // without add2 in place of one with it.
                const std::uint32_t need = best.count + (B == 0 && best.add2 != 0 ? 0 : 1);
                if (!may_reach(L, H, P, I, B, limits, need)) continue;
                if (limits.monotone && B != 0) {
                    extend(L, H, P, I, B, limits, best, +1);
                    extend(L, H, P, I, B, limits, best, -1);
                } else {
                    extend(L, H, P, I, B, limits, best);
                }
            }
            if (best.count == all && best.add2 == 0) break;
        }
        out.chunks.push_back({static_cast<std::uint32_t>(best.interval), best.count,
                              static_cast<std::int32_t>(best.add),
                              static_cast<std::int32_t>(best.add2)});
        P = best.last;
        i += best.count;
    }
    out.last_event = P;
    return out;
}

std::vector<std::int64_t> expand(std::span<const Chunk> chunks, std::int64_t prev_event) {
    std::vector<std::int64_t> t;
    std::int64_t P = prev_event;
    for (const auto& c : chunks) {
        for (std::uint32_t j = 0; j < c.count; ++j) {
            const std::int64_t jj = j;
            P += static_cast<std::int64_t>(c.interval) + jj * c.add + c.add2 * jj * (jj - 1) / 2;
            t.push_back(P);
        }
    }
    return t;
}

}  // namespace cpstep::plan

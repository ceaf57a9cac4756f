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

// The card's monotone rule at move j: the last increment A + (j-1) B within
// [add_min, add_max] and of the sign `sign` (+1 or -1) or 0, as all of them are.
void narrow_sign(std::int64_t jj, std::int64_t B, const ChunkLimits& lim, int sign, std::int64_t& a_lo,
                 std::int64_t& a_hi) {
    const std::int64_t shift = (jj - 1) * B;
    a_lo = std::max(a_lo, lim.add_min - shift);
    a_hi = std::min(a_hi, lim.add_max - shift);
    if (sign > 0) a_lo = std::max({a_lo, std::int64_t{0}, -shift});
    else a_hi = std::min({a_hi, std::int64_t{0}, -shift});
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

// For a fixed interval I and add2 B, extend the count while some add keeps
// every move within its constraints: `narrow(j, a_lo, a_hi)` narrows the adds
// [a_lo, a_hi] still possible by move j's window and delay, and
// `last(count, A)` is the realized time of the chunk's last move. With
// lim.monotone and B != 0, `sign` (+1 or -1) is the sign every increment
// A + i B (i = 0..count-2) must have or be 0, each also within [add_min,
// add_max]; the two signs are tried separately (each keeps the feasible adds an
// interval). The latest feasible add keeps the moves closest to their ideal times.
template <class Narrow, class Last>
void extend_with(std::size_t moves, std::int64_t I, std::int64_t B, const ChunkLimits& lim, Best& best, int sign,
                 Narrow narrow, Last last) {
    std::int64_t a_lo = lim.add_min, a_hi = lim.add_max;
    const std::size_t n = std::min<std::size_t>(moves, lim.max_count);
    std::uint32_t count = 1;
    for (std::size_t j = 1; j < n; ++j) {
        std::int64_t new_lo = a_lo, new_hi = a_hi;
        narrow(j, new_lo, new_hi);
        if (sign != 0) narrow_sign(static_cast<std::int64_t>(j), B, lim, sign, new_lo, new_hi);
        if (new_lo > new_hi) break;
        a_lo = new_lo;
        a_hi = new_hi;
        count = static_cast<std::uint32_t>(j + 1);
    }
    if (count > best.count || (count == best.count && B == 0 && best.add2 != 0)) {
        const std::int64_t A = count == 1 ? 0 : a_hi;
        best = {count, I, A, B, last(static_cast<std::int64_t>(count), A)};
    }
}

// Whole cycles:
//   r_j = P + (j+1) I + A j(j+1)/2 + B (j+1) j (j-1)/6
//   delay_j = I + j A + B j(j-1)/2
void extend(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t P,
            std::int64_t I, std::int64_t B, const ChunkLimits& lim, Best& best, int sign = 0) {
    extend_with(
        lo.size(), I, B, lim, best, sign,
        [&](std::size_t j, std::int64_t& a_lo, std::int64_t& a_hi) { narrow_at(lo, hi, P, I, B, j, a_lo, a_hi); },
        [&](std::int64_t c, std::int64_t A) { return P + c * I + A * (c - 1) * c / 2 + B * c * (c - 1) * (c - 2) / 6; });
}

// The same search with F fractional bits in add and add2 (ChunkLimits::frac_bits):
// times in units of 2^-F cycles, the interval a whole number of cycles:
//   X_j = (j+1) I 2^F + A j(j+1)/2 + B (j+1)j(j-1)/6 in [(lo_j - P) 2^F, (hi_j - P + 1) 2^F - 1]
//   D_j = I 2^F + j A + B j(j-1)/2 in [2^F, (2^32 - 2) 2^F]   (every delay 1..2^32-1 cycles)
void extend_frac(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t P,
                 std::int64_t I, std::int64_t B, const ChunkLimits& lim, Best& best, int sign) {
    const std::int64_t S = std::int64_t{1} << lim.frac_bits;
    extend_with(
        lo.size(), I, B, lim, best, sign,
        [&](std::size_t j, std::int64_t& a_lo, std::int64_t& a_hi) {
            const auto jj = static_cast<std::int64_t>(j);
            const std::int64_t tri = jj * (jj + 1) / 2;
            const std::int64_t base = (jj + 1) * I * S + B * ((jj + 1) * jj * (jj - 1) / 6);
            a_lo = std::max(a_lo, ceil_div_fast((lo[j] - P) * S - base, tri));
            a_hi = std::min(a_hi, floor_div_fast((hi[j] - P + 1) * S - 1 - base, tri));
            const std::int64_t dbase = I * S + B * (jj * (jj - 1) / 2);
            if (a_lo * jj + dbase < S) a_lo = std::max(a_lo, ceil_div(S - dbase, jj));
            if (a_hi * jj + dbase > (kMaxDelay - 1) * S) a_hi = std::min(a_hi, floor_div((kMaxDelay - 1) * S - dbase, jj));
        },
        [&](std::int64_t c, std::int64_t A) {
            return P + floor_div(c * I * S + A * ((c - 1) * c / 2) + B * (c * (c - 1) * (c - 2) / 6), S);
        });
}

// The chunks of moves with windows [lo_i, hi_i] after the event at prev_event, one
// at a time: `find(i, L, H, P, i_lo, i_hi)` gives the chunk from move i on (L, H its
// windows from there, P the last event, [i_lo, i_hi] its possible first delays).
template <class Find>
ChunkResult chunk_loop(std::span<const std::int64_t> lo, std::span<const std::int64_t> hi, std::int64_t prev_event,
                       Find find) {
    ChunkResult out;
    std::int64_t P = prev_event;
    std::size_t i = 0;
    while (i < lo.size()) {
        const std::span<const std::int64_t> L = lo.subspan(i), H = hi.subspan(i);
        const std::int64_t i_lo = std::max<std::int64_t>(1, L[0] - P);
        const std::int64_t i_hi = std::min<std::int64_t>(kMaxDelay, H[0] - P);
        if (i_lo > i_hi) {
            out.error = fmt::format("move {} cannot follow the previous event at cycle {}: "
                                    "its window is [{}, {}]",
                                    i, P, L[0], H[0]);
            return out;
        }
        const Best best = find(i, L, H, P, i_lo, i_hi);
        out.chunks.push_back({static_cast<std::uint32_t>(best.interval), best.count,
                              static_cast<std::int32_t>(best.add), static_cast<std::int32_t>(best.add2)});
        P = best.last;
        i += best.count;
    }
    out.last_event = P;
    return out;
}

// add2 candidates for a chunk starting at move 0 of `ideal` after the event at P:
// least-squares fits of (j+1) I + A j(j+1)/2 + B (j+1)j(j-1)/6 to the ideal times
// over 8, 16, 32, ... moves, each B in units of 2^-F, and 0.
std::vector<std::int64_t> add2_candidates(std::span<const double> ideal, std::int64_t P, double tolerance,
                                          const ChunkLimits& lim) {
    std::vector<std::int64_t> out{0};
    if (!lim.enable_add2) return out;
    const double S = std::ldexp(1.0, static_cast<int>(lim.frac_bits));
    const std::size_t n_all = std::min<std::size_t>(ideal.size(), lim.max_count);
    for (std::size_t n = 8; ; n *= 2) {
        const std::size_t m = std::min(n, n_all);
        if (m < 4) break;
        // Normal equations of the 3-parameter fit (columns j+1, tri, tet).
        double M[3][3] = {}, r[3] = {};
        for (std::size_t j = 0; j < m; ++j) {
            const double x = static_cast<double>(j);
            const double c[3] = {x + 1, x * (x + 1) / 2, (x + 1) * x * (x - 1) / 6};
            const double y = ideal[j] - tolerance / 2 - static_cast<double>(P);
            for (int a = 0; a < 3; ++a) {
                r[a] += c[a] * y;
                for (int b = 0; b < 3; ++b) M[a][b] += c[a] * c[b];
            }
        }
        // Cramer's rule (3x3).
        auto det = [](const double A[3][3]) {
            return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                   A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
        };
        const double d = det(M);
        if (d != 0 && std::isfinite(d)) {
            double Mb[3][3];
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) Mb[a][b] = b == 2 ? r[a] : M[a][b];
            const double B = det(Mb) / d * S;
            if (std::isfinite(B)) {
                const auto b = static_cast<std::int64_t>(std::llround(B));
                if (b >= lim.add2_min && b <= lim.add2_max &&
                    std::find(out.begin(), out.end(), b) == out.end())
                    out.push_back(b);
            }
        }
        if (m == n_all) break;
    }
    return out;
}

ChunkResult compress_frac(std::span<const double> ideal, std::int64_t prev_event, double tolerance,
                          const ChunkLimits& limits, std::span<const std::int64_t> lo_all,
                          std::span<const std::int64_t> hi_all) {
    return chunk_loop(lo_all, hi_all, prev_event, [&](std::size_t i, std::span<const std::int64_t> L,
                                                      std::span<const std::int64_t> H, std::int64_t P,
                                                      std::int64_t i_lo, std::int64_t i_hi) {
        std::vector<std::int64_t> bs = add2_candidates(ideal.subspan(i), P, tolerance, limits);
        if (limits.enable_add2 && L.size() >= 4) {
            // The third difference of the first moves, as the whole-cycle search takes it.
            const double d3 = ideal[i + 3] - 3 * ideal[i + 2] + 3 * ideal[i + 1] - ideal[i];
            const std::int64_t S = std::int64_t{1} << limits.frac_bits;
            for (std::int64_t b : {std::llround(d3) - 1, std::llround(d3), std::llround(d3) + 1}) {
                const std::int64_t bb = b * S;
                if (bb != 0 && bb >= limits.add2_min && bb <= limits.add2_max &&
                    std::find(bs.begin(), bs.end(), bb) == bs.end())
                    bs.push_back(bb);
            }
        }
        Best best;
        const auto all = static_cast<std::uint32_t>(std::min<std::size_t>(L.size(), limits.max_count));
        // The longest chunk of every interval with add2 B.
        const auto try_b = [&](std::int64_t B) {
            for (std::int64_t I = i_hi; I >= i_lo; --I) {
                if (limits.monotone && B != 0) {
                    extend_frac(L, H, P, I, B, limits, best, +1);
                    extend_frac(L, H, P, I, B, limits, best, -1);
                } else {
                    extend_frac(L, H, P, I, B, limits, best, 0);
                }
                if (best.count == all && best.add2 == 0) break;
            }
        };
        for (std::int64_t B : bs) try_b(B);
        // Refine add2 around the best: steps of 1/4 cycle down to 2^-F while one gains.
        if (limits.enable_add2 && best.count < all) {
            for (std::int64_t step = std::int64_t{1} << (limits.frac_bits >= 2 ? limits.frac_bits - 2 : 0); step >= 1;
                 step /= 2) {
                for (bool gained = true; gained;) {
                    gained = false;
                    const std::uint32_t before = best.count;
                    const std::int64_t at = best.add2;
                    for (std::int64_t B : {at - step, at + step}) {
                        if (B < limits.add2_min || B > limits.add2_max) continue;
                        try_b(B);
                    }
                    gained = best.count > before;
                }
            }
        }
        return best;
    });
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
    if (limits.frac_bits > 0) return compress_frac(ideal, prev_event, tolerance, limits, lo, hi);
    return chunk_loop(lo, hi, prev_event, [&](std::size_t i, std::span<const std::int64_t> L,
                                              std::span<const std::int64_t> H, std::int64_t P,
                                              std::int64_t i_lo, std::int64_t i_hi) {
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
        return best;
    });
}

std::vector<std::int64_t> expand(std::span<const Chunk> chunks, std::int64_t prev_event, unsigned frac_bits) {
    std::vector<std::int64_t> t;
    std::int64_t P = prev_event;
    if (frac_bits > 0) {
        // The card's sum: the delays in units of 2^-F, the event at the whole cycles.
        const std::int64_t S = std::int64_t{1} << frac_bits;
        for (const auto& c : chunks) {
            std::int64_t x = 0, d = std::int64_t{c.interval} * S, inc = c.add;
            for (std::uint32_t j = 0; j < c.count; ++j) {
                x += d;
                t.push_back(P + floor_div(x, S));
                d += inc;
                inc += c.add2;
            }
            P = t.back();
        }
        return t;
    }
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

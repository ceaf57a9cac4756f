// SPDX-License-Identifier: MIT
#include "plan/phases.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace cpstep::plan {

namespace {

i128 floor_div(i128 a, i128 b) {  // b > 0
    i128 q = a / b;
    if ((a % b != 0) && (a < 0)) --q;
    return q;
}
i128 ceil_div(i128 a, i128 b) { return -floor_div(-a, b); }  // b > 0

// A phase is at most this many ticks (keeps every product within 128 bits).
constexpr std::uint64_t kMaxPhaseTicks = std::uint64_t{1} << 24;
// The PHASE word's ticks field (W0[23:0]; 0 there means 1): a rest phase's most.
constexpr std::uint64_t kMaxFieldTicks = (std::uint64_t{1} << 24) - 1;
// A timed move's clocks fit the phase word's 24-bit field.
constexpr std::int64_t kMaxTimedClocks = std::int64_t{1} << 24;
// How many moves past a phase its u is steered by.
constexpr std::size_t kSteerMoves = 8;
// A phase that reloads p, V and H costs this many words against one that carries them.
constexpr std::size_t kReloadWords = 4;
// Moves before and after a reload that the plan's state there is fitted to.
constexpr std::size_t kPlanFit = 4;

// P(k) = V k + H A(k) + u G(k): the position k clocks into a phase (units of
// 2^-F / 2^s), each tick m adding x(m+1) - x(m) every clock, x(m) = V m + H m^2 + u m^3.
// The card keeps the step S = V + H + u of the tick, not V, and carries S from one
// phase into the next (a new u changes the step from the next tick on), so a
// phase from S and H is P(k) = (S - H) k + H A(k) + u Gs(k), Gs = G - k.
struct Terms {
    i128 k, A, G, Gs;
};

Terms terms(std::int64_t k, unsigned s) {
    const i128 T = i128{1} << s;
    const i128 M = k >> s, r = k & ((std::int64_t{1} << s) - 1);
    const i128 G = T * M * M * M + r * (3 * M * M + 3 * M + 1);
    return {k, T * M * M + r * (2 * M + 1), G, G - k};
}

std::int64_t to_i64(i128 x) {
    if (x > std::numeric_limits<std::int64_t>::max()) return std::numeric_limits<std::int64_t>::max();
    if (x < std::numeric_limits<std::int64_t>::min()) return std::numeric_limits<std::int64_t>::min();
    return static_cast<std::int64_t>(x);
}

i128 abs128(i128 x) { return x < 0 ? -x : x; }

// Whether x fits a signed register of `bits` bits.
bool fits(i128 x, unsigned bits) { return x >= -(i128{1} << (bits - 1)) && x < (i128{1} << (bits - 1)); }

// A phase from S, H with u for E ticks: every tick's step S + 2H m + 3u m (m + 1)
// >= 0 (the position never goes back) and the state after it fits the card's
// registers.
bool phase_holds(i128 s0, i128 a0, i128 u, std::int64_t E, const PhaseFormat& f) {
    auto step_at = [&](i128 m) { return s0 + 2 * a0 * m + 3 * u * m * (m + 1); };
    if (step_at(0) < 0 || step_at(E - 1) < 0) return false;
    if (u > 0) {
        const i128 mstar = floor_div(-(2 * a0 + 3 * u), 6 * u);
        for (i128 m = mstar - 1; m <= mstar + 2; ++m)
            if (m >= 0 && m <= E - 1 && step_at(m) < 0) return false;
    }
    return fits(s0 + 2 * a0 * i128(E) + 3 * u * i128(E) * i128(E + 1), f.v_bits) && fits(a0 + 3 * u * i128(E), f.h_bits);
}

}  // namespace

i128 move_length(double length_mm, const PhaseFormat& format) {
    if (format.path_unit_mm <= 0) return i128{1} << format.frac_bits;
    // To 2^-length_bits of the unit (a card segment's length per move, as the card holds it).
    const unsigned lb = format.length_bits;
    return i128(std::llround(std::ldexp(length_mm / format.path_unit_mm, int(lb)))) << (format.frac_bits - lb);
}

PhaseFitter::PhaseFitter(PhaseFormat format, double tolerance_cycles) : fmt_(format), tol_(tolerance_cycles) {
    if (fmt_.frac_bits < 40 || fmt_.frac_bits > 70 || fmt_.tick_log2 > 16 || fmt_.frac_bits + fmt_.tick_log2 + 2 < 64)
        throw std::invalid_argument("PhaseFitter: format out of range");
}

bool PhaseFitter::push(std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                       std::span<const PlanJerk> plan) {
    if (!error_.empty()) return false;
    for (const PlanJerk& c : plan) {
        // A segment's profile going on with the jerk, speed and acceleration the
        // one before left (a phase cut at a segment's end) changes nothing.
        if (!changes_.empty()) {
            const PlanJerk& b = changes_.back();
            const double dt = (c.at - b.at) / fmt_.clock_hz;
            const double v = b.v + b.a * dt + b.jerk * dt * dt / 2, a = b.a + b.jerk * dt;
            if (c.jerk == b.jerk && std::fabs(c.v - v) <= 1e-9 * std::max(1.0, std::fabs(v)) &&
                std::fabs(c.a - a) <= 1e-9 * std::max(1.0, std::fabs(a)))
                continue;
        }
        changes_.push_back(c);
    }
    if (rest_at >= 0) {
        if (!fit(true)) return false;
        // The motion before has ended with its last move (the open phase
        // closed there); a rest phase holds still until the tick at rest_at.
        const std::int64_t T = std::int64_t{1} << fmt_.tick_log2;
        const double gap = rest_at - double(c0_);
        const std::uint64_t R = gap > 0 ? std::uint64_t(std::floor(gap / double(T))) : 0;
        p0_ = s0_ = a0_ = 0;
        if (R > 0) {
            for (std::uint64_t left = R; left > 0;) {
                const std::uint64_t t = std::min(left, kMaxFieldTicks);
                phases_.push_back({t, 0, true});
                ++stats_.rests;
                ++stats_.phases;
                left -= t;
            }
            c0_ += std::int64_t(R) * T;
            pending_rest_ = false;
        } else {
            pending_rest_ = true;
        }
    }
    queue_.insert(queue_.end(), ideal.begin(), ideal.end());
    i128 at = cum_.size() > head_ ? cum_.back() : cum_head_;
    for (std::size_t n = 0; n < ideal.size(); ++n) {
        at += move_length(fmt_.path_unit_mm > 0 ? lengths_mm[n] : 0.0, fmt_);
        cum_.push_back(at);
    }
    return fit(false);
}

bool PhaseFitter::push_pause(std::span<const double> ideal) {
    if (!error_.empty()) return false;
    if (!fit(true)) return false;   // the motion before: every move timed, its last phase closed
    const std::int64_t T = std::int64_t{1} << fmt_.tick_log2;
    for (const double tau : ideal) {
        const std::int64_t at = static_cast<std::int64_t>(std::floor(tau));
        // Hold still (p, S and H zero) until a timed move reaches the pause move.
        while (at - c0_ >= kMaxTimedClocks) {
            const std::uint64_t R = std::min<std::uint64_t>(kMaxFieldTicks, std::uint64_t((at - c0_ - 1) / T));
            phases_.push_back({R, 0, true});
            ++stats_.rests;
            ++stats_.phases;
            c0_ += std::int64_t(R) * T;
        }
        if (at <= c0_) {
            error_ = fmt::format("pause move at clock {:.1f} comes before the phases reach it (clock {})", tau, c0_);
            return false;
        }
        phases_.push_back({std::uint64_t(at - c0_), 0, true, false, 0, 0, 0, true});
        ++stats_.rests;
        fires_.push_back(at);
        c0_ = at;
        ++stats_.phases;
        ++stats_.timed;
    }
    p0_ = s0_ = a0_ = 0;
    pending_rest_ = false;
    return true;
}

bool PhaseFitter::finish() { return error_.empty() && fit(true); }

// One phase tried from the state `st`: the longest run of queued moves (at
// most `cap`) one u times within their windows, ending at the tick after its
// last move with the next move still to come in its own window and the
// position never going back.
PhaseFitter::Trial PhaseFitter::evaluate(const State& st, bool all, std::size_t cap) const {
    const i128 s0 = st.s0, a0 = st.a0, b0 = s0 - a0;
    const unsigned s = fmt_.tick_log2;
    const std::int64_t T = std::int64_t{1} << s;
    const i128 kInf = i128{1} << 120;
    Trial tr;
    std::vector<i128> lo_run, hi_run;
    if (!fits(s0, fmt_.v_bits) || !fits(a0, fmt_.h_bits)) return tr;
    i128 jlo = -(i128{1} << (fmt_.u_bits - 1)), jhi = (i128{1} << (fmt_.u_bits - 1)) - 1;
    std::size_t n = st.head;
    for (; n < queue_.size() && n - st.head < cap; ++n) {
        const double tau = queue_[n];
        const std::int64_t hi = static_cast<std::int64_t>(std::floor(tau));
        const std::int64_t lo = static_cast<std::int64_t>(std::ceil(tau - tol_));
        const std::int64_t khi = hi - st.c0, klo = lo - 1 - st.c0;
        if (khi < 1 || (khi >> s) >= std::int64_t(kMaxPhaseTicks) - 1) break;
        const i128 target = ((cum_[n] - st.cum_head) << s) - st.p0;
        i128 l = jlo, h = jhi;
        const Terms th = terms(khi, s);
        const i128 need_hi = target - b0 * th.k - a0 * th.A;   // j Gs >= need_hi
        if (th.Gs == 0) {
            if (need_hi > 0) break;
        } else {
            l = std::max(l, ceil_div(need_hi, th.Gs));
        }
        if (klo >= 1) {
            const Terms tl = terms(klo, s);
            const i128 need_lo = target - b0 * tl.k - a0 * tl.A;   // j Gs < need_lo
            if (tl.Gs == 0) {
                if (need_lo <= 0) break;
            } else {
                h = std::min(h, floor_div(need_lo - 1, tl.Gs));
            }
        }
        if (l > h) break;
        jlo = l;
        jhi = h;
        lo_run.push_back(jlo);
        hi_run.push_back(jhi);
    }
    if (n == queue_.size() && !all && cap == kNoCap) {
        tr.wait = true;
        return tr;
    }
    auto more_target = [&](std::size_t covered) {
        return st.head + covered < cum_.size() ? ((cum_[st.head + covered] - st.cum_head) << s) - st.p0 : i128{0};
    };
    auto reached = [&](std::int64_t k, i128 tgt, i128 j) {
        const Terms t = terms(k, s);
        return b0 * t.k + a0 * t.A + j * t.Gs >= tgt;
    };
    for (std::size_t covered = n - st.head; covered > 0; --covered) {
        const i128 l = lo_run[covered - 1], h = hi_run[covered - 1];
        i128 j = (l == -kInf && h == kInf) ? 0 : l == -kInf ? h : h == kInf ? l : floor_div(l + h, 2);
        // Steer toward the moves after the phase: the j that puts the next
        // few nearest the middle of their windows (least squares in p),
        // within the interval.
        double sgg = 0, sgt = 0;
        const std::size_t ahead = std::min(queue_.size(), st.head + covered + kSteerMoves);
        for (std::size_t q = st.head + covered; q < ahead; ++q) {
            const std::int64_t kn = static_cast<std::int64_t>(std::llround(queue_[q] - tol_ / 2)) - st.c0;
            if (kn < 1) continue;
            const Terms t = terms(kn, s);
            const double g = double(t.Gs);
            const double want = double(((cum_[q] - st.cum_head) << s) - st.p0 - b0 * t.k - a0 * t.A);
            sgg += g * g;
            sgt += g * want;
        }
        if (sgg > 0) {
            const double js = std::floor(sgt / sgg);
            const i128 jj = js > 1e30 ? kInf : js < -1e30 ? -kInf : i128(js);
            j = std::clamp(jj, l, h);
        }
        // The last covered move's fire clock: the first k in its window reaching its count.
        const double tau = queue_[st.head + covered - 1];
        std::int64_t khi = static_cast<std::int64_t>(std::floor(tau)) - st.c0;
        std::int64_t klo = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(tau - tol_)) - 1 - st.c0);
        const i128 target = ((cum_[st.head + covered - 1] - st.cum_head) << s) - st.p0;
        const i128 next_target = more_target(covered);
        while (khi - klo > 1) {
            const std::int64_t mid = klo + (khi - klo) / 2;
            if (reached(mid, target, j)) khi = mid; else klo = mid;
        }
        const std::int64_t E = (khi + T - 1) >> s;   // ticks
        const bool more = st.head + covered < queue_.size();
        if (more && reached(E * T, next_target, j)) continue;
        // The next phase starts before the next move's window closes.
        if (more && st.c0 + E * T >= static_cast<std::int64_t>(std::floor(queue_[st.head + covered]))) continue;
        const bool ok = phase_holds(s0, a0, j, E, fmt_);
        if (!ok) continue;
        tr.covered = covered;
        tr.j = j;
        tr.E = E;
        return tr;
    }
    return tr;
}

// The plan's position, step (S = V + H, the phase's u to come) and half
// acceleration at the open phase's start, in the timer's units: a cubic through
// the ideal times of the moves around it (least squares, up to kPlanFit before
// and after).
bool PhaseFitter::plan_state(i128& p, i128& step, i128& h) const {
    const std::size_t from = head_ >= kPlanFit ? head_ - kPlanFit : 0;
    const std::size_t to = std::min(queue_.size(), head_ + kPlanFit);
    const std::size_t m = to - from;
    if (to <= head_ || m < 2) return false;
    const double ONE = std::ldexp(1.0, int(fmt_.frac_bits));
    const double TT = double(std::int64_t{1} << fmt_.tick_log2);
    const int deg = m >= 6 ? 3 : m >= 4 ? 2 : 1;
    // Normal equations in t scaled to the window (conditioning).
    double scale = 1;
    for (std::size_t q = from; q < to; ++q) scale = std::max(scale, std::fabs(queue_[q] - double(c0_)));
    double A[4][5] = {};
    for (std::size_t q = from; q < to; ++q) {
        const double t = (queue_[q] - tol_ / 2 - double(c0_)) / scale;
        const double n = double(cum_[q] - cum_head_) / ONE;
        double pw[4] = {1, t, t * t, t * t * t};
        for (int r = 0; r <= deg; ++r) {
            for (int c = 0; c <= deg; ++c) A[r][c] += pw[r] * pw[c];
            A[r][4] += pw[r] * n;
        }
    }
    const int N = deg + 1;
    for (int c = 0; c < N; ++c) {   // Gauss-Jordan with partial pivoting
        int piv = c;
        for (int r = c + 1; r < N; ++r)
            if (std::fabs(A[r][c]) > std::fabs(A[piv][c])) piv = r;
        if (!(std::fabs(A[piv][c]) > 0)) return false;
        for (int k = 0; k < 5; ++k) std::swap(A[c][k], A[piv][k]);
        for (int r = 0; r < N; ++r) {
            if (r == c) continue;
            const double f = A[r][c] / A[c][c];
            for (int k = c; k < 5; ++k) A[r][k] -= f * A[c][k];
        }
    }
    const double n0 = A[0][4] / A[0][0];
    const double b = A[1][4] / A[1][1] / scale;
    const double c2 = deg >= 2 ? A[2][4] / A[2][2] / (scale * scale) : 0.0;
    if (!(b > 0)) return false;
    // Between the move before (fired) and the next.
    const double next = double(cum_[head_] - cum_head_) / ONE;
    const double pos = std::clamp(n0, 0.0, next * (1 - 1e-9));
    p = i128(pos * ONE * TT);
    h = i128(c2 * TT * TT * ONE);
    step = i128(b * TT * ONE) + h;   // V + H (+ u, which the phase's fit takes up)
    return true;
}

// Close phase `tr` from `from`: the state after it, its record, the figures.
void PhaseFitter::commit(const State& from, const Trial& tr, bool reload, bool adjust, i128 ds, i128 dh) {
    State after = from;
    advance(after, tr, &fires_);
    c0_ = after.c0;
    p0_ = after.p0;
    s0_ = after.s0;
    a0_ = after.a0;
    cum_head_ = after.cum_head;
    head_ = after.head;
    stats_.max_abs_accel = std::max(stats_.max_abs_accel, to_i64(abs128(a0_)));
    stats_.max_velocity = std::max(stats_.max_velocity, to_i64(s0_));
    if (reload) {
        ++stats_.reloads;
        stats_.max_abs_accel = std::max(stats_.max_abs_accel, to_i64(abs128(from.a0)));
        stats_.max_velocity = std::max(stats_.max_velocity, to_i64(from.s0));
    }
    // A reload's r = p minus the pending move's length (times 2^s), its top 64 bits.
    const unsigned r_drop = fmt_.frac_bits + fmt_.tick_log2 + 3 - 64;
    // (Right after a timed move, which fires a clock after the phase that follows it
    // loads, the card takes off the next length then: r = p.)
    const bool after_timed = !phases_.empty() && phases_.back().timed;
    const i128 pending = reload && !after_timed ? (cum_[from.head] - from.cum_head) << fmt_.tick_log2 : 0;
    phases_.push_back({std::uint64_t(tr.E), to_i64(tr.j), pending_rest_, reload, to_i64(from.s0),
                       to_i64(from.a0), reload ? to_i64((from.p0 - pending) >> r_drop) : 0, false, adjust});
    if (adjust) {
        ++stats_.adjusts;
        stats_.max_abs_adjust = std::max({stats_.max_abs_adjust, to_i64(abs128(ds)), to_i64(abs128(dh))});
    }
    stats_.rests += pending_rest_ ? 1 : 0;
    pending_rest_ = false;
    ++stats_.phases;
    stats_.moves += tr.covered;
    stats_.max_ticks = std::max<std::uint64_t>(stats_.max_ticks, std::uint64_t(tr.E));
    stats_.max_abs_jerk = std::max(stats_.max_abs_jerk, to_i64(abs128(tr.j)));
    stats_.max_phase_moves = std::max<std::uint64_t>(stats_.max_phase_moves, tr.covered);
}

// The plan's own phase from the open phase's start: the jerk in effect there,
// up to the tick nearest the plan's next change, if every move it fires lands
// in its window and the next move's window is still open at its end.
int PhaseFitter::plan_phase(bool all) {
    if (!fmt_.plan_jerk || fmt_.path_unit_mm <= 0 || fmt_.clock_hz <= 0) return 0;
    const double T = double(std::int64_t{1} << fmt_.tick_log2);
    while (changes_.size() >= 2 && changes_[1].at <= double(c0_) + T / 2) changes_.pop_front();
    if (changes_.empty() || changes_.front().at > double(c0_) + T / 2) return 0;
    if (changes_.size() < 2) return all ? 0 : -1;
    const int r = plan_phase_try(all, false);
    return r != 0 ? r : plan_phase_try(all, true);
}

// The plan's phase as it stands (adjust: V and H first set to the plan's).
int PhaseFitter::plan_phase_try(bool all, bool adjust) {
    const unsigned s = fmt_.tick_log2;
    const std::int64_t T = std::int64_t{1} << s;
    const std::int64_t E = std::max<std::int64_t>(1, std::llround((changes_[1].at - double(c0_)) / double(T)));
    if (E >= std::int64_t(kMaxPhaseTicks)) return 0;
    const double tick_s = double(T) / fmt_.clock_hz;
    const double unit = std::ldexp(1.0 / fmt_.path_unit_mm, int(fmt_.frac_bits));   // timer units per mm
    const i128 u = i128(std::llround(changes_.front().jerk * tick_s * tick_s * tick_s / 6.0 * unit));
    if (!fits(u, fmt_.u_bits)) return 0;
    State st{c0_, p0_, s0_, a0_, head_, cum_head_};
    i128 ds = 0, dh = 0;
    if (adjust) {
        const double dt = (double(c0_) - changes_.front().at) / fmt_.clock_hz;
        const double j = changes_.front().jerk;
        const double v = changes_.front().v + changes_.front().a * dt + j * dt * dt / 2,
                     a = changes_.front().a + j * dt;
        const i128 hp = i128(std::llround(a / 2 * tick_s * tick_s * unit));
        ds = i128(std::llround(v * tick_s * unit)) + hp + u - st.s0;   // the plan's S = V + H + u
        dh = hp - st.a0;
        if (ds == 0 && dh == 0) return 0;
        st.s0 += ds;
        st.a0 += dh;
    }
    auto P = [&](std::int64_t k) {
        const Terms t = terms(k, s);
        return (st.s0 - st.a0) * t.k + st.a0 * t.A + u * t.Gs;
    };
    if (!fits(st.s0, fmt_.v_bits) || !fits(st.a0, fmt_.h_bits) || !phase_holds(st.s0, st.a0, u, E, fmt_)) return 0;
    const std::int64_t kend = E * T;
    const i128 reach = P(kend);
    std::size_t covered = 0;
    for (std::size_t n = head_;; ++n) {
        if (n >= queue_.size()) return all ? 0 : -1;   // moves to come may fire within it; the last ends greedily
        const i128 target = ((cum_[n] - cum_head_) << s) - p0_;
        const double tau = queue_[n];
        const std::int64_t hi = static_cast<std::int64_t>(std::floor(tau));
        const std::int64_t lo = static_cast<std::int64_t>(std::ceil(tau - tol_));
        if (reach < target) {
            // Not within this phase: its window must still be open after it.
            if (hi <= c0_ + kend) return 0;
            break;
        }
        std::int64_t kh = kend, kl = 0;   // reached(kh), not reached(kl)
        while (kh - kl > 1) {
            const std::int64_t mid = kl + (kh - kl) / 2;
            if (P(mid) >= target) kh = mid; else kl = mid;
        }
        if (c0_ + kh > hi || c0_ + kh < lo) return 0;
        ++covered;
    }
    Trial tr;
    tr.covered = covered;
    tr.j = u;
    tr.E = E;
    commit(st, tr, false, adjust, ds, dh);
    ++stats_.plan_phases;
    return 1;
}

// Greedy: phase after phase from the open phase's state (or, where that
// times fewer moves per word, with v and a reloaded from the plan); `all`:
// the queue has no more to come.
bool PhaseFitter::fit(bool all) {
    const i128 ONE = i128{1} << fmt_.frac_bits;
    while (head_ < queue_.size()) {
        if (head_ > 4096) {   // keep the moves the plan's state is fitted to
            const std::size_t drop = head_ - kPlanFit;
            queue_.erase(queue_.begin(), queue_.begin() + std::ptrdiff_t(drop));
            cum_.erase(cum_.begin(), cum_.begin() + std::ptrdiff_t(drop));
            head_ -= drop;
        }
        if (const int taken = plan_phase(all); taken < 0) return true;
        else if (taken > 0) continue;
        const State now{c0_, p0_, s0_, a0_, head_, cum_head_};
        State from = now;
        Trial tr = evaluate(now, all);
        if (tr.wait) return true;   // the phase may go on with later moves
        bool reload = false;
        i128 pp = 0, pv = 0, pa = 0;
        if (fmt_.reload && !pending_rest_ && plan_state(pp, pv, pa)) {
            // p as the card takes it: r = p minus the pending move's length, its top
            // 64 of F + s + 3 bits (the length's low s bits are 0).
            const unsigned drop = fmt_.frac_bits + fmt_.tick_log2 + 3 - 64;
            pp = (pp >> drop) << drop;
            const State re{c0_, pp, pv, pa, head_, cum_head_};
            Trial rt = evaluate(re, all);
            if (rt.wait) return true;   // reloaded, the phase may go on with later moves
            if (tr.covered == 0 ? rt.covered > 0 : rt.covered > kReloadWords * tr.covered) {
                tr = rt;
                reload = true;
                from = re;
            }
        }
        if (tr.covered == 0) {
            // No phase times the move (the end of a stop: the position must reach
            // it within 3e-14 moves): one timed move, like a chunk's interval,
            // fires it in the middle of its window; p starts again from zero.
            const double tau = queue_[head_];
            const std::int64_t at = static_cast<std::int64_t>(std::floor(tau - tol_ / 2));
            if (at <= c0_ || at < static_cast<std::int64_t>(std::ceil(tau - tol_)) || at - c0_ >= kMaxTimedClocks) {
                error_ = fmt::format("no phase times move {} (ideal clock {:.1f}) from the state at clock {} "
                                     "(p {:.4f}, step {:.4g}, H {:.4g} moves a tick)",
                                     stats_.moves + 1, tau, c0_, double(p0_) / double(ONE),
                                     double(s0_) / double(ONE), double(a0_) / double(ONE));
                return false;
            }
            phases_.push_back({std::uint64_t(at - c0_), 0, pending_rest_, false, 0, 0, 0, true});
            pending_rest_ = false;
            fires_.push_back(at);
            c0_ = at;
            p0_ = 0;
            cum_head_ = cum_[head_];
            ++head_;
            ++stats_.phases;
            ++stats_.timed;
            ++stats_.moves;
            continue;
        }
        // A phase that runs to the edge of its moves' windows leaves a state the
        // next phase cannot carry on from: end it earlier where the next phase
        // then times more moves without a reload.
        if (fmt_.lookahead && tr.covered > 1) {
            State next = from;
            advance(next, tr, nullptr);
            const Trial nt = evaluate(next, all);
            std::size_t best = tr.covered + (nt.wait ? queue_.size() : nt.covered);
            if (!nt.wait && nt.covered * kReloadWords < tr.covered) {
                for (std::size_t d = 1; d < tr.covered; d *= 2) {
                    const Trial t2 = evaluate(from, all, tr.covered - d);
                    if (t2.covered == 0) break;
                    State n2 = from;
                    advance(n2, t2, nullptr);
                    const Trial nt2 = evaluate(n2, all);
                    const std::size_t score = t2.covered + (nt2.wait ? queue_.size() : nt2.covered);
                    if (score > best) {
                        best = score;
                        tr = t2;
                    }
                }
            }
        }
        commit(from, tr, reload);
    }
    return true;
}

// The state after phase `tr` from `st` (and each of its moves' fire clocks).
void PhaseFitter::advance(State& st, const Trial& tr, std::vector<std::int64_t>* fires) const {
    const unsigned s = fmt_.tick_log2;
    const std::int64_t T = std::int64_t{1} << s;
    const i128 s0 = st.s0, a0 = st.a0, j = tr.j;
    const std::int64_t E = tr.E;
    auto reached = [&](std::int64_t k, i128 tgt) {
        const Terms t = terms(k, s);
        return (s0 - a0) * t.k + a0 * t.A + j * t.Gs >= tgt;
    };
    if (fires) {
        for (std::size_t m = 0; m < tr.covered; ++m) {
            const double t = queue_[st.head + m];
            std::int64_t kh = static_cast<std::int64_t>(std::floor(t)) - st.c0;
            std::int64_t kl = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(t - tol_)) - 1 - st.c0);
            const i128 tg = ((cum_[st.head + m] - st.cum_head) << s) - st.p0;
            while (kh - kl > 1) {
                const std::int64_t mid = kl + (kh - kl) / 2;
                if (reached(mid, tg)) kh = mid; else kl = mid;
            }
            fires->push_back(st.c0 + kh);
        }
    }
    const Terms te = terms(E * T, s);
    const i128 P = (s0 - a0) * te.k + a0 * te.A + j * te.Gs;
    const i128 end = tr.covered > 0 ? cum_[st.head + tr.covered - 1] : st.cum_head;
    st.p0 = st.p0 + P - ((end - st.cum_head) << s);
    st.cum_head = end;
    st.s0 = s0 + 2 * a0 * i128(E) + 3 * j * i128(E) * i128(E + 1);
    st.a0 = a0 + 3 * j * i128(E);
    st.c0 += E * T;
    st.head += tr.covered;
}

std::vector<std::int64_t> simulate_phases(std::span<const TimerPhase> phases, PhaseFormat format,
                                          std::span<const i128> lengths) {
    const std::int64_t T = std::int64_t{1} << format.tick_log2;
    // The next move's length in p's units (2^-F / 2^s).
    std::size_t next = 0;
    auto threshold = [&] {
        const i128 len = next < lengths.size() ? lengths[next] : i128{1} << format.frac_bits;
        return len << format.tick_log2;
    };
    i128 p = 0, step = 0, h = 0;   // p, the step S, H
    bool after_timed = false;      // the phase before was a timed move
    std::int64_t clock = 0;
    std::vector<std::int64_t> fires;
    for (const TimerPhase& ph : phases) {
        if (ph.rest) p = step = h = 0;
        if (ph.adjust) {
            step = ph.s;
            h = ph.a;
        }
        if (ph.reload) {
            p = (i128(ph.r_top) << (format.frac_bits + format.tick_log2 + 3 - 64)) + (after_timed ? 0 : threshold());
            step = ph.s;
            h = ph.a;
        }
        after_timed = ph.timed;
        if (ph.timed) {   // a move after `ticks` clocks
            clock += std::int64_t(ph.ticks);
            fires.push_back(clock);
            ++next;
            p = 0;
            continue;
        }
        const i128 u = ph.jerk;
        for (std::uint64_t t = 0; t < ph.ticks; ++t) {
            for (std::int64_t c = 0; c < T; ++c) {
                ++clock;
                p += step;
                if (const i128 th = threshold(); p >= th) {
                    fires.push_back(clock);
                    ++next;
                    p -= th;
                }
            }
            step += 2 * h + 6 * u;
            h += 3 * u;
        }
    }
    return fires;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/conic_arc.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "model/cp_conic.h"
#include "model/cp_conic_serial.h"

namespace cpstep::plan {

namespace {

using model::CpConic;
using model::CpConicSerial;
using model::i128;

// Circles are scaled by 256 (A = C = 256): a centre on the 1/16-step grid gives
// integer D, E and F exactly (docs/CONIC.md §7); the radius is rounded to F's
// unit, 1/(512 r) steps.
constexpr std::int64_t kScale = 256;
constexpr double kCentreGrid = 16;
// Smallest radius walked as a conic (steps): below a few steps the walk can turn
// back inside one square (docs/CONIC.md §3), and chords are as good.
constexpr double kMinRadiusSteps = 4;
// Smallest piece a helix is split into before it is left to chords.
constexpr std::size_t kMinPieceMoves = 16;

bool fits_signed(i128 v, unsigned bits) {
    const i128 lim = i128(1) << (bits - 1);
    return v >= -lim && v < lim;
}

CpConic::Coeffs coeffs_of(const ConicWalk& w) { return {w.a, w.b, w.c, w.d, w.e, w.f}; }

// Progress along the arc's sweep of the point (x, y) (steps), in radians, from the
// angle `from`, unwrapped near `near`; `k` = su / sv stretches v into u's steps, where
// the arc is a circle (its angle is the G-code's, in mm).
double progress(double x, double y, double cu, double cv, double k, double from, bool cw, double near) {
    double p = std::atan2(k * (y - cv), x - cu) - from;
    if (cw) p = -p;
    constexpr double two_pi = 2 * std::numbers::pi;
    p -= two_pi * std::round((p - near) / two_pi);
    return p;
}

// The best fraction p / q of x with p, q <= limit (continued fractions).
std::pair<std::int64_t, std::int64_t> best_fraction(double x, std::int64_t limit) {
    std::int64_t p0 = 0, q0 = 1, p1 = 1, q1 = 0;
    double f = x;
    for (int it = 0; it < 64; ++it) {
        const double a = std::floor(f);
        const std::int64_t ai = std::int64_t(a);
        const std::int64_t p2 = ai * p1 + p0, q2 = ai * q1 + q0;
        if (p2 > limit || q2 > limit) break;
        p0 = p1, q0 = q1, p1 = p2, q1 = q2;
        if (f - a < 1e-12) break;
        f = 1 / (f - a);
    }
    return {p1, q1};
}

}  // namespace

double ConicWalk::off_curve(double x, double y) const {
    const double du_ = x - centre_u, dv_ = stretch_v * (y - centre_v);
    if (stretch_v == 1) return std::abs(std::hypot(du_, dv_) - radius);
    // An ellipse in steps: first order, |G| / |grad G| of (x - cu)^2 + (k (y - cv))^2 - r^2.
    const double gval = du_ * du_ + dv_ * dv_ - radius * radius;
    const double gx = 2 * du_, gy = 2 * stretch_v * dv_;
    const double n = std::hypot(gx, gy);
    return n > 0 ? std::abs(gval) / n : radius;
}

std::array<std::uint32_t, 7> ConicWalk::words() const {
    const CpConic::Coeffs k = coeffs_of(*this);
    return CpConicSerial::words(k, CpConic::at(k, u0, v0), cw, du, dv);
}

std::vector<std::uint64_t> conic_rule_divisors(const ConicWalk& w) {
    const auto m = [&](std::int64_t x, std::int64_t y) {
        const std::int64_t gx = 2 * w.a * x + w.b * y + w.d, gy = w.b * x + 2 * w.c * y + w.e;
        return std::uint64_t(std::max(std::abs(gx), std::abs(gy)));
    };
    std::vector<std::uint64_t> out;
    out.reserve(w.moves.size());
    std::int64_t x = w.u0, y = w.v0;
    for (std::uint8_t mv : w.moves) {
        out.push_back(m(x, y));   // the node the move leaves
        x += ConicWalk::dx_of(mv);
        y += ConicWalk::dy_of(mv);
    }
    return out;
}

std::uint32_t conic_rule_length(std::uint32_t word, std::uint64_t m) {
    __extension__ typedef unsigned __int128 u128;
    if (m == 0) return 0xFFFFFFFFu;
    const u128 q = (u128(word & ((1u << 27) - 1)) << (word >> 27)) / m;
    return q > 0xFFFFFFFFu ? 0xFFFFFFFFu : std::uint32_t(q);
}

std::variant<ConicRuleLengths, std::string> conic_rule_lengths(std::span<const std::uint64_t> divisors,
                                                               double total) {
    long double inv = 0;
    for (std::uint64_t m : divisors) {
        if (m == 0) return std::string("a node of its walk has no gradient (the length rule divides by it)");
        inv += 1.0L / static_cast<long double>(m);
    }
    if (divisors.empty() || !(total > 0)) return std::string("no path to measure");
    // K 2^S = total / sum(1/m): K below 2^27, as many of its bits as S allows.
    const long double x = static_cast<long double>(total) / inv;
    int s = 0;
    while (s < 31 && std::ldexp(x, -s) >= std::ldexp(1.0L, 27) - 0.5L) ++s;
    const long double kf = std::nearbyint(std::ldexp(x, -s));
    if (!(kf >= 1) || kf >= std::ldexp(1.0L, 27))
        return fmt::format("its length rule's constant ({:.4g}) does not fit K [26:0] 2^S [31:27]", double(x));
    ConicRuleLengths out;
    out.word = std::uint32_t(s) << 27 | std::uint32_t(kf);
    out.lengths.reserve(divisors.size());
    for (std::uint64_t m : divisors) {
        const std::uint32_t l = conic_rule_length(out.word, m);
        if (l == 0 || l == 0xFFFFFFFFu)
            return fmt::format("a move's length by the rule ({} / {}) does not fit the 32-bit length", double(x), m);
        out.lengths.push_back(l);
    }
    return out;
}

ConicWalk ConicWalk::head(std::size_t n) const {
    ConicWalk h = *this;
    h.moves.resize(n);
    h.ideal.resize(n);
    h.du = h.dv = 0;
    for (std::uint8_t m : h.moves) h.du += dx_of(m), h.dv += dy_of(m);
    return h;
}

ConicWalk ConicWalk::tail(std::size_t n) const {
    ConicWalk t = *this;
    for (std::size_t j = 0; j < n; ++j) t.u0 += dx_of(moves[j]), t.v0 += dy_of(moves[j]);
    t.moves.assign(moves.begin() + std::ptrdiff_t(n), moves.end());
    t.ideal.assign(ideal.begin() + std::ptrdiff_t(n), ideal.end());
    t.du = (u0 + du) - t.u0;
    t.dv = (v0 + dv) - t.v0;
    t.cont = true;
    return t;
}

std::variant<std::vector<ConicPiece>, std::string> plan_conic_arc(const ConicArcInput& in, const Machine& m,
                                                                  ConicArcStats* stats) {
    const MotionBlock& b = *in.block;
    if (in.ciw == 0) return std::string("the card has no conic walker");
    if (in.chords.empty() || in.chords.size() != in.feeds.size()) return std::string("no chords planned");
    if (in.chords.front().from_mm != b.start || in.chords.back().to_mm != b.end)
        return std::string("an end of it shares a step with the block beside it");
    const ArcGeom g = arc_geom(b);
    const int u = int(g.u), v = int(g.v);
    const double su = m.axes[u].steps_per_mm, sv = m.axes[v].steps_per_mm;
    if (!m.axes[u].present || !m.axes[v].present) return std::string("the arc's plane has an axis the machine lacks");

    if (std::abs(g.r1 - g.r0) * su > 0.25)
        return fmt::format("its end radii differ by {:.3g} steps (a spiral)", std::abs(g.r1 - g.r0) * su);

    // The curve on the card. In u's steps, with v stretched by k = su / sv, the arc is
    // the G-code's circle: (x - cu)^2 + (k (y - cv))^2 = r^2. Equal steps/mm (k = 1):
    // A = C = 256, the centre on the 1/16-step grid (D, E, F exact). Otherwise an
    // ellipse in steps: C / A = k^2 as a fraction p / q of at most 32767 (exact for
    // steps/mm whose squares have a small ratio, 80 and 400: 1/25), the radius is the
    // G-code's within 0.05 step or the arc is left to chords, A as large as the
    // walker's 16-bit coefficients and 32-bit load words allow.
    const double k = su / sv;
    const bool circle = std::abs(k - 1) <= 1e-12;
    const double cu = g.cx * su, cv = g.cy * sv;  // exact centre, steps
    const double r = g.r0 * su;                   // in u's steps
    if (!(r >= kMinRadiusSteps) || !(r / k >= kMinRadiusSteps))
        return fmt::format("its radius is {:.3g} steps (conics from {:g})", std::min(r, r / k), kMinRadiusSteps);
    ConicWalk w;
    w.axis_u = u;
    w.axis_v = v;
    w.cw = g.cw;
    w.u0 = in.start[u];
    w.v0 = in.start[v];
    w.centre_u = cu;
    w.centre_v = cv;
    w.radius = r;
    w.stretch_v = circle ? 1.0 : k;
    double gu = cu, gv = cv;  // the card's centre
    std::function<std::int64_t(long double)> f_of;  // F for a radius (u's steps) squared
    if (circle) {
        const auto i = std::int64_t(std::llround(cu * kCentreGrid)), j = std::int64_t(std::llround(cv * kCentreGrid));
        gu = double(i) / kCentreGrid;
        gv = double(j) / kCentreGrid;
        w.a = w.c = kScale;
        w.d = -2 * kScale / std::int64_t(kCentreGrid) * i;
        w.e = -2 * kScale / std::int64_t(kCentreGrid) * j;
        f_of = [i, j](long double r2) { return i * i + j * j - std::int64_t(std::llroundl((long double)kScale * r2)); };
    } else {
        const auto [pp, qq] = best_fraction(k * k, 32767);
        if (pp <= 0 || qq <= 0) return fmt::format("no ratio of 16-bit coefficients for steps/mm {:g} and {:g}", su, sv);
        // Shape: the v semi-axis in steps is r / k; with C / A = p / q it is r sqrt(q / p).
        const double v_err = std::abs(r * std::sqrt(double(qq) / double(pp)) - r / k);
        if (v_err > 0.05)
            return fmt::format("steps/mm {:g} and {:g} make an ellipse whose axes' ratio 16-bit coefficients miss "
                               "by {:.3g} steps",
                               su, sv, v_err);
        const std::int64_t big = std::max(pp, qq);
        const double span = r + std::max(std::abs(double(w.u0) - cu), std::abs(double(w.v0) - cv)) + 4;
        const std::int64_t mult =
            std::min<std::int64_t>(32767 / big, std::int64_t(std::floor(double(1 << 29) / (span * double(big)))));
        if (mult < 1) return std::string("it is too large for the walker's 32-bit load words as an ellipse");
        w.a = qq * mult;
        w.c = pp * mult;
        w.d = std::llround(-2.0L * w.a * cu);
        w.e = std::llround(-2.0L * w.c * cv);
        gu = -double(w.d) / (2.0 * double(w.a));
        gv = -double(w.e) / (2.0 * double(w.c));
        const long double a_ = w.a, c_ = w.c, gu_ = gu, gv_ = gv;
        f_of = [a_, c_, gu_, gv_](long double r2) {
            return std::int64_t(std::llroundl(a_ * gu_ * gu_ + c_ * gv_ * gv_ - a_ * r2));
        };
    }
    w.f = f_of((long double)r * r);
    CpConic::Coeffs kc = coeffs_of(w);
    CpConic::Node node = CpConic::at(kc, w.u0, w.v0);
    if (!CpConic::on_curve(kc, node)) {
        // The radius moved towards the start node's d0 until the node passes: d0 less
        // 0.45 step first (the walk then stays within |d0 - r| - 0.45 + 0.5 of the
        // G-code's curve), through d0 itself (a curve through the node).
        const long double d0 = std::hypot((long double)w.u0 - gu, (long double)(w.stretch_v * (double(w.v0) - gv)));
        bool passed = false;
        for (const long double back : {0.45L, 0.4L, 0.3L, 0.2L, 0.1L, 0.0L}) {
            const long double rr = d0 - (d0 > (long double)r ? back : -back);
            w.f = f_of(rr * rr);
            kc = coeffs_of(w);
            node = CpConic::at(kc, w.u0, w.v0);
            if ((passed = CpConic::on_curve(kc, node))) break;
        }
        if (!passed) return std::string("its start node is not on the walker's curve");
    }
    if (!fits_signed(node.g, 32) || !fits_signed(node.gx, 32) || !fits_signed(node.gy, 32))
        return std::string("its start values exceed the walker's 32-bit load words");

    // The walk, to just past the end of the sweep.
    const double from = g.a0;  // progress 0: the G-code's start point (angles are the same in steps)
    const double margin = 3 / std::min(r, r / k);
    const double end_u = b.end[std::size_t(u)] * su, end_v = b.end[std::size_t(v)] * sv;  // exact end, steps
    const std::size_t max_moves = std::size_t(8 * (std::max(r, r / k) + 2) * g.sweep) + 64;
    std::vector<std::pair<std::int64_t, std::int64_t>> nodes{{w.u0, w.v0}};
    std::vector<double> prog{progress(double(w.u0), double(w.v0), cu, cv, w.stretch_v, from, w.cw, 0)};
    // The end node: the arc's end rounded to steps (where its chords end and the
    // next block starts) when the walk passes it near the end of the sweep, else
    // the walk's node nearest the exact end point (the next block then starts there;
    // an arc the job ends on must end on its rounded end).
    const PerAxis<std::int64_t> end = in.chords.back().end;
    std::size_t best = 0, rounded = 0;
    double best_d = std::numeric_limits<double>::infinity();
    std::int64_t x = w.u0, y = w.v0;
    double p = prog[0], worst_node = w.off_curve(double(w.u0), double(w.v0));
    while (true) {
        if (!CpConicSerial::fits(kc, node, in.ciw))
            return fmt::format("its values exceed the walker's {} bits", in.ciw);
        int dx = 0, dy = 0;
        CpConicSerial::rule(kc, node, w.cw, in.ciw, dx, dy);
        if (dx == 0 && dy == 0) return std::string("the walk stops (the gradient vanishes)");
        node = CpConic::advance(kc, node, dx, dy);
        x += dx;
        y += dy;
        w.moves.push_back(ConicWalk::pack(dx, dy));
        p = progress(double(x), double(y), cu, cv, w.stretch_v, from, w.cw, p);
        nodes.emplace_back(x, y);
        prog.push_back(p);
        worst_node = std::max(worst_node, w.off_curve(double(x), double(y)));
        if (std::abs(p - g.sweep) <= margin) {
            const double dd = std::hypot(double(x) - end_u, double(y) - end_v);
            if (dd < best_d) best_d = dd, best = w.moves.size();
            if (x == end[std::size_t(u)] && y == end[std::size_t(v)] && rounded == 0) rounded = w.moves.size();
        }
        if (p > g.sweep + margin) break;
        if (w.moves.size() > max_moves) return std::string("the walk does not come round to its end");
    }
    if (rounded) best = rounded;
    else if (in.last_motion) return std::string("the job ends on it and its walk misses the end's step");
    if (best == 0 || !(best_d <= 1.5)) return fmt::format("the walk passes {:.3g} steps from its end", best_d);
    const std::size_t T = best;
    for (std::size_t n = 1; n < T; ++n)
        if (nodes[n] == nodes[T]) return std::string("the walk visits its end node before its end");
    w.moves.resize(T);
    w.du = nodes[T].first - w.u0;
    w.dv = nodes[T].second - w.v0;
    if (!fits_signed(w.du, 24) || !fits_signed(w.dv, 24)) return std::string("it spans more than 2^23 steps");

    // The other axes (a helix's): each steps by a pattern over the piece's moves; its
    // ideal position at node n follows the sweep.
    const double sweep = g.sweep;
    const auto ideal_other = [&](std::size_t a, std::size_t n) {
        const double s = m.axes[a].steps_per_mm;
        const double f = std::clamp(prog[n] / sweep, 0.0, 1.0);
        return (b.start[a] + (b.end[a] - b.start[a]) * f) * s;
    };
    bool helix = false;
    for (std::size_t a = 0; a < std::size_t(kAxes); ++a)
        if (int(a) != u && int(a) != v && end[a] != in.start[a]) helix = true;
    std::size_t max_piece = in.umax;
    if (helix) max_piece = std::min<std::size_t>(max_piece, in.w);
    // Piece boundaries fall where every other axis's ideal position is nearest a
    // whole step (within an eighth of a piece of the even split), so that each
    // piece's pattern runs between lattice points close to the helix, as the GCD
    // split of a line does (reduce.h); the pieces are planned a quarter shorter than
    // the limit to leave that room.
    std::size_t pieces = helix ? (4 * T + 3 * max_piece - 1) / (3 * max_piece) : (T + max_piece - 1) / max_piece;
    const auto off_lattice = [&](std::size_t n) {
        double worst = 0;
        for (std::size_t a = 0; a < std::size_t(kAxes); ++a) {
            if (int(a) == u || int(a) == v || end[a] == in.start[a]) continue;
            const double at_n = ideal_other(a, n);
            worst = std::max(worst, std::abs(at_n - std::floor(at_n + 0.5)));
        }
        return worst;
    };
    // Moves per step of the fastest other axis: the window a boundary needs to find
    // a node near a whole step.
    std::int64_t rise = 0;
    for (std::size_t a = 0; a < std::size_t(kAxes); ++a)
        if (int(a) != u && int(a) != v) rise = std::max(rise, std::abs(end[a] - in.start[a]));
    const std::size_t per_step = rise > 0 ? T / std::size_t(rise) + 1 : T;
    // Splits of twice as many pieces are tried until every other axis stays within
    // half a step (+ split_epsilon_steps) of its line along the sweep; the best one
    // is kept if that never happens, when it is within a step (as a line's GCD split,
    // reduce.h, allows up to a step where nothing closer exists).
    std::vector<std::size_t> at;              // piece boundaries (move indices)
    std::vector<PerAxis<std::int64_t>> pos;   // the other axes at each boundary
    double worst_other = std::numeric_limits<double>::infinity();
    bool steep = false;
    for (std::size_t tries = pieces; pieces == tries || T / tries >= kMinPieceMoves; tries *= 2) {
        std::vector<std::size_t> at_t;
        std::vector<PerAxis<std::int64_t>> pos_t;
        const std::size_t L = T / tries;
        const std::size_t reach =
            std::min(max_piece > L ? (max_piece - L) / 2 : 0, std::max(L / 8, std::min(per_step, L / 3)));
        for (std::size_t q = 0; q <= tries; ++q) {
            std::size_t n = T * q / tries;
            if (helix && q > 0 && q < tries) {
                std::size_t bestn = n;
                for (std::size_t c = n - std::min(reach, n - at_t.back() - 1); c <= n + reach && c < T; ++c)
                    if (off_lattice(c) < off_lattice(bestn)) bestn = c;
                n = bestn;
            }
            at_t.push_back(n);
            PerAxis<std::int64_t> pa = in.start;
            for (std::size_t a = 0; a < std::size_t(kAxes); ++a) {
                if (int(a) == u || int(a) == v) continue;
                if (q == tries) pa[a] = end[a];
                else if (q > 0 && end[a] != in.start[a]) pa[a] = std::int64_t(std::floor(ideal_other(a, n) + 0.5));
            }
            pos_t.push_back(pa);
        }
        double worst = 0;
        bool steep_t = false;
        for (std::size_t q = 0; q < tries; ++q) {
            const std::uint64_t len = at_t[q + 1] - at_t[q];
            for (std::size_t a = 0; a < std::size_t(kAxes); ++a) {
                if (int(a) == u || int(a) == v) continue;
                const std::int64_t d = pos_t[q + 1][a] - pos_t[q][a];
                const std::uint64_t ad = std::uint64_t(d < 0 ? -d : d);
                if (ad > len) steep_t = true;
                if (d == 0 && ideal_other(a, at_t[q]) == ideal_other(a, at_t[q + 1])) continue;
                for (std::uint64_t n = 1; n <= len; ++n) {
                    // The pattern's position after move n of len: floor((2 v n + len) / (2 len)).
                    const auto stepped = std::int64_t((2 * ad * n + len) / (2 * len));
                    const double card = double(pos_t[q][a] + (d < 0 ? -stepped : stepped));
                    worst = std::max(worst, std::abs(card - ideal_other(a, at_t[q] + n)));
                }
            }
        }
        if (steep_t) {
            steep = true;
            continue;
        }
        if (worst < worst_other) {
            worst_other = worst;
            at = std::move(at_t);
            pos = std::move(pos_t);
            pieces = tries;
        }
        if (worst_other <= 0.5 + m.planner.split_epsilon_steps) break;
    }
    if (at.empty()) {
        if (steep) return std::string("its other axes move more steps than its plane's walk has moves");
        return std::string("no split of it keeps its other axes near their lines");
    }
    if (!(worst_other <= 1.0))
        return fmt::format("its other axes stray {:.3g} steps from their lines in every split tried", worst_other);

    // Ideal times, as a line's moves are timed (steptime.h: move i of T when the path
    // reaches i/T of its length, i.e. where the line's major coordinate reaches the
    // move's): a node is due where the circle reaches the node's coordinate along the
    // axis its octant steps every move (y where the tangent is nearer y, else x), so
    // that moves a whole step apart on that axis come at an even pace and the chunks
    // fit them as they fit a line's, however the walk mixes axial and combined moves.
    // That point's progress along the sweep falls on a chord; the chord's feed
    // profile times it at the same fraction of the chord.
    const auto timing_progress = [&](std::size_t n, double near) {
        // In u's steps with v stretched (a circle of radius r): v steps every move
        // where |x| / k >= |k y|, i.e. its speed in steps is the larger.
        const double xs = double(nodes[n].first) - cu, ys = w.stretch_v * (double(nodes[n].second) - cv);
        double px = xs, py = ys;
        if (std::abs(xs) >= w.stretch_v * std::abs(ys)) {  // v steps every move: keep it
            py = std::clamp(ys, -r, r);
            px = std::copysign(std::sqrt(std::max(0.0, r * r - py * py)), xs);
        } else {
            px = std::clamp(xs, -r, r);
            py = std::copysign(std::sqrt(std::max(0.0, r * r - px * px)), ys);
        }
        return progress(px + cu, py / w.stretch_v + cv, cu, cv, w.stretch_v, from, w.cw, near);
    };
    std::vector<double> chord_end(in.chords.size());
    {
        double q = 0;
        for (std::size_t c = 0; c < in.chords.size(); ++c) {
            const auto& to = in.chords[c].to_mm;
            q = progress(to[std::size_t(u)] * su, to[std::size_t(v)] * sv, cu, cv, w.stretch_v, from, w.cw, q);
            chord_end[c] = q;
        }
        chord_end.back() = std::max(chord_end.back(), prog[T]);
    }
    w.ideal.resize(T);
    const double gap = double(conic_gap_cycles(in.ciw)) + in.tolerance_cycles;
    double chord_start = 0;
    std::size_t c = 0;
    for (std::size_t n = 1; n <= T; ++n) {
        double t;
        if (n == T) {
            const PlannedSegment& f = in.feeds.back();
            t = (f.t_start + f.profile.duration) * in.clock_hz;
        } else {
            const double pn = std::clamp(timing_progress(n, prog[n]), 0.0, chord_end.back());
            while (c + 1 < in.chords.size() && pn > chord_end[c]) chord_start = chord_end[c], ++c;
            const PlannedSegment& f = in.feeds[c];
            const double span = chord_end[c] - chord_start;
            const double frac = span > 0 ? std::clamp((pn - chord_start) / span, 0.0, 1.0) : 1.0;
            t = (f.t_start + f.profile.time_at(f.length * frac)) * in.clock_hz;
        }
        if (n > 1 && !(t - w.ideal[n - 2] >= gap))
            return fmt::format("its moves come faster than the walker's one in {} cycles", std::uint64_t(gap));
        w.ideal[n - 1] = t;
    }

    if (stats) {
        stats->max_node_deviation = std::max(stats->max_node_deviation, worst_node);
        stats->max_other_deviation = std::max(stats->max_other_deviation, worst_other);
    }
    std::vector<ConicPiece> out;
    out.reserve(pieces);
    ConicWalk rest = std::move(w);
    for (std::size_t q = 0; q < pieces; ++q) {
        const std::size_t L = at[q + 1] - at[q];
        ConicWalk piece = q + 1 < pieces ? rest.head(L) : rest;
        if (q + 1 < pieces) rest = rest.tail(L);
        ConicPiece cp;
        CardSegment& s = cp.segment;
        s.major = u;
        s.moves = std::uint32_t(L);
        s.first_move = std::uint32_t(at[q]);
        s.loc = b.loc;
        s.step_segment = in.first_step_segment;
        for (std::size_t a = 0; a < std::size_t(kAxes); ++a) {
            const std::int64_t d = int(a) == u ? piece.du : int(a) == v ? piece.dv : pos[q + 1][a] - pos[q][a];
            s.delta[a] = d;
            s.dir_positive[a] = d >= 0;
            s.u[a] = std::uint32_t(L);
            s.v[a] = (int(a) == u || int(a) == v) ? 0 : std::uint32_t(d < 0 ? -d : d);
        }
        cp.walk = std::make_shared<const ConicWalk>(std::move(piece));
        out.push_back(std::move(cp));
    }
    return out;
}

}  // namespace cpstep::plan

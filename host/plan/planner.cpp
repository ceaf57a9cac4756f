// SPDX-License-Identifier: MIT
#include "plan/planner.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "plan/window.h"

namespace cpstep::plan {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

PerAxis<double> direction(const PerAxis<std::int64_t>& d, const Machine& m) {
    PerAxis<double> u{};
    double n = 0;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (!m.axes[a].present) continue;
        u[a] = static_cast<double>(d[a]) / m.axes[a].steps_per_mm;
        n += u[a] * u[a];
    }
    n = std::sqrt(n);
    if (n > 0) {
        for (auto& x : u) x /= n;
    }
    return u;
}

// Each axis's travel per mm of path when the segment is timed over `length`
// mm (the unit direction when length is the quantized length).
PerAxis<double> along(const PerAxis<std::int64_t>& d, double length, const Machine& m) {
    if (!(length > 0)) return direction(d, m);
    PerAxis<double> u{};
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (!m.axes[a].present) continue;
        u[a] = static_cast<double>(d[a]) / m.axes[a].steps_per_mm / length;
    }
    return u;
}

SegmentLimits limits_of(const PerAxis<double>& u, const Machine& m) {
    SegmentLimits l{kInf, kInf, kInf};
    for (std::size_t a = 0; a < kAxes; ++a) {
        const double c = std::abs(u[a]);
        if (c == 0) continue;
        l.v = std::min(l.v, m.axes[a].max_velocity / c);
        l.a = std::min(l.a, m.axes[a].max_accel / c);
        l.j = std::min(l.j, m.axes[a].max_jerk / c);
    }
    return l;
}

double card_limit_of(const PerAxis<double>& u, const Machine& m) {
    double v = kInf;
    for (std::size_t a = 0; a < kAxes; ++a) {
        const double c = std::abs(u[a]);
        if (c == 0) continue;
        const auto& ax = m.axes[a];
        const double period = static_cast<double>(ax.pulse.step_high) +
                              static_cast<double>(ax.pulse.step_low) + m.chunk_tolerance_cycles();
        v = std::min(v, m.card.clock_hz / period / ax.steps_per_mm / c);
    }
    return v;
}

}  // namespace

PerAxis<double> path_direction(const StepSegment& s, const Machine& m) {
    PerAxis<double> d{};
    double nn = 0;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (!m.axes[a].present) continue;
        d[a] = s.to_mm[a] - s.from_mm[a];
        nn += d[a] * d[a];
    }
    nn = std::sqrt(nn);
    if (!(nn > 0)) return direction(s.delta(), m);
    for (auto& x : d) x /= nn;
    return d;
}

double time_lower_bound(const std::vector<StepSegment>& segs, const Machine& m, std::size_t first,
                        std::size_t last) {
    const std::size_t n = segs.size();
    last = std::min(last, n);
    if (first >= last) return 0;
    double a_max = 0, j_max = 0;
    for (const auto& ax : m.axes) {
        if (!ax.present) continue;
        a_max = std::max(a_max, ax.max_accel);
        j_max = std::max(j_max, ax.max_jerk);
    }
    std::vector<double> L(n, 0), A(n, 0), cap(n, 0), jn(n + 1, 0), dwell(n, 0);
    std::vector<PerAxis<double>> dir(n);
    for (std::size_t i = 0; i < n; ++i) {
        const StepSegment& s = segs[i];
        if (s.kind == MotionKind::dwell) { dwell[i] = s.dwell_s; continue; }
        L[i] = s.planned_length_mm(m);
        const SegmentLimits l = project_limits(s.delta(), L[i], m);
        A[i] = l.a;
        double c = std::min(l.v, card_speed_limit(s.delta(), L[i], m));
        if (s.kind != MotionKind::rapid) c = std::min(c, s.feed);
        cap[i] = std::min(c, curvature_speed(s.radius_ends_max_mm, a_max, j_max));
        dir[i] = path_direction(s, m);
    }
    for (std::size_t i = 1; i < n; ++i) {
        const StepSegment& a = segs[i - 1];
        const StepSegment& b = segs[i];
        if (a.kind == MotionKind::dwell || b.kind == MotionKind::dwell || a.spindle_on != b.spindle_on) continue;
        jn[i] = std::min({junction_speed(dir[i - 1], dir[i], std::min(A[i - 1], A[i]),
                                         m.planner.junction_deviation_mm),
                          cap[i - 1], cap[i]});
    }
    // Acceleration-limited (jerk relaxed) passes: v^2 changes by at most 2 A L.
    // A part of the job starts and ends no faster than its junctions allow.
    std::vector<double> e(n + 1, 0);
    e[last] = last < n ? jn[last] : 0;
    for (std::size_t k = last; k-- > first;) {
        e[k] = dwell[k] > 0 || L[k] == 0 ? 0 : std::min(jn[k], std::sqrt(e[k + 1] * e[k + 1] + 2 * A[k] * L[k]));
    }
    double t = 0, v0 = first > 0 ? jn[first] : 0;
    for (std::size_t k = first; k < last; ++k) {
        if (L[k] == 0) { t += dwell[k]; v0 = 0; continue; }
        v0 = std::min(v0, e[k]);
        const double v1 = std::min(e[k + 1], std::sqrt(v0 * v0 + 2 * A[k] * L[k]));
        const double vp = std::min(cap[k], std::sqrt((2 * A[k] * L[k] + v0 * v0 + v1 * v1) / 2));
        const double d_up = (vp * vp - v0 * v0) / (2 * A[k]), d_dn = (vp * vp - v1 * v1) / (2 * A[k]);
        t += (vp - v0) / A[k] + (vp - v1) / A[k] + std::max(0.0, L[k] - d_up - d_dn) / vp;
        v0 = v1;
    }
    return t;
}

SegmentLimits project_limits(const PerAxis<std::int64_t>& delta, const Machine& m) {
    return limits_of(direction(delta, m), m);
}

SegmentLimits project_limits(const PerAxis<std::int64_t>& delta, double length, const Machine& m) {
    return limits_of(along(delta, length, m), m);
}

double card_speed_limit(const PerAxis<std::int64_t>& delta, const Machine& m) {
    return card_limit_of(direction(delta, m), m);
}

double card_speed_limit(const PerAxis<std::int64_t>& delta, double length, const Machine& m) {
    return card_limit_of(along(delta, length, m), m);
}

double curvature_speed(double r, double a, double j) {
    if (!(r < std::numeric_limits<double>::infinity())) return std::numeric_limits<double>::infinity();
    return std::min(std::sqrt(a * r), std::cbrt(j * r * r));
}

double polyline_radius(const PerAxis<double>& in, const PerAxis<double>& out, double chord) {
    double dot = 0;
    for (std::size_t i = 0; i < kAxes; ++i) dot += in[i] * out[i];
    const double half_sin = std::sqrt(std::max(0.0, (1 - std::clamp(dot, -1.0, 1.0)) / 2));
    if (half_sin < 1e-12) return std::numeric_limits<double>::infinity();
    return chord / (2 * half_sin);
}

double reversal_speed(double u, const AxisConfig& axis, double a, const Machine& m) {
    const double c = std::abs(u);
    if (!(c > 0) || !(axis.steps_per_mm > 0)) return kInf;
    const PulseTimingCycles& p = axis.pulse;
    const double gap_cycles =
        static_cast<double>(p.step_high) +
        std::max<double>(std::max<std::uint32_t>(p.dir_hold, 1) + std::max<std::uint32_t>(p.dir_setup, 1),
                         p.step_low) +
        m.chunk_tolerance_cycles();
    const double need_s = gap_cycles / m.card.clock_hz;
    const double d = 0.5 / (axis.steps_per_mm * c);  // mm of path for half a step of the axis
    const double v_d = d / need_s;                   // the fastest speed over d
    const double v2 = v_d * v_d - 2 * a * d;
    return v2 > 0 ? std::sqrt(v2) : 0.0;
}

double junction_speed(const PerAxis<double>& in, const PerAxis<double>& out, double a,
                      double deviation) {
    double dot = 0;
    for (std::size_t i = 0; i < kAxes; ++i) dot += in[i] * out[i];
    const double cos_theta = -dot;  // theta: angle between the reversed incoming and outgoing
    if (cos_theta > 0.999999) return 0;       // a reversal
    if (cos_theta < -0.999999) return kInf;   // straight on
    const double sin_half = std::sqrt((1 - cos_theta) / 2);
    return std::sqrt(a * deviation * sin_half / (1 - sin_half));
}

CurvatureBudget curvature_budget(double r, double v, const SegmentLimits& tangent, double a_normal,
                                 double j_normal) {
    CurvatureBudget b{v, tangent.a, tangent.j};
    if (!(r < kInf)) return b;
    const double k = 1 / r;
    b.v = std::min(v, curvature_speed(r, kCurvatureShare * a_normal, kCurvatureShare * j_normal));
    // Along a path of curvature k at speed v the acceleration is a_t T + k v^2 N
    // and the jerk (j_t - k^2 v^3) T + 3 k v a_t N (the change of k itself left
    // out). T and N are orthogonal unit vectors, so every axis stays within its
    // limits when the vectors' lengths stay within the smallest axis limits.
    const double an = k * b.v * b.v;
    b.a = std::min(tangent.a, std::sqrt(std::max(0.0, a_normal * a_normal - an * an)));
    const double fj = k * k * b.v * b.v * b.v / j_normal;  // <= kCurvatureShare
    // (J_t + k^2 v^3)^2 + (3 k v A_t)^2 <= J^2: on the circle J_t = J (cos phi - fj),
    // 3 k v A_t = J sin phi; phi keeps A_t / J_t at the axes' own ratio.
    const double ra = 3 * k * b.v;
    const double q = ra * tangent.a / tangent.j;
    const double phi = std::atan(q) - std::asin(std::min(1.0, q * fj / std::sqrt(1 + q * q)));
    b.a = std::min(b.a, j_normal * std::sin(phi) / ra);
    b.j = std::min(tangent.j, j_normal * std::max(0.0, std::cos(phi) - fj));
    return b;
}

double stop_distance(double v, double A, double J) { return ramp(v, 0, A, J).distance; }

using detail::Window;

struct FeedPlanner::Impl {
    // What planning needs of a step segment, and what it derives for it (a
    // PlannedSegment's fields but the times and the profile).
    struct Seg {
        MotionKind kind = MotionKind::linear;
        bool spindle_on = false;
        SourceLoc loc;
        double dwell_s = 0;
        PerAxis<std::int64_t> delta{};
        double radius_start = kInf;  // StepSegment::radius_start_mm
        double length = 0, radius = kInf, cruise = 0;
        SegmentLimits limits;
        PerAxis<double> dir{};  // unrounded direction, mm
        double junction = 0;    // speed cap at its start
        char smooth = 0;        // the path goes on smoothly at its start
    };
    // Runs of segments joined smoothly whose cruise caps lie within a ratio
    // 1 + kSpanRatio, and whose inner junction caps are no lower than the
    // span's speed (plan_feeds' comment).
    struct Span {
        std::size_t first = 0, last = 0;  // segments [first, last)
        double length = 0, vmax = kInf, a = kInf, j = kInf;
        char joined = 0;  // continues the span before it smoothly (a group may cover both)
    };

    const Machine& m;
    std::string file;
    FeedOptions options;
    FeedStats stats;
    std::vector<Diagnostic> warnings, errors;
    double a_normal = kInf, j_normal = kInf;

    Window<Seg> segs;
    std::size_t n = 0;                // segments pushed
    bool finished = false;
    std::size_t warned_feed = kNoBlock, warned_card = kNoBlock;  // the last block warned (a block's segments are consecutive)
    static constexpr std::size_t kNoBlock = static_cast<std::size_t>(-1);

    // Junctions: junction[i] is final for i < jdone (curvature steps and
    // reversals need the segment after i).
    std::size_t jdone = 0;
    PerAxis<int> last_sign{};  // sign of each axis's last motion (reversals)

    // Spans: made greedily; the one being made is kept open across pushes.
    Window<Span> spans;
    Window<double> entry;  // entry[k]: the backward pass's speed at span k's start (one past the last span too)
    std::size_t span_next = 0;  // the segment the next span starts at
    bool span_open = false;
    Span open;
    double open_lo = 0, open_hi = 0, open_sum_l = 0, open_sum_t = 0;
    std::size_t open_k = 0;

    // Backward pass: entry[0..final_upto] are final; the window ends at `horizon`.
    std::size_t final_upto = 0, horizon = 0;
    // A window being grown across pushes.
    bool window_started = false;
    std::size_t window_h = 0;
    double window_dist = 0, window_vhi = 0, window_amin = kInf, window_jmin = kInf, window_reach_s = 0;

    // Forward pass.
    std::size_t k_fwd = 0;          // the next span to plan
    std::size_t ready = 0;          // segments [0, ready) are planned
    std::size_t handed = 0;         // segments handed out by next()
    std::deque<PlannedSegment> planned;  // [handed, ready): planned, not yet handed out
    double v_in = 0, t = 0;
    std::vector<double> t_ends, best_t_ends;
    std::size_t max_held = 0;

    Impl(const Machine& machine, std::string job_file, const FeedOptions& o)
        : m(machine), file(std::move(job_file)), options(o) {
        // The smallest acceleration and jerk of any present axis: the centripetal
        // terms point across the path, along any axis.
        for (const auto& ax : m.axes) {
            if (!ax.present) continue;
            a_normal = std::min(a_normal, ax.max_accel);
            j_normal = std::min(j_normal, ax.max_jerk);
        }
        entry.push_back(0);
    }

    [[nodiscard]] bool spans_complete() const { return finished && span_next >= n && !span_open; }

    // The segment's own limits: feed, projected axis limits, the card's step
    // rate, the curvature budget.
    void limit(Seg& g, const StepSegment& s) {
        g.kind = s.kind;
        g.spindle_on = s.spindle_on;
        g.loc = s.loc;
        g.dwell_s = s.dwell_s;
        g.delta = s.delta();
        g.radius_start = s.radius_start_mm;
        Seg& p = g;
        if (s.kind == MotionKind::dwell) return;
        p.length = s.planned_length_mm(m);
        const SegmentLimits proj = project_limits(s.delta(), p.length, m);
        double v = proj.v;
        if (s.kind != MotionKind::rapid) {
            if (s.feed > v * (1 + 1e-9) && warned_feed != s.block) {
                warned_feed = s.block;
                warnings.push_back({file, s.loc,
                                    fmt::format("feed {:.4g} mm/s lowered to the axes' limit {:.4g} mm/s", s.feed, v)});
            }
            v = std::min(v, s.feed);
        }
        const double card = card_speed_limit(s.delta(), p.length, m);
        if (v > card) {
            if (warned_card != s.block) {
                warned_card = s.block;
                if (m.planner.on_limit == OnLimit::refuse) {
                    errors.push_back({file, s.loc,
                                      fmt::format("needs {:.4g} mm/s but the card's step timing allows "
                                                  "{:.4g} mm/s here (planner.on_limit = \"refuse\")",
                                                  v, card)});
                } else {
                    warnings.push_back({file, s.loc,
                                        fmt::format("planned at {:.4g} mm/s instead of {:.4g} mm/s: the card's "
                                                    "step timing allows no more",
                                                    card, v)});
                }
            }
            v = std::min(v, card);
        }
        // Curvature from the true geometry: speed cap and what is left for the
        // tangential acceleration and jerk.
        const CurvatureBudget b = curvature_budget(s.radius_mm, v, proj, a_normal, j_normal);
        p.radius = s.radius_mm;
        p.cruise = b.v;
        p.limits = {proj.v, b.a, b.j};
        // The unrounded direction (steps would make a one-step segment point along an axis).
        g.dir = path_direction(s, m);
    }

    // Junction i's cap from its two segments: whether the path goes on smoothly
    // there (acceleration carried) or turns a corner / stops (acceleration zero).
    // Zero at the ends, around dwells and where the spindle switches (the pierce
    // must start at rest).
    void join(std::size_t i) {
        const Seg& pa = segs[i - 1];
        Seg& pb = segs[i];
        const Seg& a = pa;
        const Seg& b = pb;
        if (a.kind == MotionKind::dwell || b.kind == MotionKind::dwell || a.spindle_on != b.spindle_on) return;
        double c = 0;
        for (std::size_t k = 0; k < kAxes; ++k) c += pa.dir[k] * pb.dir[k];
        pb.smooth = std::acos(std::clamp(c, -1.0, 1.0)) <= kSmoothTurnRad;
        const double jv = junction_speed(pa.dir, pb.dir, std::min(pa.limits.a, pb.limits.a),
                                         m.planner.junction_deviation_mm);
        // The path's own bend at the junction point (a line running into an arc).
        const double bend = curvature_speed(b.radius_start, kCurvatureShare * a_normal, kCurvatureShare * j_normal);
        pb.junction = std::min({jv, bend, pa.cruise, pb.cruise});
    }

    // Junction i made final: curvature steps and reversals (needs segment i + 1
    // when there is one).
    void settle(std::size_t i) {
        Seg& g = segs[i];
        if (i >= 1 && g.junction > 0) curvature_step(i);
        // Axes that reverse where the path goes on (a zigzag's corners, or an axis
        // that last moved some segments back): DIR hold and setup at that speed.
        if (g.kind != MotionKind::dwell) {
            const auto& d = g.delta;
            for (std::size_t a = 0; a < kAxes; ++a) {
                if (d[a] == 0) continue;
                const int sign = d[a] > 0 ? 1 : -1;
                if (last_sign[a] != 0 && sign != last_sign[a] && g.junction > 0)
                    g.junction = std::min(g.junction, reversal_speed(g.dir[a], m.axes[a], g.limits.a, m));
                last_sign[a] = sign;
            }
        }
    }

    // Curvature steps: where the path's curvature jumps at a junction (a line
    // running into an arc tangentially, two arcs of different radii or turning
    // opposite ways) the centripetal acceleration steps by v^2 |k_b - k_a|. No
    // speed but zero makes that step a ramp; as a CNC's transition jerk limit
    // does, it is counted as a ramp over planner.curvature_step_s, and each axis's
    // share of it kept within that axis's jerk times that time (docs/PLANNING.md,
    // "Curvature steps").
    void curvature_step(std::size_t i) {
        // The inside of a turn: the polyline's turn from `from` to `to`, square to `along`.
        auto inward = [&](std::size_t from, std::size_t to, const PerAxis<double>& along) {
            PerAxis<double> tv{};
            double tt = 0, ta = 0;
            const PerAxis<double>& df = segs[from].dir;
            const PerAxis<double>& dt = segs[to].dir;
            for (std::size_t k = 0; k < kAxes; ++k) ta += (dt[k] - df[k]) * along[k];
            for (std::size_t k = 0; k < kAxes; ++k) {
                tv[k] = dt[k] - df[k] - ta * along[k];
                tt += tv[k] * tv[k];
            }
            if (!(tt > 1e-24)) return std::optional<PerAxis<double>>{};
            for (double& x : tv) x /= std::sqrt(tt);
            return std::optional<PerAxis<double>>{tv};
        };
        // Junction j joins two moves smoothly (smooth is never set next to a dwell).
        auto usable = [&](std::size_t j) { return j >= 1 && j < n && segs[j].smooth; };
        const double ka = 1 / segs[i - 1].radius, kb = 1 / segs[i].radius;  // 0 when straight
        if (ka == 0 && kb == 0) return;
        // Each side's inward normal: from the polyline's turn inside that side's
        // curve when there is one (the next smooth junction), else this junction's.
        std::optional<PerAxis<double>> na, nb;
        if (ka > 0)
            na = usable(i - 1) && 1 / segs[i - 2].radius > 0 ? inward(i - 2, i - 1, segs[i - 1].dir)
                                                                 : inward(i - 1, i, segs[i - 1].dir);
        if (kb > 0)
            nb = usable(i + 1) && 1 / segs[i + 1].radius > 0 ? inward(i, i + 1, segs[i].dir)
                                                                 : inward(i - 1, i, segs[i].dir);
        // The step's size: |k_b - k_a| turning the same way, k_a + k_b opposite
        // ways (an unknown side counted as opposite); its direction the inward
        // normal of the sharper side (either, per axis, when a side is unknown).
        double side = 1;
        if (ka > 0 && kb > 0) {
            side = -1;
            if (na && nb) {
                double c = 0;
                for (std::size_t k = 0; k < kAxes; ++k) c += (*na)[k] * (*nb)[k];
                side = c >= 0 ? 1 : -1;
            }
        }
        const double dk = side > 0 ? std::abs(kb - ka) : ka + kb;
        if (!(dk > 0)) return;
        PerAxis<double> share;  // of the step, per axis
        share.fill(1);
        if (const auto& sharp = kb >= ka ? nb : na; side > 0 && sharp) {
            for (std::size_t k = 0; k < kAxes; ++k) share[k] = std::abs((*sharp)[k]);
        } else if (side < 0 && na && nb) {
            for (std::size_t k = 0; k < kAxes; ++k) share[k] = std::max(std::abs((*na)[k]), std::abs((*nb)[k]));
        }
        double cap = kInf;
        for (std::size_t k = 0; k < kAxes; ++k) {
            if (m.axes[k].present && share[k] * dk > 0)
                cap = std::min(cap, std::sqrt(m.axes[k].max_jerk * m.planner.curvature_step_s / (share[k] * dk)));
        }
        segs[i].junction = std::min(segs[i].junction, cap);
    }

    // Spans, as far as the junctions allow. One 7-phase profile covers a span,
    // so speed and acceleration carry across the junctions inside it. A
    // junction's cap limits the speed at that point only: it lowers the span's
    // speed when the segment joins, but is not the cap of the segment after it
    // (a line leaving an arc keeps its own cruise).
    void make_spans() {
        for (;;) {
            if (!span_open) {
                const std::size_t i = span_next;
                if (i >= n) return;
                if (segs[i].kind == MotionKind::dwell) {
                    add_span({i, i + 1, 0, 0, 0, 0, 0});
                    span_next = i + 1;
                    continue;
                }
                open = Span{i, i, 0, kInf, kInf, kInf, 0};
                open_lo = kInf;
                open_hi = 0;
                open_sum_l = 0;
                open_sum_t = 0;
                open_k = i;
                span_open = true;
            }
            const std::size_t i = open.first;
            for (;;) {
                std::size_t& k = open_k;
                if (k >= n) {
                    if (!finished) return;
                    break;
                }
                const Seg& g = segs[k];
                if (!(g.kind != MotionKind::dwell && (k == i || g.smooth))) break;
                if (k > i && k >= jdone) return;  // its junction is not final yet
                const double cap = g.cruise;
                double nlo = std::min(open_lo, cap);
                if (k > i) nlo = std::min(nlo, g.junction);
                const double nhi = std::max(open_hi, cap);
                // The time the span loses by running at its lowest cap, against each cap.
                const double loss = (open_sum_l + g.length) / nlo - (open_sum_t + g.length / cap);
                if (k > i && (nhi > nlo * (1 + kSpanRatio) || loss > kSpanLossS ||
                              open_sum_t + g.length / cap > kSpanMaxS))
                    break;
                open_lo = nlo;
                open_hi = nhi;
                open_sum_l += g.length;
                open_sum_t += g.length / cap;
                open.length += g.length;
                open.a = std::min(open.a, g.limits.a);
                open.j = std::min(open.j, g.limits.j);
                ++k;
            }
            open.last = open_k;
            open.vmax = open_lo;
            span_open = false;
            span_next = open.last;
            add_span(open);
        }
    }

    void add_span(Span sp) {
        const std::size_t k = spans.end();
        sp.joined = k > 0 && sp.length > 0 && spans[k - 1].length > 0 && segs[sp.first].smooth;
        spans.push_back(sp);
        entry.push_back(0);
    }

    double cap_at(std::size_t si) const {  // speed cap where span si starts
        const Span& sp = spans[si];
        if (sp.length == 0) return 0.0;
        double c = std::min(segs[sp.first].junction, sp.vmax);
        if (si > 0) c = std::min(c, spans[si - 1].vmax);
        return c;
    }

    // Backward pass over spans, streaming: entry[k] is the fastest speed at the
    // start of span k from which every later span can still be planned. It is
    // computed over a lookahead window that ends at rest; an entry that equals
    // its own cap (cap_at) does not depend on anything after it, so it and every
    // entry before it are final. The window grows by at least the stopping
    // distance from its highest speed at a time until such a final entry lies
    // beyond what the forward pass needs (docs/PLANNING.md, "Lookahead").
    // False while it waits for spans not yet made.
    bool make_final(std::size_t need) {
        const bool complete = spans_complete();
        const std::size_t ns = spans.end();
        if (complete) need = std::min(need, ns);
        while (final_upto < need) {
            // Grow the window by the stopping distance from its highest cap.
            if (!window_started) {
                window_h = std::max(horizon, final_upto);
                window_dist = 0;
                window_vhi = 0;
                window_amin = kInf;
                window_jmin = kInf;
                // Its reach past the span being planned, in time at the caps.
                window_reach_s = 0;
                for (std::size_t q = std::min(k_fwd, window_h); q < window_h; ++q)
                    if (spans[q].length > 0) window_reach_s += spans[q].length / spans[q].vmax;
            }
            for (;;) {
                if (window_started) {
                    const bool more =
                        (window_h < need + 1 ||
                         !(window_dist >= options.window_stop_factor * stop_distance(window_vhi, window_amin, window_jmin))) &&
                        !(window_h >= need + 1 && window_reach_s >= options.max_lookahead_s);
                    // Whether a window that reaches the last span made ends at
                    // the job's end is known only when the next span is made.
                    if (window_h >= ns && !complete) return false;
                    if (!more || window_h >= ns) break;
                } else if (window_h >= ns) {
                    return false;  // no span to start it with yet
                }
                const Span& sp = spans[window_h];
                window_dist += sp.length;
                if (sp.length > 0) {
                    if (window_h >= k_fwd) window_reach_s += sp.length / sp.vmax;
                    window_vhi = std::max(window_vhi, sp.vmax);
                    window_amin = std::min(window_amin, sp.a);
                    window_jmin = std::min(window_jmin, sp.j);
                }
                ++window_h;
                window_started = true;
            }
            window_started = false;
            const std::size_t h = window_h;
            horizon = h;
            ++stats.windows;
            const double reach_s = window_reach_s;  // from the span being planned to h
            {
                double mm = 0;
                for (std::size_t q = std::min(k_fwd, h); q < h; ++q) mm += spans[q].length;
                const std::size_t from = std::min(k_fwd, h);
                stats.max_lookahead_spans = std::max(stats.max_lookahead_spans, h - from);
                stats.max_lookahead_mm = std::max(stats.max_lookahead_mm, mm);
                stats.max_lookahead_s = std::max(stats.max_lookahead_s, reach_s);
            }
            entry[horizon] = 0;  // at rest at the window's end (the job's end when horizon = ns)
            std::size_t q = final_upto;
            for (std::size_t k = horizon; k-- > final_upto;) {
                const Span& sp = spans[k];
                ++stats.backward_steps;
                if (sp.length == 0) {
                    entry[k] = 0;
                } else {
                    const double c = cap_at(k);
                    entry[k] = reachable_speed(entry[k + 1], sp.length, sp.a, sp.j, c);
                    if (entry[k] < c) continue;
                }
                q = std::max(q, k);  // bound by its own cap: final
            }
            final_upto = horizon == ns && complete ? ns : q;
            // Looked as far as it may: the entries the forward pass needs stand as
            // they are (each no faster than its whole-job entry; later windows,
            // reaching farther, give the entries after them no slower, so every
            // span can still be planned).
            if (final_upto < need && reach_s >= options.max_lookahead_s) {
                final_upto = need;
                ++stats.cut_windows;
            }
        }
        return true;
    }

    // Where spans k..me-1 join smoothly, one profile may cover them all (a
    // group): from the entry speed to entry[me] with the smallest acceleration
    // that fills the group, so that the speed follows a rising or falling cap
    // with its acceleration carried across the span boundaries.
    bool try_group(std::size_t k, std::size_t me, double v0, Profile& prof, std::vector<double>& ends) {
        double L = 0, A = kInf, J = kInf;
        for (std::size_t q = k; q < me; ++q) {
            L += spans[q].length;
            A = std::min(A, spans[q].a);
            J = std::min(J, spans[q].j);
        }
        const double v1 = reachable_speed(v0, L, A, J, entry[me]);
        const double dv = std::abs(v1 - v0);
        double Ap = A;
        if (dv > 0) {
            // The ramp v0 -> v1 lasting the whole group: dv/A' + A'/J = T with
            // T = 2 L / (v0 + v1); the smaller root (longest constant phase).
            const double T = 2 * L / (v0 + v1);
            const double disc = J * J * T * T - 4 * J * dv;
            if (disc > 0) Ap = std::min(A, 2 * J * dv / (J * T + std::sqrt(disc)) * (1 + 1e-9));
        }
        auto p = make_profile(L, v0, v1, std::max(v0, v1), Ap, J);
        if (!p) return false;
        // Under every cap: the profile is monotone, so a segment's highest speed is at an end.
        ends.clear();
        double s_at = 0, v_at = v0;
        for (std::size_t q = k; q < me; ++q) {
            for (std::size_t i = spans[q].first; i < spans[q].last; ++i) {
                const Seg& g = segs[i];
                const double c = g.cruise * (1 + 1e-9);
                if (v_at > c || (i > spans[k].first && v_at > g.junction * (1 + 1e-9))) return false;
                const bool last = q + 1 == me && i + 1 == spans[q].last;
                s_at = last ? L : s_at + g.length;
                const double te = last ? p->duration : p->time_at(s_at);
                v_at = last ? p->v_exit : p->at(te).v;
                if (v_at > c) return false;
                ends.push_back(te);
            }
        }
        prof = *p;
        return true;
    }

    double span_time(std::size_t k, double v0, double& v1) {
        const Span& sp = spans[k];
        v1 = reachable_speed(v0, sp.length, sp.a, sp.j, entry[k + 1]);
        auto p = make_profile(sp.length, v0, v1, sp.vmax, sp.a, sp.j);
        return p ? p->duration : kInf;
    }

    // How far a group from span k may reach: at most kMaxGroupSpans spans, and
    // the spans after k at most kGroupMaxS at their caps. Null while the spans
    // that decide it are not made yet.
    std::optional<std::size_t> group_limit(std::size_t k) {
        const std::size_t cap = k + kMaxGroupSpans;
        double sec = 0;
        for (std::size_t q = k + 1; q <= cap; ++q) {
            if (q >= spans.end()) {
                if (!spans_complete()) return std::nullopt;
                return spans.end();
            }
            if (spans[q].length > 0) sec += spans[q].length / spans[q].vmax;
            if (sec > kGroupMaxS) return q;
        }
        return cap;
    }

    // Forward pass. Where spans join smoothly a group may cover them (try_group);
    // it is taken when it stays under every segment's cap and junction cap and
    // beats the spans one by one. Otherwise each span gets its own profile (zero
    // acceleration at its ends).
    void forward() {
        while (errors.empty()) {
            if (k_fwd >= spans.end()) return;
            const std::optional<std::size_t> limit = group_limit(k_fwd);
            if (!limit || !make_final(*limit + 1)) return;
            const std::size_t k = k_fwd;
            const Span& sp = spans[k];
            if (sp.length == 0) {
                PlannedSegment p;
                p.t_start = t;
                p.duration = segs[sp.first].dwell_s;
                t += p.duration;
                planned.push_back(p);
                v_in = 0;
                ready = sp.last;
                ++k_fwd;
                continue;
            }
            const double v0 = std::min(v_in, entry[k]);
            // The longest group (2, 4, 8, ... spans) that stays under the caps.
            std::size_t m_best = k + 1;
            Profile prof;
            Profile cand;
            for (std::size_t g = 2; g <= kMaxGroupSpans; g *= 2) {
                const std::size_t mg = k + g;
                if (mg > *limit) break;
                bool ok = true;
                for (std::size_t q = k + 1; q < mg && ok; ++q) ok = spans[q].joined;
                if (!ok || !try_group(k, mg, v0, cand, t_ends)) break;
                // Taken only when faster than the spans one by one.
                double tt = 0, vv = v0;
                for (std::size_t q = k; q < mg; ++q) {
                    double v1;
                    tt += span_time(q, vv, v1);
                    vv = v1;
                }
                if (cand.duration > tt * (1 + 1e-12)) break;
                m_best = mg;
                prof = cand;
                best_t_ends.swap(t_ends);
            }
            if (m_best == k + 1) {
                const double v1 = reachable_speed(v0, sp.length, sp.a, sp.j, entry[k + 1]);
                auto p = make_profile(sp.length, v0, v1, sp.vmax, sp.a, sp.j);
                if (!p) {  // cannot happen after both passes; kept as a guard
                    errors.push_back({file, segs[sp.first].loc, "internal: no feasible profile"});
                    return;
                }
                prof = *p;
                best_t_ends.clear();
                double s_at = 0;
                for (std::size_t i = sp.first; i < sp.last; ++i) {
                    s_at += segs[i].length;
                    best_t_ends.push_back(i + 1 == sp.last ? prof.duration : prof.time_at(s_at));
                }
            } else {
                ++stats.groups;
            }
            // Cut the profile at its segments' ends.
            double s_at = 0, t_at = 0;
            std::size_t e = 0;
            const std::size_t end = spans[m_best - 1].last;
            for (std::size_t i = spans[k].first; i < end; ++i, ++e) {
                const Seg& g = segs[i];
                PlannedSegment p;
                p.length = g.length;
                p.radius = g.radius;
                p.cruise = g.cruise;
                p.limits = g.limits;
                const double t_end = best_t_ends[e];
                p.profile = prof.slice(t_at, t_end, s_at, p.length);
                p.duration = p.profile.duration;
                if (!(p.duration > 0) && p.length > 0) {  // a path that moves takes time; kept as a guard
                    errors.push_back({file, segs[i].loc, "internal: a segment planned with no duration"});
                    return;
                }
                p.t_start = t;
                t += p.duration;
                s_at += p.length;
                t_at = t_end;
                planned.push_back(p);
            }
            v_in = prof.v_exit;
            ready = end;
            k_fwd = m_best;
        }
    }

    void advance() {
        make_spans();
        forward();
        // What is no longer needed: segments planned (but the three newest,
        // for the junctions), spans before the one planned next (and the one
        // before it, for its cap).
        segs.drop_before(std::min(ready, n >= 3 ? n - 3 : 0));
        if (k_fwd >= 1) {
            spans.drop_before(k_fwd - 1);
            entry.drop_before(k_fwd - 1);
        }
        max_held = std::max(max_held, segs.held() + planned.size());
    }
};

FeedPlanner::FeedPlanner(const Machine& m, std::string job_file, const FeedOptions& options)
    : impl_(std::make_unique<Impl>(m, std::move(job_file), options)) {}
FeedPlanner::~FeedPlanner() = default;
FeedPlanner::FeedPlanner(FeedPlanner&&) noexcept = default;
FeedPlanner& FeedPlanner::operator=(FeedPlanner&&) noexcept = default;

void FeedPlanner::push(const StepSegment& s) {
    Impl& p = *impl_;
    if (p.finished) throw std::logic_error("FeedPlanner::push after finish");
    const std::size_t i = p.n;
    p.segs.push_back(Impl::Seg{});
    ++p.n;
    p.limit(p.segs[i], s);
    if (i >= 1) {
        p.join(i);
        p.settle(i - 1);  // needs segment i
        p.jdone = i;
    }
    if (p.errors.empty()) p.advance();
}

void FeedPlanner::finish() {
    Impl& p = *impl_;
    if (p.finished) return;
    p.finished = true;
    if (p.n >= 1) p.settle(p.n - 1);
    p.jdone = p.n;
    if (p.errors.empty()) p.advance();
    p.stats.spans = p.spans.end();
}

std::optional<PlannedSegment> FeedPlanner::next() {
    Impl& p = *impl_;
    if (!p.errors.empty() || p.planned.empty()) return std::nullopt;
    std::optional<PlannedSegment> out = std::move(p.planned.front());
    p.planned.pop_front();
    ++p.handed;
    return out;
}

std::size_t FeedPlanner::pushed() const { return impl_->n; }
std::size_t FeedPlanner::handed_out() const { return impl_->handed; }
bool FeedPlanner::done() const { return impl_->finished && impl_->handed == impl_->n && impl_->errors.empty(); }
const std::vector<Diagnostic>& FeedPlanner::warnings() const { return impl_->warnings; }
const std::vector<Diagnostic>& FeedPlanner::errors() const { return impl_->errors; }
const FeedStats& FeedPlanner::stats() const { return impl_->stats; }
std::size_t FeedPlanner::held() const { return impl_->segs.held() + impl_->planned.size(); }
std::size_t FeedPlanner::max_held() const { return impl_->max_held; }

Result<std::vector<PlannedSegment>> plan_feeds(const std::vector<StepSegment>& segs, const Machine& m,
                                               const std::string& job_file, const FeedOptions& options,
                                               FeedStats* stats) {
    Result<std::vector<PlannedSegment>> result;
    FeedPlanner planner(m, job_file, options);
    std::vector<PlannedSegment> out;
    out.reserve(segs.size());
    for (const StepSegment& s : segs) {
        planner.push(s);
        while (auto p = planner.next()) out.push_back(std::move(*p));
    }
    planner.finish();
    while (auto p = planner.next()) out.push_back(std::move(*p));
    result.warnings = planner.warnings();
    if (!planner.errors().empty()) {
        result.errors = planner.errors();
        return result;
    }
    if (out.size() != segs.size()) throw std::logic_error("plan_feeds: a segment was not planned");
    if (stats) *stats = planner.stats();
    result.value = std::move(out);
    return result;
}

}  // namespace cpstep::plan

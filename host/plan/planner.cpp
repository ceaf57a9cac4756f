// SPDX-License-Identifier: MIT
#include "plan/planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>

#include <fmt/format.h>

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

Result<std::vector<PlannedSegment>> plan_feeds(const std::vector<StepSegment>& segs,
                                               const Machine& m, const std::string& job_file,
                                               const FeedOptions& options, FeedStats* stats) {
    FeedStats stats_;
    Result<std::vector<PlannedSegment>> result;
    const std::size_t n = segs.size();
    std::vector<PlannedSegment> out(n);
    std::set<std::size_t> warned_feed, warned_card;
    // The smallest acceleration and jerk of any present axis: the centripetal
    // terms point across the path, along any axis.
    double a_normal = kInf, j_normal = kInf;
    for (const auto& ax : m.axes) {
        if (!ax.present) continue;
        a_normal = std::min(a_normal, ax.max_accel);
        j_normal = std::min(j_normal, ax.max_jerk);
    }

    std::vector<PerAxis<double>> dir(n);  // unrounded direction, mm
    for (std::size_t i = 0; i < n; ++i) {
        const StepSegment& s = segs[i];
        PlannedSegment& p = out[i];
        if (s.kind == MotionKind::dwell) continue;
        p.length = s.planned_length_mm(m);
        const SegmentLimits proj = project_limits(s.delta(), p.length, m);
        double v = proj.v;
        if (s.kind != MotionKind::rapid) {
            if (s.feed > v * (1 + 1e-9) && warned_feed.insert(s.block).second) {
                result.warnings.push_back(
                    {job_file, s.loc,
                     fmt::format("feed {:.4g} mm/s lowered to the axes' limit {:.4g} mm/s",
                                 s.feed, v)});
            }
            v = std::min(v, s.feed);
        }
        const double card = card_speed_limit(s.delta(), p.length, m);
        if (v > card) {
            if (m.planner.on_limit == OnLimit::refuse) {
                if (warned_card.insert(s.block).second) {
                    result.errors.push_back(
                        {job_file, s.loc,
                         fmt::format("needs {:.4g} mm/s but the card's step timing allows "
                                     "{:.4g} mm/s here (planner.on_limit = \"refuse\")",
                                     v, card)});
                }
            } else if (warned_card.insert(s.block).second) {
                result.warnings.push_back(
                    {job_file, s.loc,
                     fmt::format("planned at {:.4g} mm/s instead of {:.4g} mm/s: the card's "
                                 "step timing allows no more",
                                 card, v)});
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
        dir[i] = path_direction(s, m);
    }
    if (!result.errors.empty()) return result;

    // Junctions: the speed cap at the start of segment i, and whether the path
    // goes on smoothly there (acceleration carried) or turns a corner / stops
    // (acceleration zero). Zero at the ends, around dwells and where the spindle
    // switches (the pierce must start at rest).
    std::vector<double> junction(n + 1, 0.0);
    std::vector<char> smooth(n + 1, 0);
    for (std::size_t i = 1; i < n; ++i) {
        const StepSegment& a = segs[i - 1];
        const StepSegment& b = segs[i];
        if (a.kind == MotionKind::dwell || b.kind == MotionKind::dwell ||
            a.spindle_on != b.spindle_on) {
            continue;
        }
        double c = 0;
        for (std::size_t k = 0; k < kAxes; ++k) c += dir[i - 1][k] * dir[i][k];
        smooth[i] = std::acos(std::clamp(c, -1.0, 1.0)) <= kSmoothTurnRad;
        const double jv = junction_speed(dir[i - 1], dir[i],
                                         std::min(out[i - 1].limits.a, out[i].limits.a),
                                         m.planner.junction_deviation_mm);
        // The path's own bend at the junction point (a line running into an arc).
        const double bend = curvature_speed(b.radius_start_mm, kCurvatureShare * a_normal,
                                            kCurvatureShare * j_normal);
        junction[i] = std::min({jv, bend, out[i - 1].cruise, out[i].cruise});
    }
    // Curvature steps: where the path's curvature jumps at a junction (a line
    // running into an arc tangentially, two arcs of different radii or turning
    // opposite ways) the centripetal acceleration steps by v^2 |k_b - k_a|. No
    // speed but zero makes that step a ramp; as a CNC's transition jerk limit
    // does, it is counted as a ramp over planner.curvature_step_s, and each axis's
    // share of it kept within that axis's jerk times that time (docs/PLANNING.md,
    // "Curvature steps").
    // The inside of a turn: the polyline's turn from `from` to `to`, square to `along`.
    auto inward = [&](std::size_t from, std::size_t to, const PerAxis<double>& along) {
        PerAxis<double> t{};
        double tt = 0, ta = 0;
        for (std::size_t k = 0; k < kAxes; ++k) ta += (dir[to][k] - dir[from][k]) * along[k];
        for (std::size_t k = 0; k < kAxes; ++k) {
            t[k] = dir[to][k] - dir[from][k] - ta * along[k];
            tt += t[k] * t[k];
        }
        if (!(tt > 1e-24)) return std::optional<PerAxis<double>>{};
        for (double& x : t) x /= std::sqrt(tt);
        return std::optional<PerAxis<double>>{t};
    };
    // Junction j joins two moves smoothly (smooth[] is never set next to a dwell).
    auto usable = [&](std::size_t j) { return j >= 1 && j < n && smooth[j]; };
    for (std::size_t i = 1; i < n; ++i) {
        if (!(junction[i] > 0)) continue;
        const double ka = 1 / out[i - 1].radius, kb = 1 / out[i].radius;  // 0 when straight
        if (ka == 0 && kb == 0) continue;
        // Each side's inward normal: from the polyline's turn inside that side's
        // curve when there is one (the next smooth junction), else this junction's.
        std::optional<PerAxis<double>> na, nb;
        if (ka > 0) na = usable(i - 1) && 1 / out[i - 2].radius > 0 ? inward(i - 2, i - 1, dir[i - 1])
                                                                    : inward(i - 1, i, dir[i - 1]);
        if (kb > 0) nb = usable(i + 1) && 1 / out[i + 1].radius > 0 ? inward(i, i + 1, dir[i])
                                                                    : inward(i - 1, i, dir[i]);
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
        if (!(dk > 0)) continue;
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
        junction[i] = std::min(junction[i], cap);
    }
    // Axes that reverse where the path goes on (a zigzag's corners, or an axis
    // that last moved some segments back): DIR hold and setup at that speed.
    {
        PerAxis<int> last{};  // sign of each axis's last motion
        for (std::size_t i = 0; i < n; ++i) {
            const StepSegment& s = segs[i];
            if (s.kind == MotionKind::dwell) continue;
            const auto d = s.delta();
            for (std::size_t a = 0; a < kAxes; ++a) {
                if (d[a] == 0) continue;
                const int sign = d[a] > 0 ? 1 : -1;
                if (last[a] != 0 && sign != last[a] && junction[i] > 0) {
                    junction[i] = std::min(
                        junction[i], reversal_speed(dir[i][a], m.axes[a], out[i].limits.a, m));
                }
                last[a] = sign;
            }
        }
    }

    // Spans: runs of segments joined smoothly whose cruise caps lie within a
    // ratio 1 + kSpanRatio, and whose inner junction caps are no lower than the
    // span's speed. One 7-phase profile covers a span, so speed and
    // acceleration carry across the junctions inside it. A junction's cap
    // limits the speed at that point only: it lowers the span's speed when the
    // segment joins, but is not the cap of the segment after it (a line leaving
    // an arc keeps its own cruise).
    struct Span {
        std::size_t first = 0, last = 0;  // segments [first, last)
        double length = 0, vmax = kInf, a = kInf, j = kInf;
    };
    std::vector<Span> spans;
    for (std::size_t i = 0; i < n;) {
        if (segs[i].kind == MotionKind::dwell) {
            spans.push_back({i, i + 1, 0, 0, 0, 0});
            ++i;
            continue;
        }
        Span sp{i, i, 0, kInf, kInf, kInf};
        double lo = kInf, hi = 0, sum_l = 0, sum_t = 0;
        std::size_t k = i;
        while (k < n && segs[k].kind != MotionKind::dwell && (k == i || smooth[k])) {
            const double cap = out[k].cruise;
            double nlo = std::min(lo, cap);
            if (k > i) nlo = std::min(nlo, junction[k]);
            const double nhi = std::max(hi, cap);
            // The time the span loses by running at its lowest cap, against each cap.
            const double loss = (sum_l + out[k].length) / nlo - (sum_t + out[k].length / cap);
            if (k > i && (nhi > nlo * (1 + kSpanRatio) || loss > kSpanLossS)) break;
            lo = nlo;
            hi = nhi;
            sum_l += out[k].length;
            sum_t += out[k].length / cap;
            sp.length += out[k].length;
            sp.a = std::min(sp.a, out[k].limits.a);
            sp.j = std::min(sp.j, out[k].limits.j);
            ++k;
        }
        sp.last = k;
        sp.vmax = lo;
        spans.push_back(sp);
        i = k;
    }
    const std::size_t ns = spans.size();
    // joined[k]: span k continues span k - 1 smoothly (a group may cover both).
    std::vector<char> joined(ns, 0);
    for (std::size_t k = 1; k < ns; ++k) {
        joined[k] = spans[k].length > 0 && spans[k - 1].length > 0 && smooth[spans[k].first];
    }

    // Backward pass over spans, streaming: entry[k] is the fastest speed at the
    // start of span k from which every later span can still be planned. It is
    // computed over a lookahead window that ends at rest; an entry that equals
    // its own cap (cap_at) does not depend on anything after it, so it and every
    // entry before it are final. The window grows by at least the stopping
    // distance from its highest speed at a time until such a final entry lies
    // beyond what the forward pass needs (docs/PLANNING.md, "Lookahead").
    std::vector<double> entry(ns + 1, 0.0);
    auto cap_at = [&](std::size_t si) {  // speed cap where span si starts
        const Span& sp = spans[si];
        if (sp.length == 0) return 0.0;
        double c = std::min(junction[sp.first], sp.vmax);
        if (si > 0) c = std::min(c, spans[si - 1].vmax);
        return c;
    };
    std::size_t final_upto = 0;  // entry[0..final_upto] are final
    std::size_t horizon = 0;     // the window ends at the start of span `horizon`
    const double window_stop = options.window_stop_factor;
    auto make_final = [&](std::size_t need) {
        need = std::min(need, ns);
        while (final_upto < need) {
            // Grow the window by the stopping distance from its highest cap.
            std::size_t h = std::max(horizon, final_upto);
            double dist = 0, vhi = 0, amin = kInf, jmin = kInf;
            do {
                const Span& sp = spans[h];
                dist += sp.length;
                if (sp.length > 0) {
                    vhi = std::max(vhi, sp.vmax);
                    amin = std::min(amin, sp.a);
                    jmin = std::min(jmin, sp.j);
                }
                ++h;
            } while (h < ns && (h < need + 1 || !(dist >= window_stop * stop_distance(vhi, amin, jmin))));
            horizon = h;
            ++stats_.windows;
            {
                double mm = 0, sec = 0;
                for (std::size_t q = need - 1 < h ? need - 1 : h; q < h; ++q) {
                    mm += spans[q].length;
                    if (spans[q].length > 0) sec += spans[q].length / spans[q].vmax;
                }
                const std::size_t from = std::min(need - 1, h);
                stats_.max_lookahead_spans = std::max(stats_.max_lookahead_spans, h - from);
                stats_.max_lookahead_mm = std::max(stats_.max_lookahead_mm, mm);
                stats_.max_lookahead_s = std::max(stats_.max_lookahead_s, sec);
            }
            entry[horizon] = 0;  // at rest at the window's end (the job's end when horizon = ns)
            std::size_t q = final_upto;
            for (std::size_t k = horizon; k-- > final_upto;) {
                const Span& sp = spans[k];
                ++stats_.backward_steps;
                if (sp.length == 0) {
                    entry[k] = 0;
                } else {
                    const double c = cap_at(k);
                    entry[k] = reachable_speed(entry[k + 1], sp.length, sp.a, sp.j, c);
                    if (entry[k] < c) continue;
                }
                q = std::max(q, k);  // bound by its own cap: final
            }
            final_upto = horizon == ns ? ns : q;
        }
    };

    // Forward pass. Where spans k..m-1 join smoothly, one profile may cover them
    // all (a group): from the entry speed to entry[m] with the smallest
    // acceleration that fills the group, so that the speed follows a rising or
    // falling cap with its acceleration carried across the span boundaries; it is
    // taken when it stays under every segment's cap and junction cap and beats
    // the spans one by one. Otherwise each span gets its own profile (zero
    // acceleration at its ends).
    std::vector<double> t_ends, best_t_ends;  // group candidate: time at each segment end
    auto try_group = [&](std::size_t k, std::size_t me, double v0, Profile& prof,
                         std::vector<double>& ends) -> bool {
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
                const double c = out[i].cruise * (1 + 1e-9);
                if (v_at > c || (i > spans[k].first && v_at > junction[i] * (1 + 1e-9))) return false;
                const bool last = q + 1 == me && i + 1 == spans[q].last;
                s_at = last ? L : s_at + out[i].length;
                const double te = last ? p->duration : p->time_at(s_at);
                v_at = last ? p->v_exit : p->at(te).v;
                if (v_at > c) return false;
                ends.push_back(te);
            }
        }
        prof = *p;
        return true;
    };
    auto span_time = [&](std::size_t k, double v0, double& v1) {
        const Span& sp = spans[k];
        v1 = reachable_speed(v0, sp.length, sp.a, sp.j, entry[k + 1]);
        auto p = make_profile(sp.length, v0, v1, sp.vmax, sp.a, sp.j);
        return p ? p->duration : kInf;
    };
    double v_in = 0, t = 0;
    for (std::size_t k = 0; k < ns;) {
        make_final(k + kMaxGroupSpans + 1);
        const Span& sp = spans[k];
        if (sp.length == 0) {
            PlannedSegment& p = out[sp.first];
            p.t_start = t;
            p.duration = segs[sp.first].dwell_s;
            t += p.duration;
            v_in = 0;
            ++k;
            continue;
        }
        const double v0 = std::min(v_in, entry[k]);
        // The longest group (2, 4, 8, ... spans) that stays under the caps.
        std::size_t m_best = k + 1;
        Profile prof;
        Profile cand;
        for (std::size_t g = 2; g <= kMaxGroupSpans; g *= 2) {
            const std::size_t mg = k + g;
            if (mg > final_upto || mg > ns) break;
            bool ok = true;
            for (std::size_t q = k + 1; q < mg && ok; ++q) ok = joined[q];
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
                result.errors.push_back({job_file, segs[sp.first].loc, "internal: no feasible profile"});
                return result;
            }
            prof = *p;
            best_t_ends.clear();
            double s_at = 0;
            for (std::size_t i = sp.first; i < sp.last; ++i) {
                s_at += out[i].length;
                best_t_ends.push_back(i + 1 == sp.last ? prof.duration : prof.time_at(s_at));
            }
        } else {
            ++stats_.groups;
        }
        // Cut the profile at its segments' ends.
        double s_at = 0, t_at = 0;
        std::size_t e = 0;
        for (std::size_t i = spans[k].first; i < spans[m_best - 1].last; ++i, ++e) {
            PlannedSegment& p = out[i];
            const double t_end = best_t_ends[e];
            p.profile = prof.slice(t_at, t_end, s_at, p.length);
            p.duration = p.profile.duration;
            if (!(p.duration > 0) && p.length > 0) {  // a path that moves takes time; kept as a guard
                result.errors.push_back({job_file, segs[i].loc, "internal: a segment planned with no duration"});
                return result;
            }
            p.t_start = t;
            t += p.duration;
            s_at += p.length;
            t_at = t_end;
        }
        v_in = prof.v_exit;
        k = m_best;
    }
    stats_.spans = ns;
    if (stats) *stats = stats_;
    result.value = std::move(out);
    return result;
}

}  // namespace cpstep::plan

#include "plan/planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
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

}  // namespace

SegmentLimits project_limits(const PerAxis<std::int64_t>& delta, const Machine& m) {
    const PerAxis<double> u = direction(delta, m);
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

double card_speed_limit(const PerAxis<std::int64_t>& delta, const Machine& m) {
    const PerAxis<double> u = direction(delta, m);
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

Result<std::vector<PlannedSegment>> plan_feeds(const std::vector<StepSegment>& segs,
                                               const Machine& m, const std::string& job_file) {
    Result<std::vector<PlannedSegment>> result;
    const std::size_t n = segs.size();
    std::vector<PlannedSegment> out(n);
    std::vector<double> junction(n + 1, 0.0);  // speed limit at the start of segment i
    std::set<std::size_t> warned_feed, warned_card;

    for (std::size_t i = 0; i < n; ++i) {
        const StepSegment& s = segs[i];
        PlannedSegment& p = out[i];
        if (s.kind == MotionKind::dwell) continue;
        p.length = s.length_mm(m);
        p.limits = project_limits(s.delta(), m);
        double v = p.limits.v;
        if (s.kind != MotionKind::rapid) {
            if (s.feed > v * (1 + 1e-9) && warned_feed.insert(s.block).second) {
                result.warnings.push_back(
                    {job_file, s.loc,
                     fmt::format("feed {:.4g} mm/s lowered to the axes' limit {:.4g} mm/s",
                                 s.feed, v)});
            }
            v = std::min(v, s.feed);
        }
        const double card = card_speed_limit(s.delta(), m);
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
        p.cruise = v;
    }
    if (!result.errors.empty()) return result;

    // Curvature: a chain of short chords (an arc) bends the path with the radius
    // its chords and turns imply; junction deviation alone would not see it.
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> bend(n + 1, inf);  // curvature speed at the start of segment i
    for (std::size_t i = 1; i < n; ++i) {
        const StepSegment& a = segs[i - 1];
        const StepSegment& b = segs[i];
        if (a.kind == MotionKind::dwell || b.kind == MotionKind::dwell) continue;
        const double r = polyline_radius(direction(a.delta(), m), direction(b.delta(), m),
                                         std::min(out[i - 1].length, out[i].length));
        bend[i] = curvature_speed(r, std::min(out[i - 1].limits.a, out[i].limits.a),
                                  std::min(out[i - 1].limits.j, out[i].limits.j));
    }
    // A segment inside a bend (both ends limited) cruises no faster than its ends.
    for (std::size_t i = 0; i < n; ++i) out[i].cruise = std::min(out[i].cruise, std::max(bend[i], bend[i + 1]));

    // Junction limits; zero at the ends, around dwells and where the spindle switches.
    for (std::size_t i = 1; i < n; ++i) {
        const StepSegment& a = segs[i - 1];
        const StepSegment& b = segs[i];
        if (a.kind == MotionKind::dwell || b.kind == MotionKind::dwell ||
            a.spindle_on != b.spindle_on) {
            continue;
        }
        const double jv = junction_speed(direction(a.delta(), m), direction(b.delta(), m),
                                         std::min(out[i - 1].limits.a, out[i].limits.a),
                                         m.planner.junction_deviation_mm);
        junction[i] = std::min({jv, bend[i], out[i - 1].cruise, out[i].cruise});
    }
    // Backward pass: each entry no faster than the segment can shed before its exit.
    std::vector<double> entry(n + 1, 0.0);
    entry[n] = 0;
    for (std::size_t k = n; k-- > 0;) {
        if (segs[k].kind == MotionKind::dwell) {
            entry[k] = 0;
            continue;
        }
        entry[k] = reachable_speed(entry[k + 1], out[k].length, out[k].limits.a, out[k].limits.j,
                                   junction[k]);
    }
    // Forward pass: each exit no faster than reachable from the entry.
    double v_in = 0;
    for (std::size_t k = 0; k < n; ++k) {
        PlannedSegment& p = out[k];
        p.t_start = k == 0 ? 0.0 : out[k - 1].t_start + out[k - 1].duration;
        if (segs[k].kind == MotionKind::dwell) {
            p.duration = segs[k].dwell_s;
            v_in = 0;
            continue;
        }
        const double v0 = std::min(v_in, entry[k]);
        const double v1 = reachable_speed(v0, p.length, p.limits.a, p.limits.j, entry[k + 1]);
        auto prof = make_profile(p.length, v0, v1, p.cruise, p.limits.a, p.limits.j);
        if (!prof) {  // cannot happen after both passes; kept as a guard
            result.errors.push_back({job_file, segs[k].loc, "internal: no feasible profile"});
            return result;
        }
        p.profile = *prof;
        p.duration = prof->duration;
        v_in = v1;
    }
    result.value = std::move(out);
    return result;
}

}  // namespace cpstep::plan

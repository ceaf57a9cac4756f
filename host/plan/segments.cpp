#include "plan/segments.h"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

namespace cpstep::plan {

PerAxis<std::int64_t> StepSegment::delta() const {
    PerAxis<std::int64_t> d{};
    for (std::size_t a = 0; a < kAxes; ++a) d[a] = end[a] - start[a];
    return d;
}

double StepSegment::length_mm(const Machine& m) const {
    double sum = 0;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (!m.axes[a].present) continue;
        const double mm = static_cast<double>(end[a] - start[a]) / m.axes[a].steps_per_mm;
        sum += mm * mm;
    }
    return std::sqrt(sum);
}

std::int64_t mm_to_steps(double mm, double steps_per_mm) {
    return static_cast<std::int64_t>(std::floor(mm * steps_per_mm + 0.5));
}

std::vector<PerAxis<double>> arc_chord_points(const MotionBlock& b, double tol) {
    const double cx = b.center_x, cy = b.center_y;
    const double r0 = std::hypot(b.start[0] - cx, b.start[1] - cy);
    const double r1 = std::hypot(b.end[0] - cx, b.end[1] - cy);
    const double a0 = std::atan2(b.start[1] - cy, b.start[0] - cx);
    const double a1 = std::atan2(b.end[1] - cy, b.end[0] - cx);
    const bool cw = b.kind == MotionKind::arc_cw;
    constexpr double two_pi = 2 * std::numbers::pi;
    double sweep = cw ? a0 - a1 : a1 - a0;
    const bool closed = std::hypot(b.end[0] - b.start[0], b.end[1] - b.start[1]) < 1e-9;
    if (closed) {
        sweep = two_pi;
    } else {
        while (sweep <= 0) sweep += two_pi;
        while (sweep > two_pi) sweep -= two_pi;
    }
    // A chord of angle theta on radius r stands off the arc by r(1 - cos(theta/2)).
    const double r = std::max(r0, r1);
    double max_angle = std::numbers::pi / 2;
    if (tol < r) max_angle = std::min(max_angle, 2 * std::acos(1 - tol / r));
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(sweep / max_angle - 1e-9)));
    std::vector<PerAxis<double>> pts;
    pts.reserve(n);
    for (std::size_t i = 1; i < n; ++i) {
        const double f = static_cast<double>(i) / static_cast<double>(n);
        const double ang = a0 + (cw ? -1 : 1) * sweep * f;
        const double rad = r0 + (r1 - r0) * f;
        PerAxis<double> p = b.start;
        p[0] = cx + rad * std::cos(ang);
        p[1] = cy + rad * std::sin(ang);
        for (std::size_t a = 2; a < kAxes; ++a) p[a] = b.start[a] + (b.end[a] - b.start[a]) * f;
        pts.push_back(p);
    }
    pts.push_back(b.end);
    return pts;
}

Result<std::vector<StepSegment>> make_step_segments(const Job& job, const Machine& m) {
    Result<std::vector<StepSegment>> result;
    std::vector<StepSegment> out;
    auto to_steps = [&](const PerAxis<double>& p) {
        PerAxis<std::int64_t> s{};
        for (std::size_t a = 0; a < kAxes; ++a) {
            if (m.axes[a].present) s[a] = mm_to_steps(p[a], m.axes[a].steps_per_mm);
        }
        return s;
    };
    // Whether p is inside the travel; reports the first offending axis once per block.
    auto check = [&](const MotionBlock& b, const PerAxis<double>& p) {
        for (std::size_t a = 0; a < kAxes; ++a) {
            const auto& ax = m.axes[a];
            const char L = static_cast<char>(std::toupper(kAxisLetters[a]));
            if (!ax.present) {
                if (std::abs(p[a]) > 1e-9) {
                    result.errors.push_back(
                        {job.file, b.loc,
                         fmt::format("axis {} is not on this machine ({})", L, m.file)});
                    return false;
                }
                continue;
            }
            const double eps = 1e-9;
            if (p[a] < ax.travel_min_mm - eps || p[a] > ax.travel_max_mm + eps) {
                result.errors.push_back(
                    {job.file, b.loc,
                     fmt::format("{} {:.3f} mm is outside the travel {:g}..{:g} mm of axis {}", L,
                                 p[a], ax.travel_min_mm, ax.travel_max_mm, kAxisLetters[a])});
                return false;
            }
        }
        return true;
    };

    PerAxis<std::int64_t> pos{};
    bool have_pos = false;
    for (std::size_t bi = 0; bi < job.blocks.size(); ++bi) {
        const MotionBlock& b = job.blocks[bi];
        if (!have_pos) {
            pos = to_steps(b.start);
            have_pos = true;
        }
        StepSegment proto;
        proto.kind = b.kind;
        proto.loc = b.loc;
        proto.block = bi;
        proto.feed = b.feed;
        proto.spindle_on = b.spindle_on;
        if (b.kind == MotionKind::dwell) {
            proto.start = proto.end = pos;
            proto.dwell_s = b.dwell_s;
            out.push_back(proto);
            continue;
        }
        std::vector<PerAxis<double>> pts;
        if (b.kind == MotionKind::arc_cw || b.kind == MotionKind::arc_ccw) {
            pts = arc_chord_points(b, m.planner.arc_tolerance_mm);
        } else {
            pts.push_back(b.end);
        }
        for (const auto& p : pts) {
            if (!check(b, p)) break;
            const auto target = to_steps(p);
            if (target == pos) continue;  // shorter than a step: merged into the next
            StepSegment s = proto;
            s.start = pos;
            s.end = target;
            bool too_long = false;
            for (std::size_t a = 0; a < kAxes; ++a) {
                if (std::llabs(target[a] - pos[a]) >= (std::int64_t{1} << 31)) too_long = true;
            }
            if (too_long) {
                result.errors.push_back({job.file, b.loc, "move of 2^31 steps or more on one axis"});
                break;
            }
            out.push_back(s);
            pos = target;
        }
    }
    if (result.errors.empty()) result.value = std::move(out);
    return result;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/segments.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "plan/nurbs.h"
#include "plan/window.h"

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

double StepSegment::planned_length_mm(const Machine& m) const {
    const double q = length_mm(m);
    double sum = 0;
    for (std::size_t a = 0; a < kAxes; ++a) {
        if (!m.axes[a].present) continue;
        const double mm = to_mm[a] - from_mm[a];
        sum += mm * mm;
    }
    const double u = std::sqrt(sum);
    return u >= kMinUnroundedLengthRatio * q ? u : q;
}

std::int64_t mm_to_steps(double mm, double steps_per_mm) {
    return static_cast<std::int64_t>(std::floor(mm * steps_per_mm + 0.5));
}

PerAxis<double> ArcGeom::at(const MotionBlock& b, double frac) const {
    const double ang = a0 + (cw ? -1 : 1) * sweep * frac;
    const double rad = r0 + (r1 - r0) * frac;
    PerAxis<double> p{};
    for (std::size_t a = 0; a < kAxes; ++a) p[a] = b.start[a] + (b.end[a] - b.start[a]) * frac;
    p[u] = cx + rad * std::cos(ang);
    p[v] = cy + rad * std::sin(ang);
    return p;
}

ArcGeom arc_geom(const MotionBlock& b) {
    const ArcFrame f = arc_frame(b);
    ArcGeom g;
    g.u = f.first;
    g.v = f.second;
    g.cx = f.center_first;
    g.cy = f.center_second;
    g.r0 = std::hypot(b.start[g.u] - g.cx, b.start[g.v] - g.cy);
    g.r1 = std::hypot(b.end[g.u] - g.cx, b.end[g.v] - g.cy);
    g.a0 = std::atan2(b.start[g.v] - g.cy, b.start[g.u] - g.cx);
    const double a1 = std::atan2(b.end[g.v] - g.cy, b.end[g.u] - g.cx);
    g.cw = b.kind == MotionKind::arc_cw;
    constexpr double two_pi = 2 * std::numbers::pi;
    g.sweep = g.cw ? g.a0 - a1 : a1 - g.a0;
    const bool closed = std::hypot(b.end[g.u] - b.start[g.u], b.end[g.v] - b.start[g.v]) < 1e-9;
    if (closed) {
        g.sweep = two_pi;
    } else {
        while (g.sweep <= 0) g.sweep += two_pi;
        while (g.sweep > two_pi) g.sweep -= two_pi;
    }
    return g;
}

namespace {

// How many chords stand off the arc by at most tol: a chord of angle theta on
// radius r stands off it by r(1 - cos(theta/2)).
double arc_chord_count(const ArcGeom& g, double tol) {
    const double r = std::max(g.r0, g.r1);
    double max_angle = std::numbers::pi / 2;
    if (tol < r) max_angle = std::min(max_angle, 2 * std::acos(1 - tol / r));
    return std::max(1.0, std::ceil(g.sweep / max_angle - 1e-9));
}

std::vector<PerAxis<double>> arc_chord_points(const MotionBlock& b, const ArcGeom& g, std::size_t n) {
    std::vector<PerAxis<double>> pts;
    pts.reserve(n);
    for (std::size_t i = 1; i < n; ++i) pts.push_back(g.at(b, static_cast<double>(i) / static_cast<double>(n)));
    pts.push_back(b.end);
    return pts;
}

// The points that bound an arc: its ends and the axis-extreme points (0, 90,
// 180, 270 degrees) the sweep passes; the chord points lie within their box
// (to within the end radii's difference, which the G-code's arc tolerance
// keeps small; the chord points are checked too). Checked against the travel
// before any chord is made, so a huge arc is refused at once.
std::vector<PerAxis<double>> arc_extremes(const MotionBlock& b, const ArcGeom& g) {
    constexpr double two_pi = 2 * std::numbers::pi;
    std::vector<PerAxis<double>> pts{b.start, b.end};
    for (int q = 0; q < 4; ++q) {
        const double ang = q * std::numbers::pi / 2;
        double d = g.cw ? g.a0 - ang : ang - g.a0;  // how far along the sweep the angle lies
        while (d < 0) d += two_pi;
        while (d >= two_pi) d -= two_pi;
        if (d <= g.sweep) pts.push_back(g.at(b, d / g.sweep));
    }
    return pts;
}

// Most chords one arc may become (a full circle of radius 1e12 mm at 0.005 mm
// would be 3e7): far above any arc inside a machine's travel.
constexpr std::size_t kMaxArcChords = 1'000'000;

}  // namespace

std::vector<PerAxis<double>> arc_chord_points(const MotionBlock& b, double tol) {
    const ArcGeom g = arc_geom(b);
    return arc_chord_points(b, g, static_cast<std::size_t>(arc_chord_count(g, tol)));
}

std::vector<PerAxis<double>> nurbs_chord_points(const MotionBlock& b, double tol, std::vector<double>* radii) {
    const Nurbs& c = *b.curve;
    const std::vector<double> us = c.chord_parameters(tol);
    if (us.empty()) return {};  // more chords than Nurbs::kMaxChords, or too far out: refused by the caller
    const std::size_t n = us.size();
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i) r[i] = c.radius(us[i]);
    // A chord's ends also take the radius at its middle: the tighter of the two
    // points' and the chord's interior stands for the curve there.
    std::vector<double> rr = r;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        const double mid = c.radius((us[i] + us[i + 1]) / 2);
        rr[i] = std::min(rr[i], mid);
        rr[i + 1] = std::min(rr[i + 1], mid);
    }
    if (radii) *radii = rr;
    std::vector<PerAxis<double>> pts;
    pts.reserve(n - 1);
    for (std::size_t i = 1; i + 1 < n; ++i) {
        const Eigen::Vector3d q = c.point(us[i]);
        PerAxis<double> p = b.start;
        p[0] = q[0];
        p[1] = q[1];
        pts.push_back(p);
    }
    pts.push_back(b.end);
    return pts;
}

namespace {

double norm(const PerAxis<double>& v) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s);
}
PerAxis<double> sub(const PerAxis<double>& a, const PerAxis<double>& b) {
    PerAxis<double> d{};
    for (std::size_t i = 0; i < kAxes; ++i) d[i] = a[i] - b[i];
    return d;
}
double dot(const PerAxis<double>& a, const PerAxis<double>& b) {
    double s = 0;
    for (std::size_t i = 0; i < kAxes; ++i) s += a[i] * b[i];
    return s;
}

// Turn angle (rad) at b of the polyline a-b-c.
double turn(const PerAxis<double>& a, const PerAxis<double>& b, const PerAxis<double>& c) {
    const auto u = sub(b, a), w = sub(c, b);
    const double nu = norm(u), nw = norm(w);
    if (nu == 0 || nw == 0) return 0;
    return std::acos(std::clamp(dot(u, w) / (nu * nw), -1.0, 1.0));
}

}  // namespace

namespace {

// The path radius at point i of a polyline of n points (path_radii), from
// accessors of its points, their smoothness and their arc radii: it reads at
// most 65 points each side of i. n may be a bound (the polyline still
// growing) when i + 65 < the points known.
template <class Pts, class Smooth, class Arc>
double radius_at(std::size_t i, std::size_t n, const Pts& pts, const Smooth& smooth, const Arc& arc_radius) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    if (i == 0 || i + 1 >= n || !smooth(i)) return inf;
    if (arc_radius(i) < inf) return arc_radius(i);
    // The smooth run around i, as far as fitting needs (at most 64 points a side).
    std::size_t left = 1, right = 1;
    double best = inf;
    for (std::size_t m = 1;; m *= 2) {
        // Widen each side to m points while the run stays smooth and straight-edged.
        while (left < m && i >= left + 1 && smooth(i - left) && arc_radius(i - left) == inf) ++left;
        while (right < m && i + right + 1 < n && smooth(i + right) && arc_radius(i + right) == inf) ++right;
        const auto& A = pts(i - left);
        const auto& B = pts(i + right);
        const auto& P = pts(i);
        const auto ab = sub(B, A), ap = sub(P, A), bp = sub(P, B);
        const double lab = norm(ab);
        double h = norm(ap);
        if (lab > 0) {
            const double t = dot(ap, ab) / (lab * lab);
            PerAxis<double> off{};
            for (std::size_t k = 0; k < kAxes; ++k) off[k] = ap[k] - t * ab[k];
            h = norm(off);
        }
        // Circumradius |PA||PB| / (2h), with the noise added to h: never too large.
        best = norm(ap) * norm(bp) / (2 * (h + kGeometryNoiseMm));
        const bool grown = left == m || right == m;
        if (h >= 10 * kGeometryNoiseMm || m >= 64 || !grown) break;
    }
    return best;
}

// How far radius_at() reads past its point.
constexpr std::size_t kRadiusReach = 65;

}  // namespace

std::vector<double> path_radii(const std::vector<PerAxis<double>>& pts,
                               const std::vector<double>& arc_radius) {
    const std::size_t n = pts.size();
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<double> r(n, inf);
    if (n < 3) return r;
    // smooth[i]: the polyline goes on through point i with no corner.
    std::vector<char> smooth(n, 0);
    for (std::size_t i = 1; i + 1 < n; ++i) smooth[i] = turn(pts[i - 1], pts[i], pts[i + 1]) <= kSmoothTurnRad;
    for (std::size_t i = 1; i + 1 < n; ++i)
        r[i] = radius_at(
            i, n, [&](std::size_t k) -> const PerAxis<double>& { return pts[k]; },
            [&](std::size_t k) { return smooth[k] != 0; }, [&](std::size_t k) { return arc_radius[k]; });
    return r;
}

struct StepSegmenter::Impl {
    const Machine& m;
    std::string file;
    std::vector<Diagnostic> errors;
    static constexpr double inf = std::numeric_limits<double>::infinity();

    PerAxis<std::int64_t> pos{};
    bool have_pos = false;
    bool finished = false;
    // The polyline of every point the blocks pass (arc chords, NURBS chords,
    // line ends; a dwell repeats its point), in a window: its points, the arc
    // radius each lies on (infinity: none), whether it goes on smoothly there
    // (known once the point after it is), its path radius (radius_at(), NaN
    // until made).
    detail::Window<PerAxis<double>> verts;
    detail::Window<double> arc_r;
    detail::Window<char> smooth;
    detail::Window<double> radius;
    std::size_t cur_vertex = 0;
    // Segments made, waiting for the points after them; each with its first point.
    struct Pending {
        StepSegment s;
        std::size_t first = 0;
    };
    std::deque<Pending> pending;
    bool last_was_dwell = false;  // the segment handed out before
    std::deque<StepSegment> ready;
    std::size_t handed = 0, max_held = 0;

    Impl(const Machine& machine, std::string job_file) : m(machine), file(std::move(job_file)) {}

    PerAxis<std::int64_t> to_steps(const PerAxis<double>& p) const {
        PerAxis<std::int64_t> s{};
        for (std::size_t a = 0; a < kAxes; ++a) {
            if (m.axes[a].present) s[a] = mm_to_steps(p[a], m.axes[a].steps_per_mm);
        }
        return s;
    }

    // Whether p is inside the travel; reports the first offending axis once per block.
    bool check(const MotionBlock& b, const PerAxis<double>& p) {
        for (std::size_t a = 0; a < kAxes; ++a) {
            const auto& ax = m.axes[a];
            const char L = static_cast<char>(std::toupper(kAxisLetters[a]));
            if (!ax.present) {
                if (std::abs(p[a]) > 1e-9) {
                    errors.push_back({file, b.loc, fmt::format("axis {} is not on this machine ({})", L, m.file)});
                    return false;
                }
                continue;
            }
            const double eps = 1e-9;
            if (p[a] < ax.travel_min_mm - eps || p[a] > ax.travel_max_mm + eps) {
                errors.push_back({file, b.loc,
                                  fmt::format("{} {:.3f} mm is outside the travel {:g}..{:g} mm of axis {}", L, p[a],
                                              ax.travel_min_mm, ax.travel_max_mm, kAxisLetters[a])});
                return false;
            }
        }
        return true;
    }

    void add_vertex(const PerAxis<double>& p, double arc) {
        const std::size_t i = verts.end();
        verts.push_back(p);
        arc_r.push_back(arc);
        smooth.push_back(0);
        radius.push_back(std::numeric_limits<double>::quiet_NaN());
        // The point before it now has both neighbours.
        if (i >= 2) smooth[i - 1] = turn(verts[i - 2], verts[i - 1], verts[i]) <= kSmoothTurnRad;
    }

    double radius_of(std::size_t v) {
        double& r = radius[v];
        if (std::isnan(r)) {
            const std::size_t known = verts.end();
            // The polyline's length is known once finished; before, a bound
            // radius_at() never reaches (v + kRadiusReach < known).
            const std::size_t n = finished ? (known < 3 ? 0 : known) : std::numeric_limits<std::size_t>::max();
            r = radius_at(
                v, n, [&](std::size_t k) -> const PerAxis<double>& { return verts[k]; },
                [&](std::size_t k) { return smooth[k] != 0; }, [&](std::size_t k) { return arc_r[k]; });
        }
        return r;
    }

    void add_block(const MotionBlock& b, std::size_t bi) {
        if (!have_pos) {
            pos = to_steps(b.start);
            have_pos = true;
            add_vertex(b.start, inf);
        }
        StepSegment proto;
        proto.kind = b.kind;
        proto.loc = b.loc;
        proto.block = bi;
        proto.feed = b.feed;
        proto.spindle_on = b.spindle_on;
        proto.torch = b.spindle_on || b.output0;
        if (b.kind == MotionKind::dwell) {
            proto.start = proto.end = pos;
            proto.dwell_s = b.dwell_s;
            proto.from_mm = proto.to_mm = verts[verts.end() - 1];
            pending.push_back({proto, verts.end() - 1});
            // A dwell is a stop: its point repeats, so the bend across it is no curve.
            add_vertex(verts[verts.end() - 1], inf);
            cur_vertex = verts.end() - 1;
            return;
        }
        std::vector<PerAxis<double>> pts;
        const bool is_arc = b.kind == MotionKind::arc_cw || b.kind == MotionKind::arc_ccw;
        double rad = inf;
        std::vector<double> curve_r;  // nurbs: the true radius at each point (start first)
        if (b.kind == MotionKind::nurbs) {
            pts = nurbs_chord_points(b, m.planner.arc_tolerance_mm, &curve_r);
            if (pts.empty()) {
                errors.push_back({file, b.loc,
                                  fmt::format("the curve needs more than {} chords within arc_tolerance_mm = {:g} (or its "
                                              "numbers are too large to meet it in double precision)",
                                              Nurbs::kMaxChords, m.planner.arc_tolerance_mm)});
                return;
            }
            arc_r.back() = std::min(arc_r.back(), curve_r.front());  // the curve's start point
        } else if (is_arc) {
            const ArcGeom g = arc_geom(b);
            bool inside = true;
            for (const auto& p : arc_extremes(b, g)) inside = inside && check(b, p);
            if (!inside) return;
            const double n = arc_chord_count(g, m.planner.arc_tolerance_mm);
            if (n > double(kMaxArcChords)) {
                errors.push_back(
                    {file, b.loc,
                     fmt::format("an arc of radius {:.6g} mm needs {:.3g} chords within arc_tolerance_mm = {:g}; "
                                 "at most {} are made",
                                 std::max(g.r0, g.r1), n, m.planner.arc_tolerance_mm, kMaxArcChords)});
                return;
            }
            pts = arc_chord_points(b, g, static_cast<std::size_t>(n));
            rad = std::min(g.r0, g.r1);              // in the arc's own plane (G17, G18 or G19)
            arc_r.back() = std::min(arc_r.back(), rad);  // the arc's start point
        } else {
            pts.push_back(b.end);
        }
        for (std::size_t pi = 0; pi < pts.size(); ++pi) {
            const auto& p = pts[pi];
            if (!check(b, p)) break;
            add_vertex(p, curve_r.empty() ? rad : curve_r[pi + 1]);
            const auto target = to_steps(p);
            if (target == pos) continue;  // shorter than a step: merged into the next
            StepSegment s = proto;
            s.start = pos;
            s.end = target;
            s.from_mm = verts[cur_vertex];
            s.to_mm = p;
            const std::size_t first = cur_vertex;
            cur_vertex = verts.end() - 1;
            bool too_long = false;
            for (std::size_t a = 0; a < kAxes; ++a) {
                if (std::llabs(target[a] - pos[a]) >= (std::int64_t{1} << 31)) too_long = true;
            }
            if (too_long) {
                errors.push_back({file, b.loc, "move of 2^31 steps or more on one axis"});
                break;
            }
            pending.push_back({s, first});
            pos = target;
        }
    }

    // Segments whose radii are known: the segment after them is made, and the
    // points far enough past their last (or the job has ended).
    void settle() {
        while (errors.empty() && !pending.empty()) {
            Pending& k = pending.front();
            const bool has_next = pending.size() >= 2;
            if (!has_next && !finished) break;
            const std::size_t last = has_next ? pending[1].first : verts.end() - 1;
            if (!finished && last + kRadiusReach >= verts.end()) break;
            StepSegment& s = k.s;
            const bool dwell = s.kind == MotionKind::dwell;
            if (!dwell) {
                double rad = inf;
                for (std::size_t v = k.first + 1; v < last; ++v) rad = std::min(rad, radius_of(v));
                const std::size_t v0 = k.first, v1 = last;
                // A dwell is a stop: the path's bend across it (through its repeated
                // vertex) caps nothing. (A trailing dwell's repeated vertex, the
                // polyline's last, used to give the move before it a radius of 0: a
                // cruise of 0 and "internal: no feasible profile".)
                const bool dwell_after = has_next && pending[1].s.kind == MotionKind::dwell;
                const double r0 = last_was_dwell ? inf : radius_of(v0), r1 = dwell_after ? inf : radius_of(v1);
                // A chord whose both ends are on a curve is part of it. A straight
                // block (G0/G1) between two arcs is not: the arcs' radii at its ends
                // are theirs (the junction caps take them), the line is straight.
                const bool straight_between_arcs =
                    (s.kind == MotionKind::linear || s.kind == MotionKind::rapid) && (arc_r[v0] < inf || arc_r[v1] < inf);
                if (r0 < inf && r1 < inf && !straight_between_arcs) rad = std::min({rad, r0, r1});
                s.radius_mm = rad;
                s.radius_ends_max_mm = std::max(r0, r1);
                s.radius_start_mm = r0;
            }
            last_was_dwell = dwell;
            ready.push_back(std::move(s));
            pending.pop_front();
        }
        // The points a segment still waiting may read (radius_at reaches
        // kRadiusReach points back).
        const std::size_t keep = pending.empty() ? cur_vertex : pending.front().first;
        const std::size_t from = keep > kRadiusReach ? keep - kRadiusReach : 0;
        verts.drop_before(from);
        arc_r.drop_before(from);
        smooth.drop_before(from);
        radius.drop_before(from);
        max_held = std::max(max_held, verts.held());
    }
};

StepSegmenter::StepSegmenter(const Machine& m, std::string job_file)
    : impl_(std::make_unique<Impl>(m, std::move(job_file))) {}
StepSegmenter::~StepSegmenter() = default;
StepSegmenter::StepSegmenter(StepSegmenter&&) noexcept = default;
StepSegmenter& StepSegmenter::operator=(StepSegmenter&&) noexcept = default;

void StepSegmenter::push(const MotionBlock& b, std::size_t index) {
    Impl& p = *impl_;
    if (p.finished) throw std::logic_error("StepSegmenter::push after finish");
    p.add_block(b, index);
    p.settle();
}

void StepSegmenter::finish() {
    Impl& p = *impl_;
    if (p.finished) return;
    p.finished = true;
    p.settle();
}

std::optional<StepSegment> StepSegmenter::next() {
    Impl& p = *impl_;
    if (!p.errors.empty() || p.ready.empty()) return std::nullopt;
    std::optional<StepSegment> s = std::move(p.ready.front());
    p.ready.pop_front();
    ++p.handed;
    return s;
}

std::size_t StepSegmenter::handed_out() const { return impl_->handed; }
bool StepSegmenter::done() const {
    return impl_->finished && impl_->errors.empty() && impl_->pending.empty() && impl_->ready.empty();
}
const std::vector<Diagnostic>& StepSegmenter::errors() const { return impl_->errors; }
std::size_t StepSegmenter::held_points() const { return impl_->verts.held(); }
std::size_t StepSegmenter::max_held_points() const { return impl_->max_held; }

Result<std::vector<StepSegment>> make_step_segments(const Job& job, const Machine& m) {
    Result<std::vector<StepSegment>> result;
    StepSegmenter segmenter(m, job.file);
    std::vector<StepSegment> out;
    for (std::size_t bi = 0; bi < job.blocks.size(); ++bi) {
        segmenter.push(job.blocks[bi], bi);
        while (auto s = segmenter.next()) out.push_back(std::move(*s));
    }
    segmenter.finish();
    while (auto s = segmenter.next()) out.push_back(std::move(*s));
    if (!segmenter.errors().empty()) {
        result.errors = segmenter.errors();
        return result;
    }
    result.value = std::move(out);
    return result;
}

}  // namespace cpstep::plan

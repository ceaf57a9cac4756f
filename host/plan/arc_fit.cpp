// SPDX-License-Identifier: MIT
#include "plan/arc_fit.h"

#include "plan/segments.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

namespace cpstep::plan {

namespace {

struct Pt {
    double x = 0, y = 0;
};
Pt operator-(Pt a, Pt b) { return {a.x - b.x, a.y - b.y}; }
double dot(Pt a, Pt b) { return a.x * b.x + a.y * b.y; }
double cross(Pt a, Pt b) { return a.x * b.y - a.y * b.x; }
double norm(Pt a) { return std::hypot(a.x, a.y); }

constexpr double kInf = std::numeric_limits<double>::infinity();

// A G1 that may join a run: no pause, no curve, only X and Y move.
bool eligible(const MotionBlock& b) {
    if (b.kind != MotionKind::linear || b.pause != PauseKind::none || b.dwell_s != 0 || b.curve) return false;
    for (int a = 2; a < kAxes; ++a)
        if (b.start[a] != b.end[a]) return false;
    return true;
}

// Whether b continues a run that `first` starts: the same feed, spindle and tool,
// the same coordinates besides X and Y, and starting where `prev` ends.
bool continues(const MotionBlock& first, const MotionBlock& prev, const MotionBlock& b) {
    if (!eligible(b) || b.feed != first.feed || b.spindle_on != first.spindle_on || b.output0 != first.output0 ||
        b.spindle_ccw != first.spindle_ccw || b.tool != first.tool)
        return false;
    for (int a = 0; a < kAxes; ++a)
        if (b.start[a] != prev.end[a]) return false;
    for (int a = 2; a < kAxes; ++a)
        if (b.start[a] != first.start[a]) return false;
    return true;
}

// Points p[i..j] within tol of the line from p[i] to p[j], each no farther back
// along it than the one before: the largest distance, or infinity.
double line_fit(const std::vector<Pt>& p, std::size_t i, std::size_t j, double tol) {
    const Pt d = p[j] - p[i];
    const double L = norm(d);
    if (!(L > 0)) return kInf;
    const Pt u{d.x / L, d.y / L};
    double along = 0, worst = 0;
    for (std::size_t k = i + 1; k < j; ++k) {
        const Pt w = p[k] - p[i];
        const double s = dot(w, u), e = std::abs(cross(u, w));
        if (e > tol || s < along || s > L) return kInf;
        along = s;
        worst = std::max(worst, e);
    }
    return worst;
}

struct ArcFit {
    double cx = 0, cy = 0, deviation = kInf;
    bool ccw = false;
};

// A circle through p[i] and p[j] (its centre on their bisector, placed to make
// the largest radial distance of p[i+1..j-1] smallest) that every point and every
// line p[k]p[k+1] stays within tol of, every line going round its centre the way
// the path bends, by less than 1.9 pi in all. deviation = infinity when there is none.
ArcFit arc_fit(const std::vector<Pt>& p, std::size_t i, std::size_t j, double tol) {
    ArcFit fail;
    if (j < i + 3) return fail;
    // Which way the path turns, from its ends and middle (each line must then go
    // round the centre that way, checked below).
    const double bend = cross(p[(i + j) / 2] - p[i], p[j] - p[(i + j) / 2]);
    if (bend == 0) return fail;
    const int turn = bend > 0 ? 1 : -1;
    const Pt d = p[j] - p[i];
    const double L = norm(d);
    if (L <= tol) return fail;  // (nearly) closed: the circle through the ends is not determined
    const Pt m{(p[i].x + p[j].x) / 2, (p[i].y + p[j].y) / 2};
    const Pt n{-d.y / L, d.x / L};
    // Start at the circle through the ends and the middle point.
    const Pt q = p[(i + j) / 2];
    const Pt a = q - p[i], b = p[j] - p[i];
    const double den = 2 * cross(a, b);
    if (std::abs(den) <= 1e-15 * norm(a) * norm(b)) return fail;
    const double a2 = dot(a, a), b2 = dot(b, b);
    const Pt c0{p[i].x + (b.y * a2 - a.y * b2) / den, p[i].y + (a.x * b2 - b.x * a2) / den};
    const double t0 = dot(c0 - m, n);
    const auto worst = [&](double t) {
        const Pt c{m.x + t * n.x, m.y + t * n.y};
        const double r = norm(p[i] - c);
        double w = 0;
        for (std::size_t k = i + 1; k < j; ++k) w = std::max(w, std::abs(norm(p[k] - c) - r));
        return w;
    };
    double lo = t0 - 0.5 * (std::abs(t0) + L), hi = t0 + 0.5 * (std::abs(t0) + L);
    for (int it = 0; it < 80; ++it) {
        const double t1 = lo + (hi - lo) / 3, t2 = hi - (hi - lo) / 3;
        if (worst(t1) <= worst(t2)) hi = t2;
        else lo = t1;
    }
    const double t = (lo + hi) / 2;
    const Pt c{m.x + t * n.x, m.y + t * n.y};
    const double r = norm(p[i] - c);
    if (!(r > tol) || r > 1e6) return fail;
    // Every vertex near the circle, every line near the arc, one way round.
    std::vector<double> e(j - i + 1, 0.0);
    for (std::size_t k = i + 1; k < j; ++k) e[k - i] = std::abs(norm(p[k] - c) - r);
    double sweep = 0, dev = 0;
    for (std::size_t k = i; k < j; ++k) {
        const Pt u = p[k] - c, v = p[k + 1] - c;
        const double step = std::atan2(cross(u, v), dot(u, v));
        if (step * turn <= 0) return fail;
        sweep += step;
        const double half = norm(p[k + 1] - p[k]) / 2;
        if (half >= r) return fail;
        const double sag = r - std::sqrt(r * r - half * half);
        const double here = std::max(e[k - i], e[k + 1 - i]) + sag;
        if (here > tol) return fail;
        dev = std::max(dev, here);
    }
    if (std::abs(sweep) >= 1.9 * std::numbers::pi) return fail;
    return {c.x, c.y, dev, turn > 0};
}

// The longest stretch from p[s] (at least `least` lines) for which
// fits(s, s + len) holds, by doubling and then bisection: 0 for none. `avail`
// lines from p[s] are held; `known`: they are all the run has. At most
// kArcFitMaxLines lines are taken. Null when the answer depends on lines not yet
// held; `need` is then how many it needs.
template <class Fits>
std::optional<std::size_t> longest(std::size_t s, std::size_t avail, bool known, std::size_t least, Fits fits,
                                   std::size_t& need) {
    const std::size_t lines = std::min(avail, kArcFitMaxLines);
    known = known || avail >= kArcFitMaxLines;
    if (lines < least) {
        if (known) return 0;
        need = least;
        return std::nullopt;
    }
    if (!fits(s, s + least)) return 0;
    std::size_t good = least, bad = lines + 1;
    for (std::size_t len = least * 2;; len *= 2) {
        if (len > lines) {
            if (!known) {
                need = std::min(len, kArcFitMaxLines);
                return std::nullopt;
            }
            break;
        }
        if (!fits(s, s + len)) {
            bad = len;
            break;
        }
        good = len;
    }
    if (bad == lines + 1 && good < lines) {
        if (fits(s, s + lines)) return lines;
        bad = lines;
    }
    while (bad - good > 1) {
        const std::size_t mid = good + (bad - good) / 2;
        if (fits(s, s + mid)) good = mid;
        else bad = mid;
    }
    return good;
}

}  // namespace

struct ArcFitter::Impl {
    double tol = 0;          // G1 chains (0: passed through)
    double curve_tol = 0;    // NURBS blocks (0: passed through)
    ArcFitStats st;
    bool finished = false;
    bool in_run = false;
    bool whole_runs = false;
    MotionBlock first, prev;        // the run's first line and its last so far
    std::vector<MotionBlock> run;   // the run's lines, run[k] from p[k] to p[k + 1]
    std::vector<Pt> p;
    std::size_t s = 0;              // the first line not yet handed out
    std::size_t need = 0;           // lines from s the next decision needs
    std::deque<MotionBlock> out;

    // A NURBS block as arcs and lines (arc_fit.h): false when it stays a NURBS.
    bool fit_curve(const MotionBlock& b) {
        const double chord = curve_tol * kCurveChordShare;
        const std::vector<PerAxis<double>> pts = nurbs_chord_points(b, chord);
        if (pts.size() < 3) return false;  // too few chords for an arc, or more than Nurbs::kMaxChords
        ArcFitter inner(ArcFitTolerances{curve_tol - chord, 0});
        MotionBlock line = b;
        line.kind = MotionKind::linear;
        line.curve.reset();
        for (const PerAxis<double>& q : pts) {
            line.end = q;
            inner.push(line);
            line.start = q;
        }
        inner.finish();
        std::vector<MotionBlock> made;
        while (auto nb = inner.next()) made.push_back(std::move(*nb));
        const ArcFitStats& is = inner.stats();
        if (is.arcs == 0 || made.size() >= nurbs_chord_points(b, curve_tol).size()) return false;
        ++st.curves;
        st.curve_arcs += is.arcs;
        st.curve_lines += made.size() - is.arcs;
        // Within the rest of the tolerance of the chords, which lie within `chord` of the curve.
        st.curve_max_deviation_mm = std::max(st.curve_max_deviation_mm, is.max_deviation_mm + chord);
        for (MotionBlock& nb : made) out.push_back(std::move(nb));
        return true;
    }

    // Hands out what the lines held decide (all of them once the run `ended`).
    void decide(bool ended) {
        if (whole_runs && !ended) return;
        while (s < run.size()) {
            const std::size_t avail = run.size() - s;
            if (!ended && avail < need) return;
            need = 0;
            const auto la = longest(s, avail, ended, 3, [&](std::size_t x, std::size_t y) {
                return arc_fit(p, x, y, tol).deviation <= tol;
            }, need);
            if (!la) return;
            const auto ll = longest(s, avail, ended, 2, [&](std::size_t x, std::size_t y) {
                return line_fit(p, x, y, tol) <= tol;
            }, need);
            if (!ll) return;
            if (*la == 0 && *ll == 0) {
                out.push_back(run[s]);
                ++s;
                continue;
            }
            MotionBlock nb = run[s];
            nb.end = run[s + std::max(*la, *ll) - 1].end;
            if (*ll >= *la) {
                st.max_deviation_mm = std::max(st.max_deviation_mm, line_fit(p, s, s + *ll, tol));
                ++st.merged;
                st.lines_in_merged += *ll;
                s += *ll;
            } else {
                const ArcFit f = arc_fit(p, s, s + *la, tol);
                nb.kind = f.ccw ? MotionKind::arc_ccw : MotionKind::arc_cw;
                nb.plane = Plane::xy;
                nb.center_x = f.cx;
                nb.center_y = f.cy;
                st.max_deviation_mm = std::max(st.max_deviation_mm, f.deviation);
                ++st.arcs;
                st.lines_in_arcs += *la;
                s += *la;
            }
            out.push_back(std::move(nb));
        }
        if (ended || s == run.size()) {
            // p keeps where the next line of the run would start.
            run.clear();
            if (!p.empty()) p.erase(p.begin(), p.end() - 1);
            s = 0;
        } else if (s > run.size() / 2) {  // drop what is handed out (amortized)
            run.erase(run.begin(), run.begin() + std::ptrdiff_t(s));
            p.erase(p.begin(), p.begin() + std::ptrdiff_t(s));
            s = 0;
        }
    }
};

ArcFitter::ArcFitter(ArcFitTolerances tol, bool whole_runs) : impl_(std::make_unique<Impl>()) {
    impl_->tol = tol.lines_mm > 0 ? tol.lines_mm : 0;
    impl_->curve_tol = tol.curves_mm > 0 ? tol.curves_mm : 0;
    impl_->whole_runs = whole_runs;
}
ArcFitter::ArcFitter(double tol_mm, bool whole_runs) : ArcFitter(ArcFitTolerances{tol_mm, tol_mm}, whole_runs) {}

ArcFitTolerances arc_fit_tolerances(const Machine& m) {
    ArcFitTolerances t;
    t.lines_mm = m.planner.fit_arcs_mm;
    if (m.planner.arcs == ArcMode::conic && m.card.conic_width > 0) t.curves_mm = m.planner.arc_tolerance_mm;
    return t;
}
ArcFitter::~ArcFitter() = default;
ArcFitter::ArcFitter(ArcFitter&&) noexcept = default;
ArcFitter& ArcFitter::operator=(ArcFitter&&) noexcept = default;

void ArcFitter::push(const MotionBlock& b) {
    Impl& f = *impl_;
    if (f.finished) throw std::logic_error("ArcFitter::push after finish");
    if (!(f.tol > 0) && !(f.curve_tol > 0)) {
        f.out.push_back(b);
        return;
    }
    if (f.in_run && continues(f.first, f.prev, b)) {
        f.run.push_back(b);
        f.p.push_back({b.end[0], b.end[1]});
        f.prev = b;
        f.decide(false);
        return;
    }
    if (f.in_run) {
        f.decide(true);
        f.in_run = false;
    }
    if (!(f.tol > 0) || !eligible(b)) {   // (no chains fitted: every block ends a run)
        if (!(b.kind == MotionKind::nurbs && b.curve && f.curve_tol > 0 && f.fit_curve(b))) f.out.push_back(b);
        return;
    }
    f.in_run = true;
    f.first = f.prev = b;
    f.run.assign(1, b);
    f.p = {{b.start[0], b.start[1]}, {b.end[0], b.end[1]}};
    f.s = 0;
    f.need = 0;
    f.decide(false);
}

void ArcFitter::finish() {
    Impl& f = *impl_;
    if (f.finished) return;
    f.finished = true;
    if (f.in_run) f.decide(true);
    f.in_run = false;
}

std::optional<MotionBlock> ArcFitter::next() {
    Impl& f = *impl_;
    if (f.out.empty()) return std::nullopt;
    std::optional<MotionBlock> b = std::move(f.out.front());
    f.out.pop_front();
    return b;
}

const ArcFitStats& ArcFitter::stats() const { return impl_->st; }
std::size_t ArcFitter::held() const { return impl_->run.size() - impl_->s + impl_->out.size(); }

Job fit_arcs(const Job& job, double tol_mm, ArcFitStats* stats) {
    return fit_arcs(job, ArcFitTolerances{tol_mm, tol_mm}, stats);
}

Job fit_arcs(const Job& job, ArcFitTolerances tol_mm, ArcFitStats* stats) {
    if (!tol_mm.any()) return job;
    Job out;
    out.file = job.file;
    out.blocks.reserve(job.blocks.size());
    ArcFitter fitter(tol_mm);
    for (const MotionBlock& b : job.blocks) {
        fitter.push(b);
        while (auto nb = fitter.next()) out.blocks.push_back(std::move(*nb));
    }
    fitter.finish();
    while (auto nb = fitter.next()) out.blocks.push_back(std::move(*nb));
    if (stats) *stats = fitter.stats();
    return out;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/nurbs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>
#include <fmt/format.h>

namespace cpstep::plan {

namespace {

using Hom = Eigen::Vector4d;
using Local = std::array<Hom, kMaxNurbsOrder>;

// de Boor's algorithm for a B-spline of degree q over the knots t, evaluated
// at u in span k (t[k] <= u < t[k+1] of the original knot vector). d[j] is the
// control point of global index k - q + j. The derivative curves' knot
// vectors are the original one with the first (and last) 1 or 2 knots
// dropped, so the same indices into t serve all three (docs/CURVES.md).
Hom de_boor(int q, std::size_t k, Local d, const std::vector<double>& t, double u) {
    const auto K = static_cast<std::ptrdiff_t>(k);
    for (int r = 1; r <= q; ++r) {
        for (int j = q; j >= r; --j) {
            const double lo = t[static_cast<std::size_t>(j + K - q)];
            const double hi = t[static_cast<std::size_t>(j + 1 + K - r)];
            const double alpha = (u - lo) / (hi - lo);
            d[static_cast<std::size_t>(j)] =
                (1.0 - alpha) * d[static_cast<std::size_t>(j - 1)] + alpha * d[static_cast<std::size_t>(j)];
        }
    }
    return d[static_cast<std::size_t>(q)];
}

// The homogeneous control points (w P, w) of span k for degree p: d[j] is
// the point of global index k - p + j.
Local local_points(const std::vector<Hom>& hom, int p, std::size_t k) {
    const std::size_t first = k - static_cast<std::size_t>(p);
    Local d{};
    for (int j = 0; j <= p; ++j) d[static_cast<std::size_t>(j)] = hom[first + static_cast<std::size_t>(j)];
    return d;
}

// 5-point Gauss-Legendre on [a, b].
constexpr std::array<double, 5> kGlX = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
                                        0.9061798459386640};
constexpr std::array<double, 5> kGlW = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
                                        0.2369268850561891, 0.2369268850561891};

}  // namespace

std::optional<std::string> Nurbs::validate(int order, std::size_t points, const std::vector<double>& weights,
                                           const std::vector<double>& knots) {
    if (order < 2 || order > kMaxNurbsOrder)
        return fmt::format("NURBS order {} is outside 2..{}", order, kMaxNurbsOrder);
    if (points < static_cast<std::size_t>(order))
        return fmt::format("a NURBS of order {} needs at least {} control points, got {}", order, order, points);
    if (weights.size() != points)
        return fmt::format("{} weights for {} control points", weights.size(), points);
    for (std::size_t i = 0; i < weights.size(); ++i) {
        if (!std::isfinite(weights[i]) || !(weights[i] > 0))
            return fmt::format("weight {:g} of control point {} must be > 0", weights[i], i + 1);
    }
    const std::size_t need = points + static_cast<std::size_t>(order);
    if (knots.size() != need)
        return fmt::format("a NURBS of order {} with {} control points needs {} knots, got {}", order, points, need,
                           knots.size());
    for (std::size_t i = 0; i < knots.size(); ++i) {
        if (!std::isfinite(knots[i])) return fmt::format("knot {} is not a finite number", i + 1);
        if (i > 0 && knots[i] < knots[i - 1])
            return fmt::format("knots must not decrease: knot {} ({:g}) is below knot {} ({:g})", i + 1, knots[i], i,
                               knots[i - 1]);
    }
    const auto ord = static_cast<std::size_t>(order);
    for (std::size_t i = 1; i < ord; ++i) {
        if (knots[i] != knots[0])
            return fmt::format("knots must be clamped: the first {} knots must be equal (the curve starts at the "
                               "first control point)",
                               order);
        if (knots[need - 1 - i] != knots[need - 1])
            return fmt::format("knots must be clamped: the last {} knots must be equal (the curve ends at the last "
                               "control point)",
                               order);
    }
    if (!(knots[need - 1] > knots[0])) return std::string("the knots span no parameter range (all equal)");
    // Interior multiplicity at most order - 1 (degree): C0 at worst.
    std::size_t i = ord;
    while (i < points) {
        std::size_t j = i;
        while (j + 1 < points && knots[j + 1] == knots[i]) ++j;
        const std::size_t mult = j - i + 1;
        if (mult >= ord)
            return fmt::format("interior knot {:g} is repeated {} times; at most {} (order - 1) keep the curve "
                               "connected",
                               knots[i], mult, order - 1);
        i = j + 1;
    }
    return std::nullopt;
}

std::vector<double> Nurbs::uniform_clamped_knots(std::size_t points, int order) {
    const auto k = static_cast<std::size_t>(order);
    std::vector<double> t;
    t.reserve(points + k);
    for (std::size_t i = 0; i < points + k; ++i) {
        if (i < k) {
            t.push_back(0.0);
        } else if (i < points) {
            t.push_back(static_cast<double>(i - k + 1));
        } else {
            t.push_back(static_cast<double>(points - k + 1));
        }
    }
    return t;
}

Nurbs::Nurbs(int order, std::vector<Eigen::Vector3d> points, std::vector<double> weights, std::vector<double> knots)
    : order_(order), points_(std::move(points)), weights_(std::move(weights)), knots_(std::move(knots)) {
    if (auto e = validate(order_, points_.size(), weights_, knots_)) throw std::invalid_argument(*e);
    hom_.reserve(points_.size());
    for (std::size_t i = 0; i < points_.size(); ++i) {
        Hom h;
        h.head<3>() = weights_[i] * points_[i];
        h[3] = weights_[i];
        hom_.push_back(h);
    }
}

std::vector<double> Nurbs::breakpoints() const {
    std::vector<double> b;
    for (std::size_t i = static_cast<std::size_t>(degree()); i <= points_.size(); ++i) {
        if (b.empty() || knots_[i] != b.back()) b.push_back(knots_[i]);
    }
    return b;
}

std::size_t Nurbs::span(double u) const {
    const auto p = static_cast<std::size_t>(degree());
    const std::size_t n = points_.size();
    // The last non-empty span [t_k, t_k+1) with t_k <= u, within p..n-1.
    auto it = std::upper_bound(knots_.begin() + static_cast<std::ptrdiff_t>(p),
                               knots_.begin() + static_cast<std::ptrdiff_t>(n), u);
    std::size_t k = static_cast<std::size_t>(it - knots_.begin());
    k = k == p ? p : k - 1;
    if (k > n - 1) k = n - 1;
    while (k > p && knots_[k] == knots_[k + 1]) --k;   // u at or past the end: the last non-empty span
    while (k < n - 1 && knots_[k] == knots_[k + 1]) ++k;  // u before the start: the first
    return k;
}

Eigen::Vector3d Nurbs::point(double u) const {
    const std::size_t k = span(u);
    const Hom a0 = de_boor(degree(), k, local_points(hom_, degree(), k), knots_, u);
    return a0.head<3>() / a0[3];
}

NurbsPoint Nurbs::eval(double u) const {
    const int p = degree();
    const std::size_t k = span(u);
    const std::size_t first = k - static_cast<std::size_t>(p);
    const Local d = local_points(hom_, p, k);
    const Hom a0 = de_boor(p, k, d, knots_, u);
    Hom a1 = Hom::Zero(), a2 = Hom::Zero();
    if (p >= 1) {
        // First derivative control points Q_j = p (d_{j+1} - d_j) / (t_{k+j+1} - t_{k-p+j+1}).
        Local q{};
        for (int j = 0; j < p; ++j) {
            const double den = knots_[k + static_cast<std::size_t>(j) + 1] - knots_[first + static_cast<std::size_t>(j) + 1];
            q[static_cast<std::size_t>(j)] =
                p * (d[static_cast<std::size_t>(j) + 1] - d[static_cast<std::size_t>(j)]) / den;
        }
        a1 = de_boor(p - 1, k, q, knots_, u);
        if (p >= 2) {
            // Second: R_j = (p-1) (Q_{j+1} - Q_j) / (t_{k+j+1} - t_{k-p+j+2}).
            Local r{};
            for (int j = 0; j < p - 1; ++j) {
                const double den =
                    knots_[k + static_cast<std::size_t>(j) + 1] - knots_[first + static_cast<std::size_t>(j) + 2];
                r[static_cast<std::size_t>(j)] =
                    (p - 1) * (q[static_cast<std::size_t>(j) + 1] - q[static_cast<std::size_t>(j)]) / den;
            }
            a2 = de_boor(p - 2, k, r, knots_, u);
        }
    }
    // Quotient rule on C = A / w.
    NurbsPoint out;
    const double w = a0[3], w1 = a1[3], w2 = a2[3];
    out.c = a0.head<3>() / w;
    out.d1 = (a1.head<3>() - w1 * out.c) / w;
    out.d2 = (a2.head<3>() - 2 * w1 * out.d1 - w2 * out.c) / w;
    return out;
}

double Nurbs::radius(double u) const {
    const NurbsPoint e = eval(u);
    const double s = e.d1.norm();
    const double cross = e.d1.cross(e.d2).norm();
    if (cross <= 0) return std::numeric_limits<double>::infinity();
    return s * s * s / cross;
}

double Nurbs::length(double ua, double ub, double rel_tol) const {
    if (ua > ub) return -length(ub, ua, rel_tol);
    if (ua == ub) return 0;
    auto gl = [&](double a, double b) {
        const double h = (b - a) / 2, m = (a + b) / 2;
        double s = 0;
        for (std::size_t i = 0; i < kGlX.size(); ++i) s += kGlW[i] * eval(m + h * kGlX[i]).d1.norm();
        return s * h;
    };
    // Adaptive: accept a piece when its two halves agree with the whole.
    auto adapt = [&](auto&& self, double a, double b, double whole, double tol, int depth) -> double {
        const double m = (a + b) / 2;
        const double l = gl(a, m), r = gl(m, b);
        if (std::abs(l + r - whole) <= tol || depth >= 40) return l + r;
        return self(self, a, m, l, tol / 2, depth + 1) + self(self, m, b, r, tol / 2, depth + 1);
    };
    std::vector<double> cuts{ua};
    for (double b : breakpoints())
        if (b > ua && b < ub) cuts.push_back(b);
    cuts.push_back(ub);
    double total = 0;
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double whole = gl(cuts[i], cuts[i + 1]);
        const double tol = std::max(rel_tol * std::abs(whole), 1e-300);
        total += adapt(adapt, cuts[i], cuts[i + 1], whole, tol, 0);
    }
    return total;
}

double Nurbs::chord_error(double ua, double ub) const {
    return chord_error_until(ua, ub, std::numeric_limits<double>::infinity());
}

double Nurbs::chord_error_until(double ua, double ub, double stop) const {
    const Eigen::Vector3d P = point(ua), Q = point(ub);
    const Eigen::Vector3d chord = Q - P;
    const double len = chord.norm();
    auto dist = [&](double u) {
        const Eigen::Vector3d c = point(u);
        const Eigen::Vector3d v = c - P;
        if (len == 0) return v.norm();
        // Distance to the segment (not the infinite line): beyond an end, to that end.
        const double t = v.dot(chord) / (len * len);
        if (t <= 0) return v.norm();
        if (t >= 1) return (c - Q).norm();
        return (v - t * chord).norm();
    };
    constexpr int kN = 16;
    double best = 0;
    int bi = 0;
    for (int i = 1; i < kN; ++i) {
        const double d = dist(ua + (ub - ua) * i / kN);
        if (d > stop) return d;
        if (d > best) { best = d; bi = i; }
    }
    if (bi == 0) return best;
    // Golden-section refinement around the best sample.
    double a = ua + (ub - ua) * (bi - 1) / kN, b = ua + (ub - ua) * (bi + 1) / kN;
    const double g = (std::sqrt(5.0) - 1) / 2;
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = dist(x1), f2 = dist(x2);
    for (int it = 0; it < 60 && b - a > 1e-15 * std::max(1.0, std::abs(b)); ++it) {
        if (std::max(f1, f2) > stop) return std::max(f1, f2);  // (the answer to "> stop?" is known)
        if (f1 > f2) {
            b = x2; x2 = x1; f2 = f1; x1 = b - g * (b - a); f1 = dist(x1);
        } else {
            a = x1; x1 = x2; f1 = f2; x2 = a + g * (b - a); f2 = dist(x2);
        }
    }
    return std::max({best, f1, f2});
}

double Nurbs::chord_estimate(double tol_mm, double stop) const {
    // 8-point Gauss-Legendre nodes and weights on [-1, 1] (Abramowitz & Stegun 25.4.30).
    static constexpr double kX[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                     0.9602898564975363};
    static constexpr double kW[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                     0.1012285362903763};
    // sqrt(kappa) |C'| = sqrt(|C' x C''| / |C'|): the integrand over the parameter.
    auto f = [&](double u) {
        const NurbsPoint e = eval(u);
        const double s = e.d1.norm();
        return s > 0 ? std::sqrt(e.d1.cross(e.d2).norm() / s) : 0.0;
    };
    const std::vector<double> br = breakpoints();
    const double k = 1 / std::sqrt(8 * tol_mm);
    double total = 0;
    for (std::size_t i = 0; i + 1 < br.size() && !(total > stop); ++i) {
        const double m = (br[i] + br[i + 1]) / 2;
        for (const auto& [a, b] : {std::pair{br[i], m}, std::pair{m, br[i + 1]}}) {
            const double c = (a + b) / 2, h = (b - a) / 2;
            double sum = 0;
            for (int j = 0; j < 4; ++j) sum += kW[j] * (f(c - h * kX[j]) + f(c + h * kX[j]));
            total += std::max(1.0, k * h * sum);
        }
    }
    return total;
}

std::vector<double> Nurbs::chord_parameters(double tol_mm, std::size_t max_chords) const {
    std::vector<double> out;
    const double limit = kEstimateMargin * static_cast<double>(max_chords);
    if (chord_estimate(tol_mm, limit) > limit) return out;  // (NaN: not told here; the cap below holds)
    const std::vector<double> br = breakpoints();
    out.push_back(br.front());
    bool over = false;
    auto split = [&](auto&& self, double a, double b, int depth) -> void {
        if (over) return;
        if (out.size() > max_chords) {
            over = true;
            return;
        }
        if (chord_error_until(a, b, tol_mm) > tol_mm) {
            // A piece 2^-40 of a half span that still stands off by more than the
            // tolerance: the curve's numbers are too large for it in double
            // precision. Refused, as a curve of too many chords is (not accepted
            // out of tolerance, nor halved a million times before the cap).
            if (depth >= kMaxDepth) {
                over = true;
                return;
            }
            const double m = (a + b) / 2;
            self(self, a, m, depth + 1);
            self(self, m, b, depth + 1);
            return;
        }
        out.push_back(b);
    };
    for (std::size_t i = 0; i + 1 < br.size(); ++i) {
        const double m = (br[i] + br[i + 1]) / 2;
        split(split, br[i], m, 0);
        split(split, m, br[i + 1], 0);
    }
    if (over) out.clear();
    return out;
}

CurveDistance::CurveDistance(const Nurbs& c, double tol_mm) {
    for (double u : c.chord_parameters(tol_mm)) pts_.push_back(c.point(u));
    if (pts_.empty()) pts_.push_back(c.point(c.breakpoints().front()));  // (a curve the planner refused)
}

double CurveDistance::operator()(const Eigen::Vector3d& p) {
    // Chords from a little behind the last nearest one to well ahead of it.
    constexpr std::size_t kBack = 16, kAhead = 1024;
    const std::size_t lo = hint_ > kBack ? hint_ - kBack : 0;
    const std::size_t hi = std::min(pts_.size() - 1, hint_ + kAhead);
    double best = (p - pts_[lo]).norm();
    std::size_t best_i = lo;
    for (std::size_t i = lo; i < hi; ++i) {
        const Eigen::Vector3d d = pts_[i + 1] - pts_[i];
        const double l2 = d.squaredNorm();
        const double t = l2 > 0 ? std::clamp((p - pts_[i]).dot(d) / l2, 0.0, 1.0) : 0.0;
        const double dist = (p - (pts_[i] + t * d)).norm();
        if (dist < best) {
            best = dist;
            best_i = i;
        }
    }
    hint_ = best_i;
    return best;
}

}  // namespace cpstep::plan

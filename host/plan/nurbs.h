// SPDX-License-Identifier: MIT
// Rational B-spline (NURBS) curves, seed 002 eq. 1:
//
//   C(u) = sum_i N_{i,p}(u) w_i P_i / sum_i N_{i,p}(u) w_i
//
// with C, C' and C'' by de Boor's algorithm on the homogeneous control points
// (w P, w) and the quotient rule (docs/CURVES.md). Points are 3-D (machine mm);
// a G5.x curve lies in the XY plane at the Z where it starts.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cpstep::plan {

// Orders (degree + 1) a curve may have: 2 (a polyline) .. kMaxNurbsOrder.
inline constexpr int kMaxNurbsOrder = 16;

struct NurbsPoint {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();   // C(u)
    Eigen::Vector3d d1 = Eigen::Vector3d::Zero();  // C'(u)
    Eigen::Vector3d d2 = Eigen::Vector3d::Zero();  // C''(u)
};

class Nurbs {
public:
    // Throws std::invalid_argument with validate()'s message when invalid.
    Nurbs(int order, std::vector<Eigen::Vector3d> points, std::vector<double> weights,
          std::vector<double> knots);

    // Why these inputs make no curve (nullopt: they do): order 2..16 and at
    // most the number of points, every weight finite and > 0, exactly
    // points + order knots, finite and non-decreasing, clamped (the first
    // `order` knots equal, the last `order` equal, so that the curve starts at
    // the first point and ends at the last), no interior knot repeated more
    // than order - 1 times (the curve would break there), a non-empty domain.
    static std::optional<std::string> validate(int order, std::size_t points,
                                               const std::vector<double>& weights,
                                               const std::vector<double>& knots);

    // LinuxCNC's G5.2 knot vector for n points of order k (its
    // knot_vector_creator): k zeros, then 1, 2, ..., n - k, then k times
    // n - k + 1. Uniform and clamped; the domain is [0, n - k + 1].
    static std::vector<double> uniform_clamped_knots(std::size_t points, int order);

    [[nodiscard]] int order() const { return order_; }
    [[nodiscard]] int degree() const { return order_ - 1; }
    [[nodiscard]] const std::vector<Eigen::Vector3d>& points() const { return points_; }
    [[nodiscard]] const std::vector<double>& weights() const { return weights_; }
    [[nodiscard]] const std::vector<double>& knots() const { return knots_; }
    [[nodiscard]] double u_min() const { return knots_[static_cast<std::size_t>(degree())]; }
    [[nodiscard]] double u_max() const { return knots_[points_.size()]; }
    // The distinct knots in [u_min, u_max] (span boundaries), ascending.
    [[nodiscard]] std::vector<double> breakpoints() const;

    // C(u), C'(u), C''(u). Outside [u_min, u_max] the end spans' rational
    // pieces are continued (smoothly), which integrators that overshoot use.
    [[nodiscard]] NurbsPoint eval(double u) const;
    // C(u) alone: eval(u).c exactly (the same arithmetic), without the
    // derivatives (about half the work: what chord sampling calls most).
    [[nodiscard]] Eigen::Vector3d point(double u) const;

    // Radius of curvature |C'|^3 / |C' x C''| (infinity where straight).
    [[nodiscard]] double radius(double u) const;

    // Arc length over [ua, ub] (ua <= ub inside the domain): adaptive
    // 5-point Gauss-Legendre quadrature of |C'|, split at the knots, to a
    // relative tolerance of about `rel_tol`.
    [[nodiscard]] double length(double ua, double ub, double rel_tol = 1e-13) const;
    [[nodiscard]] double length() const { return length(u_min(), u_max()); }

    // Largest distance of the curve over [ua, ub] from the chord C(ua)-C(ub).
    [[nodiscard]] double chord_error(double ua, double ub) const;

    // Parameters u_min = u_0 < ... < u_n = u_max of a polyline whose chords
    // stand off the curve by at most tol_mm (every knot span split into at
    // least two, then halved until chord_error() fits). Empty when that takes
    // more than max_chords chords (a curve far too large for the tolerance:
    // callers refuse it rather than sample for ever), or when a piece halved
    // kMaxDepth times still does not fit (numbers too large for the tolerance
    // in double precision, e.g. a line at x = 1e20 mm). A curve whose
    // chord_estimate() is over kEstimateMargin x max_chords is refused that
    // way before any chord is made.
    static constexpr std::size_t kMaxChords = 1'000'000;
    static constexpr double kEstimateMargin = 2;
    static constexpr int kMaxDepth = 40;
    [[nodiscard]] std::vector<double> chord_parameters(double tol_mm, std::size_t max_chords = kMaxChords) const;

    // The fewest chords within tol_mm any polyline of the curve can have, in
    // the limit of short chords: the integral of sqrt(kappa / (8 tol)) over
    // the arc length (a chord of length h over curvature kappa stands off by
    // kappa h^2 / 8), by Gauss-Legendre quadrature on each half knot span,
    // at least one per half span. Cheap (16 evaluations per span): how a curve
    // far too large for its tolerance is told before it is sampled. Stops
    // adding once past `stop` (returns a value > stop); NaN when the curve's
    // numbers overflow.
    [[nodiscard]] double chord_estimate(double tol_mm,
                                        double stop = std::numeric_limits<double>::infinity()) const;

private:
    [[nodiscard]] std::size_t span(double u) const;
    // chord_error(), returning as soon as one sample stands off by more than
    // `stop` (that sample's distance): the same answer to "> stop?" for less.
    [[nodiscard]] double chord_error_until(double ua, double ub, double stop) const;

    int order_;
    std::vector<Eigen::Vector3d> points_;
    std::vector<double> weights_;
    std::vector<double> knots_;
    std::vector<Eigen::Vector4d> hom_;  // (w P, w)
};

// Distances of points from a curve, for points that come in order along it
// (a stepped path, the samples of a run): the curve as a polyline within
// tol_mm, each point measured against the chords near the previous point's.
class CurveDistance {
public:
    explicit CurveDistance(const Nurbs& curve, double tol_mm = 1e-6);
    // The distance of p from the curve (exact within tol_mm).
    double operator()(const Eigen::Vector3d& p);

private:
    std::vector<Eigen::Vector3d> pts_;
    std::size_t hint_ = 0;
};

}  // namespace cpstep::plan

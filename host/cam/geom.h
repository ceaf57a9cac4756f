// SPDX-License-Identifier: MIT
// Plane geometry of the plasma CAM (docs/PLASMA.md): points, affine maps and the
// two kinds of segment a cut is made of — straight lines and conic arcs. A conic
// arc is P(t) = c + u·cos t + v·sin t for t from t0 to t1: a circular arc when u
// and v are perpendicular and equally long, an elliptical arc otherwise. That form
// is closed under every affine map (a circle scaled unevenly is an ellipse), so
// transforms stay exact; ellipses become circular arcs only when a cut is made.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace cpstep::cam {

inline constexpr double kPi = 3.14159265358979323846;

struct Vec2 {
  double x = 0, y = 0;
  Vec2 operator+(Vec2 o) const { return {x + o.x, y + o.y}; }
  Vec2 operator-(Vec2 o) const { return {x - o.x, y - o.y}; }
  Vec2 operator*(double s) const { return {x * s, y * s}; }
  Vec2 operator/(double s) const { return {x / s, y / s}; }
  Vec2 operator-() const { return {-x, -y}; }
  friend bool operator==(const Vec2&, const Vec2&) = default;
};
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::hypot(a.x, a.y); }
inline double dist(Vec2 a, Vec2 b) { return norm(a - b); }
inline Vec2 perp_left(Vec2 a) { return {-a.y, a.x}; }
inline Vec2 unit(Vec2 a) { const double n = norm(a); return n > 0 ? a / n : Vec2{}; }

// x' = m00·x + m01·y + tx, y' = m10·x + m11·y + ty. Composition: (a * b)(p) = a(b(p)).
struct Affine {
  double m00 = 1, m01 = 0, m10 = 0, m11 = 1, tx = 0, ty = 0;
  Vec2 apply(Vec2 p) const { return {m00 * p.x + m01 * p.y + tx, m10 * p.x + m11 * p.y + ty}; }
  Vec2 linear(Vec2 p) const { return {m00 * p.x + m01 * p.y, m10 * p.x + m11 * p.y}; }
  double det() const { return m00 * m11 - m01 * m10; }
  Affine operator*(const Affine& b) const;
  static Affine translate(double dx, double dy) { return {1, 0, 0, 1, dx, dy}; }
  static Affine rotate(double radians);
  static Affine rotate_deg(double degrees) { return rotate(degrees * kPi / 180.0); }
  static Affine scale(double sx, double sy) { return {sx, 0, 0, sy, 0, 0}; }
};

struct Box {
  Vec2 lo{1e300, 1e300}, hi{-1e300, -1e300};
  bool empty() const { return lo.x > hi.x; }
  void add(Vec2 p);
  void add_box(const Box& b);
  double width() const { return hi.x - lo.x; }
  double height() const { return hi.y - lo.y; }
};

enum class SegKind { line, arc };

struct Seg {
  SegKind kind = SegKind::line;
  Vec2 a, b;                 // start and end points (arcs: cached from the parameters)
  Vec2 c, u, v;              // arcs: P(t) = c + u cos t + v sin t
  double t0 = 0, t1 = 0;     // arcs: from t0 to t1 (t1 < t0: traversed backwards)
  int src = -1;              // the entity it came from (Drawing::sources), -1: made here

  static Seg line(Vec2 a, Vec2 b, int src = -1);
  // A circular arc about c of radius r from angle t0 to t1 (radians; t1 > t0: counter-clockwise).
  static Seg circle_arc(Vec2 c, double r, double t0, double t1, int src = -1);
  static Seg conic_arc(Vec2 c, Vec2 u, Vec2 v, double t0, double t1, int src = -1);

  Vec2 at(double t) const;           // arcs: P(t); lines: a + t·(b − a)
  Vec2 deriv(double t) const;        // dP/dt along the direction of travel
  Vec2 start_tangent() const;        // unit
  Vec2 end_tangent() const;          // unit
  bool closed() const { return kind == SegKind::arc && std::abs(t1 - t0) >= 2 * kPi - 1e-12; }
  bool is_circular(double rel_tol = 1e-9) const;
  double radius() const { return norm(u); }           // circular arcs
  bool ccw() const { return cross(u, v) * (t1 - t0) > 0; }  // circular arcs: counter-clockwise in the plane
  double sweep() const { return std::abs(t1 - t0); }  // arcs: the parameter swept (radians)
  double length() const;
  Box box() const;
  Seg reversed() const;
  Seg transformed(const Affine& m) const;
  // Two pieces at parameter t (lines: 0..1; arcs: between t0 and t1).
  std::pair<Seg, Seg> split(double t) const;
  // The parameter of the point nearest p (lines and circular arcs exactly; ellipses by search).
  double nearest_param(Vec2 p) const;
  double distance(Vec2 p) const { return dist(at(nearest_param(p)), p); }
  // Points from start to end (start included, end included) within `tol` of the curve.
  void flatten(double tol, std::vector<Vec2>& out, bool include_start = true) const;
  void refresh();                    // recompute a, b from the arc parameters
};

// Circular arcs (lines unchanged) within `tol` of a conic arc: consecutive arcs
// through three points of the curve, halved until every sampled point is within tol.
std::vector<Seg> to_circular(const Seg& s, double tol);

// Signed area of a closed polyline (counter-clockwise > 0).
double signed_area(const std::vector<Vec2>& pts);
bool point_in_polygon(Vec2 p, const std::vector<Vec2>& poly);

std::string fmt_num(double v);  // shortest of %.6g-style for messages

}  // namespace cpstep::cam

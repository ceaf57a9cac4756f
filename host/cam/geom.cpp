// SPDX-License-Identifier: MIT
#include "cam/geom.h"

#include <algorithm>
#include <cstdio>

namespace cpstep::cam {

Affine Affine::operator*(const Affine& b) const {
  Affine r;
  r.m00 = m00 * b.m00 + m01 * b.m10;
  r.m01 = m00 * b.m01 + m01 * b.m11;
  r.m10 = m10 * b.m00 + m11 * b.m10;
  r.m11 = m10 * b.m01 + m11 * b.m11;
  r.tx = m00 * b.tx + m01 * b.ty + tx;
  r.ty = m10 * b.tx + m11 * b.ty + ty;
  return r;
}

Affine Affine::rotate(double rad) {
  const double c = std::cos(rad), s = std::sin(rad);
  return {c, -s, s, c, 0, 0};
}

void Box::add(Vec2 p) {
  lo.x = std::min(lo.x, p.x);
  lo.y = std::min(lo.y, p.y);
  hi.x = std::max(hi.x, p.x);
  hi.y = std::max(hi.y, p.y);
}
void Box::add_box(const Box& b) {
  if (b.empty()) return;
  add(b.lo);
  add(b.hi);
}

Seg Seg::line(Vec2 a, Vec2 b, int src) {
  Seg s;
  s.kind = SegKind::line;
  s.a = a;
  s.b = b;
  s.src = src;
  return s;
}

Seg Seg::circle_arc(Vec2 c, double r, double t0, double t1, int src) {
  return conic_arc(c, {r, 0}, {0, r}, t0, t1, src);
}

Seg Seg::conic_arc(Vec2 c, Vec2 u, Vec2 v, double t0, double t1, int src) {
  Seg s;
  s.kind = SegKind::arc;
  s.c = c;
  s.u = u;
  s.v = v;
  s.t0 = t0;
  s.t1 = t1;
  s.src = src;
  s.refresh();
  return s;
}

void Seg::refresh() {
  if (kind != SegKind::arc) return;
  a = at(t0);
  b = at(t1);
}

Vec2 Seg::at(double t) const {
  if (kind == SegKind::line) return a + (b - a) * t;
  return c + u * std::cos(t) + v * std::sin(t);
}

Vec2 Seg::deriv(double t) const {
  if (kind == SegKind::line) return b - a;
  const Vec2 d = u * -std::sin(t) + v * std::cos(t);
  return t1 >= t0 ? d : -d;
}

Vec2 Seg::start_tangent() const { return unit(deriv(kind == SegKind::line ? 0.0 : t0)); }
Vec2 Seg::end_tangent() const { return unit(deriv(kind == SegKind::line ? 1.0 : t1)); }

bool Seg::is_circular(double rel_tol) const {
  if (kind != SegKind::arc) return false;
  const double nu = norm(u), nv = norm(v);
  const double r = std::max(nu, nv);
  return std::abs(nu - nv) <= rel_tol * r && std::abs(dot(u, v)) <= rel_tol * r * r;
}

double Seg::length() const {
  if (kind == SegKind::line) return dist(a, b);
  if (is_circular()) return radius() * sweep();
  const int n = 512;  // Simpson on |P'(t)|
  const double h = (t1 - t0) / n;
  double s = 0;
  for (int i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    s += w * norm(deriv(t0 + h * i));
  }
  return std::abs(s * h / 3);
}

namespace {
// t moved by whole turns into [lo, lo + 2π).
double wrap_from(double t, double lo) {
  double d = std::fmod(t - lo, 2 * kPi);
  if (d < 0) d += 2 * kPi;
  return lo + d;
}
}  // namespace

Box Seg::box() const {
  Box bx;
  bx.add(a);
  bx.add(b);
  if (kind == SegKind::line) return bx;
  const double lo = std::min(t0, t1), hi = std::max(t0, t1);
  const double cands[4] = {std::atan2(v.x, u.x), std::atan2(v.x, u.x) + kPi, std::atan2(v.y, u.y),
                           std::atan2(v.y, u.y) + kPi};
  for (double t : cands) {
    const double w = wrap_from(t, lo);
    if (w <= hi) bx.add(at(w));
  }
  return bx;
}

Seg Seg::reversed() const {
  Seg r = *this;
  std::swap(r.a, r.b);
  std::swap(r.t0, r.t1);
  return r;
}

Seg Seg::transformed(const Affine& m) const {
  Seg r = *this;
  if (kind == SegKind::line) {
    r.a = m.apply(a);
    r.b = m.apply(b);
    return r;
  }
  r.c = m.apply(c);
  r.u = m.linear(u);
  r.v = m.linear(v);
  r.refresh();
  return r;
}

std::pair<Seg, Seg> Seg::split(double t) const {
  Seg p = *this, q = *this;
  if (kind == SegKind::line) {
    const Vec2 m = at(t);
    p.b = m;
    q.a = m;
  } else {
    p.t1 = t;
    q.t0 = t;
    p.refresh();
    q.refresh();
  }
  return {p, q};
}

double Seg::nearest_param(Vec2 p) const {
  if (kind == SegKind::line) {
    const Vec2 d = b - a;
    const double l2 = dot(d, d);
    if (l2 == 0) return 0;
    return std::clamp(dot(p - a, d) / l2, 0.0, 1.0);
  }
  const double lo = std::min(t0, t1), hi = std::max(t0, t1);
  if (is_circular()) {
    const Vec2 q = p - c;
    const double t = std::atan2(dot(q, v), dot(q, u));
    const double w = wrap_from(t, lo);
    if (w <= hi) return w;
    return dist(at(lo), p) <= dist(at(hi), p) ? lo : hi;
  }
  // Ellipses: a coarse scan, then golden-section refinement around the best sample.
  const int n = 256;
  double best = lo, bd = 1e300;
  for (int i = 0; i <= n; ++i) {
    const double t = lo + (hi - lo) * i / n;
    const double d = dist(at(t), p);
    if (d < bd) { bd = d; best = t; }
  }
  double x0 = std::max(lo, best - (hi - lo) / n), x1 = std::min(hi, best + (hi - lo) / n);
  for (int it = 0; it < 60; ++it) {
    const double m1 = x0 + (x1 - x0) * 0.381966, m2 = x0 + (x1 - x0) * 0.618034;
    if (dist(at(m1), p) < dist(at(m2), p)) x1 = m2; else x0 = m1;
  }
  return 0.5 * (x0 + x1);
}

void Seg::flatten(double tol, std::vector<Vec2>& out, bool include_start) const {
  if (include_start) out.push_back(a);
  if (kind == SegKind::line) {
    out.push_back(b);
    return;
  }
  const double r = std::max(norm(u), norm(v));
  const double step = r > tol ? 2 * std::acos(std::max(-1.0, 1 - tol / r)) : kPi / 2;
  int n = std::max(2, int(std::ceil(sweep() / std::max(step, 1e-6))));
  if (!is_circular()) {
    // halve until every chord's midpoint is within tol of the curve
    for (int tries = 0; tries < 16; ++tries) {
      bool ok = true;
      for (int i = 0; i < n && ok; ++i) {
        const double ta = t0 + (t1 - t0) * i / n, tb = t0 + (t1 - t0) * (i + 1) / n;
        const Vec2 pa = at(ta), pb = at(tb), pm = at(0.5 * (ta + tb));
        const Vec2 d = pb - pa;
        const double l = norm(d);
        const double e = l > 0 ? std::abs(cross(d, pm - pa)) / l : dist(pm, pa);
        if (e > tol) ok = false;
      }
      if (ok) break;
      n *= 2;
    }
  }
  for (int i = 1; i < n; ++i) out.push_back(at(t0 + (t1 - t0) * i / n));
  out.push_back(b);
}

namespace {
// The circle through three points; nullopt when they are (nearly) collinear.
std::optional<std::pair<Vec2, double>> circle3(Vec2 p, Vec2 q, Vec2 r) {
  const double d = 2 * (p.x * (q.y - r.y) + q.x * (r.y - p.y) + r.x * (p.y - q.y));
  const double scale = std::max({dist(p, q), dist(q, r), dist(p, r)});
  if (std::abs(d) < 1e-12 * scale * scale) return std::nullopt;
  const double p2 = dot(p, p), q2 = dot(q, q), r2 = dot(r, r);
  const Vec2 c{(p2 * (q.y - r.y) + q2 * (r.y - p.y) + r2 * (p.y - q.y)) / d,
               (p2 * (r.x - q.x) + q2 * (p.x - r.x) + r2 * (q.x - p.x)) / d};
  return std::pair{c, dist(c, p)};
}

Seg arc3(Vec2 a, Vec2 m, Vec2 b, int src) {
  const auto cr = circle3(a, m, b);
  if (!cr) return Seg::line(a, b, src);
  const auto [c, r] = *cr;
  const bool ccw = cross(m - a, b - m) > 0;
  const double ta = std::atan2(a.y - c.y, a.x - c.x);
  double tb = std::atan2(b.y - c.y, b.x - c.x);
  if (ccw) { while (tb <= ta) tb += 2 * kPi; }
  else { while (tb >= ta) tb -= 2 * kPi; }
  Seg s = Seg::circle_arc(c, r, ta, tb, src);
  s.a = a;  // exact end points: consecutive pieces share them bit for bit
  s.b = b;
  return s;
}
}  // namespace

std::vector<Seg> to_circular(const Seg& s, double tol) {
  if (s.kind == SegKind::line || s.is_circular()) return {s};
  int n = std::max(4, int(std::ceil(s.sweep() / (kPi / 8))));
  for (int tries = 0; tries < 14; ++tries, n *= 2) {
    std::vector<Seg> out;
    bool ok = true;
    for (int i = 0; i < n && ok; ++i) {
      const double ta = s.t0 + (s.t1 - s.t0) * i / n, tb = s.t0 + (s.t1 - s.t0) * (i + 1) / n;
      const Seg piece = arc3(i == 0 ? s.a : s.at(ta), s.at(0.5 * (ta + tb)), i + 1 == n ? s.b : s.at(tb), s.src);
      for (int k = 1; k < 8 && ok; ++k) {
        const Vec2 p = s.at(ta + (tb - ta) * k / 8);
        if (piece.distance(p) > tol) ok = false;
      }
      out.push_back(piece);
    }
    if (ok) {
      for (std::size_t i = 1; i < out.size(); ++i) out[i].a = out[i - 1].b;
      return out;
    }
  }
  std::vector<Seg> lines;  // never reached for sane tolerances
  std::vector<Vec2> pts;
  s.flatten(tol, pts);
  for (std::size_t i = 1; i < pts.size(); ++i) lines.push_back(Seg::line(pts[i - 1], pts[i], s.src));
  return lines;
}

double signed_area(const std::vector<Vec2>& pts) {
  double a = 0;
  for (std::size_t i = 0, n = pts.size(); i < n; ++i) a += cross(pts[i], pts[(i + 1) % n]);
  return 0.5 * a;
}

bool point_in_polygon(Vec2 p, const std::vector<Vec2>& poly) {
  bool in = false;
  for (std::size_t i = 0, n = poly.size(), j = n - 1; i < n; j = i++) {
    const Vec2 a = poly[i], b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace cpstep::cam

// SPDX-License-Identifier: MIT
#include "cam/kerf.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace cpstep::cam {

namespace {

std::optional<Seg> offset_seg(const Seg& s, double d, double tol) {
  if (s.kind == SegKind::line) {
    const Vec2 n = perp_left(unit(s.b - s.a)) * d;
    Seg r = s;
    r.a = s.a + n;
    r.b = s.b + n;
    return r;
  }
  const double r = s.radius();
  const double r2 = s.ccw() ? r - d : r + d;  // the left of a counter-clockwise arc is its centre
  if (r2 <= tol) return std::nullopt;
  Seg o = Seg::conic_arc(s.c, s.u * (r2 / r), s.v * (r2 / r), s.t0, s.t1, s.src);
  return o;
}

// Points where the carriers of two segments meet (a line's is the whole line, an arc's the whole circle).
std::vector<Vec2> carrier_hits(const Seg& p, const Seg& q) {
  std::vector<Vec2> out;
  auto line_line = [&](Vec2 a, Vec2 da, Vec2 b, Vec2 db) {
    const double den = cross(da, db);
    if (std::abs(den) < 1e-14 * norm(da) * norm(db)) return;
    const double t = cross(b - a, db) / den;
    out.push_back(a + da * t);
  };
  auto line_circle = [&](Vec2 a, Vec2 da, Vec2 c, double r) {
    const Vec2 f = a - c;
    const double A = dot(da, da), B = 2 * dot(f, da), C = dot(f, f) - r * r;
    double disc = B * B - 4 * A * C;
    if (disc < 0) {
      if (disc > -1e-9 * B * B) disc = 0; else return;
    }
    const double sq = std::sqrt(disc);
    out.push_back(a + da * ((-B - sq) / (2 * A)));
    out.push_back(a + da * ((-B + sq) / (2 * A)));
  };
  auto circle_circle = [&](Vec2 c0, double r0, Vec2 c1, double r1) {
    const double dd = dist(c0, c1);
    if (dd < 1e-12) return;
    const double a = (r0 * r0 - r1 * r1 + dd * dd) / (2 * dd);
    double h2 = r0 * r0 - a * a;
    if (h2 < 0) {
      if (h2 > -1e-9 * r0 * r0) h2 = 0; else return;
    }
    const Vec2 ex = (c1 - c0) / dd;
    const Vec2 m = c0 + ex * a;
    const double h = std::sqrt(h2);
    out.push_back(m + perp_left(ex) * h);
    out.push_back(m - perp_left(ex) * h);
  };
  const bool pl = p.kind == SegKind::line, ql = q.kind == SegKind::line;
  if (pl && ql) line_line(p.a, p.b - p.a, q.a, q.b - q.a);
  else if (pl) line_circle(p.a, p.b - p.a, q.c, q.radius());
  else if (ql) line_circle(q.a, q.b - q.a, p.c, p.radius());
  else circle_circle(p.c, p.radius(), q.c, q.radius());
  return out;
}

// Position of x along segment s in travel units: lines 0..1, arcs 0..sweep
// (travel angle from the start, centred on the arc so that points just outside it are negative or > sweep).
double travel_param(const Seg& s, Vec2 x) {
  if (s.kind == SegKind::line) {
    const Vec2 d = s.b - s.a;
    return dot(x - s.a, d) / dot(d, d);
  }
  const Vec2 q = x - s.c;
  const double t = std::atan2(dot(q, s.v), dot(q, s.u));
  const double dir = s.t1 >= s.t0 ? 1 : -1;
  const double sweep = s.sweep();
  const double gap = 2 * kPi - sweep;
  double delta = std::fmod((t - s.t0) * dir + gap / 2, 2 * kPi);
  if (delta < 0) delta += 2 * kPi;
  return delta - gap / 2;
}

double end_param(const Seg& s) { return s.kind == SegKind::line ? 1.0 : s.sweep(); }

Seg trimmed(const Seg& s, double p0, double p1) {
  if (s.kind == SegKind::line) {
    Seg r = s;
    r.a = s.at(p0);
    r.b = s.at(p1);
    return r;
  }
  const double dir = s.t1 >= s.t0 ? 1 : -1;
  Seg r = s;
  r.t0 = s.t0 + dir * p0;
  r.t1 = s.t0 + dir * p1;
  r.refresh();
  return r;
}

double param_scale(const Seg& s) {  // travel units per mm
  return s.kind == SegKind::line ? 1.0 / std::max(1e-12, dist(s.a, s.b)) : 1.0 / std::max(1e-12, s.radius());
}

struct Item {
  Seg orig, off;
  double p0 = 0, p1 = 0;
  bool alive = true;
};

bool segs_intersect(Vec2 a, Vec2 b, Vec2 c, Vec2 d, Vec2* at) {
  const Vec2 r = b - a, s = d - c;
  const double den = cross(r, s);
  if (den == 0) return false;
  const double t = cross(c - a, s) / den, u = cross(c - a, r) / den;
  if (t > 0 && t < 1 && u > 0 && u < 1) {
    if (at) *at = a + r * t;
    return true;
  }
  return false;
}

}  // namespace

std::optional<Vec2> first_crossing(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      Vec2 x;
      if (segs_intersect(a[i], a[(i + 1) % a.size()], b[j], b[(j + 1) % b.size()], &x)) return x;
    }
  return std::nullopt;
}

std::optional<Vec2> self_crossing(const std::vector<Vec2>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;
      Vec2 x;
      if (segs_intersect(a[i], a[(i + 1) % n], a[j], a[(j + 1) % n], &x)) return x;
    }
  return std::nullopt;
}

OffsetResult offset_left(const std::vector<Seg>& path, double d, double tol) {
  OffsetResult res;
  auto at_text = [](Vec2 p) {
    std::string s(1, '(');
    s.append(fmt_num(p.x)).append(", ").append(fmt_num(p.y)).append(")");
    return s;
  };
  if (d <= 0) {
    res.segs = path;
    return res;
  }
  std::vector<Item> items;
  for (const Seg& s : path) {
    auto o = offset_seg(s, d, tol);
    if (!o) {
      res.notes.push_back("an arc of radius " + fmt_num(s.radius()) + " mm at " + at_text(s.at(0.5 * (s.t0 + s.t1))) +
                          " is tighter than half the kerf (" + fmt_num(d) + " mm)");
      continue;
    }
    items.push_back({s, *o, 0, end_param(*o), true});
  }
  if (items.empty()) {
    res.notes.push_back("the contour is narrower than the kerf: nothing is left to cut");
    return res;
  }
  std::vector<bool> convex(items.size(), false);
  for (int round = 0; round < 64; ++round) {
    std::vector<std::size_t> live;
    for (std::size_t i = 0; i < items.size(); ++i)
      if (items[i].alive) { items[i].p0 = 0; items[i].p1 = end_param(items[i].off); live.push_back(i); }
    if (live.size() == 1 && items[live[0]].off.closed()) break;
    if (live.size() < 2) break;
    std::fill(convex.begin(), convex.end(), false);
    for (std::size_t k = 0; k < live.size(); ++k) {
      Item& A = items[live[k]];
      Item& B = items[live[(k + 1) % live.size()]];
      if (dist(A.off.b, B.off.a) <= tol) continue;  // tangent: the offsets meet
      const bool adjacent = dist(A.orig.b, B.orig.a) <= tol;
      const Vec2 ta = A.orig.end_tangent(), tb = B.orig.start_tangent();
      const double turn = cross(ta, tb);
      if (adjacent && (turn < -1e-9 || (std::abs(turn) <= 1e-9 && dot(ta, tb) < 0))) {
        convex[live[k]] = true;  // a gap on the waste side: an arc about the corner joins them
        continue;
      }
      const Vec2 v = adjacent ? A.orig.b : (A.off.b + B.off.a) * 0.5;
      const auto hits = carrier_hits(A.off, B.off);
      if (hits.empty()) { convex[live[k]] = true; continue; }  // joined by a straight line below
      Vec2 x = hits.front();
      for (Vec2 h : hits)
        if (dist(h, v) < dist(x, v)) x = h;
      A.p1 = travel_param(A.off, x);
      B.p0 = travel_param(B.off, x);
    }
    bool removed = false;
    for (std::size_t i : live) {
      Item& it = items[i];
      if ((it.p1 - it.p0) / param_scale(it.off) <= tol) {
        it.alive = false;
        removed = true;
        res.notes.push_back("a segment of " + fmt_num(it.orig.length()) + " mm at " + at_text(it.orig.a) +
                            " disappears in the kerf: a feature narrower than the kerf");
      }
    }
    if (!removed) break;
  }
  std::vector<Seg> out;
  std::vector<std::size_t> live;
  for (std::size_t i = 0; i < items.size(); ++i)
    if (items[i].alive) live.push_back(i);
  for (std::size_t k = 0; k < live.size(); ++k) {
    const Item& A = items[live[k]];
    const Item& B = items[live[(k + 1) % live.size()]];
    out.push_back(live.size() == 1 ? A.off : trimmed(A.off, A.p0, A.p1));
    if (!convex[live[k]] || live.size() == 1) continue;
    const Vec2 from = out.back().b, to = B.off.a;
    if (dist(from, to) <= tol) continue;
    if (dist(A.orig.b, B.orig.a) <= tol) {
      const Vec2 v = A.orig.b;
      const double t0 = std::atan2(from.y - v.y, from.x - v.x);
      double t1 = std::atan2(to.y - v.y, to.x - v.x);
      while (t1 >= t0) t1 -= 2 * kPi;  // clockwise: the torch turns right round the corner
      while (t1 < t0 - 2 * kPi) t1 += 2 * kPi;
      Seg j = Seg::circle_arc(v, d, t0, t1, -1);
      j.a = from;
      j.b = to;
      out.push_back(j);
    } else {
      out.push_back(Seg::line(from, to));
    }
  }
  // drop what is shorter than the tolerance and close every joint exactly
  std::vector<Seg> clean;
  for (const Seg& s : out)
    if (s.closed() || dist(s.a, s.b) > tol || (s.kind == SegKind::arc && s.length() > tol)) clean.push_back(s);
  for (std::size_t i = 0; i < clean.size(); ++i) clean[(i + 1) % clean.size()].a = clean[i].b;
  // the contour must keep its orientation and must not cross itself
  std::vector<Vec2> before, after;
  for (std::size_t i = 0; i < path.size(); ++i) path[i].flatten(0.01, before, i == 0);
  for (std::size_t i = 0; i < clean.size(); ++i) clean[i].flatten(0.01, after, i == 0);
  if (after.size() > 1) after.pop_back();
  if (before.size() > 1) before.pop_back();
  const double a0 = signed_area(before), a1 = signed_area(after);
  if (clean.empty() || a0 * a1 <= 0 || std::abs(a1) < 1e-9) {
    res.notes.push_back("the contour is narrower than the kerf: nothing is left to cut");
    res.segs.clear();
    return res;
  }
  if (auto x = self_crossing(after))
    res.notes.push_back("the kerf-compensated contour crosses itself near " + at_text(*x) +
                        ": a feature narrower than the kerf");
  res.segs = std::move(clean);
  return res;
}

}  // namespace cpstep::cam

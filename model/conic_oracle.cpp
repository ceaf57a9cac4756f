// SPDX-License-Identifier: MIT
#include "conic_oracle.h"

#include <cmath>
#include <complex>
#include <limits>

namespace cpstep::oracle {
namespace {

using ld = long double;
using Poly = std::vector<ld>;  // coefficients, lowest power first
constexpr ld kInf = std::numeric_limits<ld>::infinity();

Poly mul(const Poly& p, const Poly& q) {
  Poly r(p.size() + q.size() - 1, 0);
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = 0; j < q.size(); ++j) r[i + j] += p[i] * q[j];
  return r;
}
Poly add(Poly p, const Poly& q) {
  if (q.size() > p.size()) p.resize(q.size(), 0);
  for (size_t i = 0; i < q.size(); ++i) p[i] += q[i];
  return p;
}
Poly scale(Poly p, ld s) {
  for (ld& c : p) c *= s;
  return p;
}

// All complex roots of p (Durand-Kerner), after dropping negligible leading terms.
std::vector<std::complex<ld>> roots(Poly p) {
  ld big = 0;
  for (ld c : p) big = std::max(big, std::fabs(c));
  while (p.size() > 1 && std::fabs(p.back()) <= big * 1e-24L) p.pop_back();
  const size_t n = p.size() - 1;
  std::vector<std::complex<ld>> z(n);
  if (n == 0) return z;
  const ld lead = p.back();
  for (ld& c : p) c /= lead;
  ld bound = 1;
  for (size_t i = 0; i < n; ++i) bound = std::max(bound, 1 + std::fabs(p[i]));
  for (size_t i = 0; i < n; ++i) z[i] = std::polar(bound * 0.9L, ld(2 * M_PI * i / n + 0.4));
  for (int it = 0; it < 500; ++it) {
    ld moved = 0;
    for (size_t i = 0; i < n; ++i) {
      std::complex<ld> v = 0;  // monic: evaluate by Horner
      for (size_t k = p.size(); k-- > 0;) v = v * z[i] + p[k];
      std::complex<ld> den = 1;
      for (size_t j = 0; j < n; ++j)
        if (j != i) den *= z[i] - z[j];
      if (std::abs(den) == 0) den = 1e-30L;
      const std::complex<ld> dz = v / den;
      z[i] -= dz;
      moved = std::max(moved, std::abs(dz));
    }
    if (moved < 1e-30L) break;
  }
  return z;
}

// Newton on the foot-point equations G(q) = 0, (q - p) x grad G(q) = 0.
bool polish(const Conic& k, ld px, ld py, ld& qx, ld& qy) {
  for (int it = 0; it < 60; ++it) {
    const ld gx = k.gx(qx, qy), gy = k.gy(qx, qy);
    const ld f1 = k.value(qx, qy);
    const ld f2 = (qx - px) * gy - (qy - py) * gx;
    const ld j11 = gx, j12 = gy;
    const ld j21 = gy + (qx - px) * k.b - (qy - py) * 2 * k.a;
    const ld j22 = (qx - px) * 2 * k.c - gx - (qy - py) * k.b;
    const ld det = j11 * j22 - j12 * j21;
    if (det == 0 || !std::isfinite(det)) break;
    const ld sx = (f1 * j22 - f2 * j12) / det, sy = (j11 * f2 - j21 * f1) / det;
    qx -= sx;
    qy -= sy;
    if (std::fabs(sx) + std::fabs(sy) < 1e-17L * (1 + std::fabs(qx) + std::fabs(qy))) break;
  }
  const ld g = std::hypot(k.gx(qx, qy), k.gy(qx, qy));
  return std::isfinite(qx) && std::isfinite(qy) && std::fabs(k.value(qx, qy)) <= 1e-12L * (1 + g) * (1 + std::fabs(qx) + std::fabs(qy));
}

}  // namespace

Conic circle(long double cx, long double cy, long double r) {
  return {1, 0, 1, -2 * cx, -2 * cy, cx * cx + cy * cy - r * r};
}

Foot nearest(const Conic& k, long double px, long double py) {
  if (k.b == 0 && k.a == k.c && k.a != 0) {  // a circle
    const ld cx = -k.d / (2 * k.a), cy = -k.e / (2 * k.a);
    const ld r2 = cx * cx + cy * cy - k.f / k.a;
    if (r2 < 0) return {kInf, 0, 0};
    const ld r = std::sqrt(r2), h = std::hypot(px - cx, py - cy);
    if (h == 0) return {r, cx + r, cy};
    return {std::fabs(h - r), cx + (px - cx) * r / h, cy + (py - cy) * r / h};
  }
  if (k.a == 0 && k.b == 0 && k.c == 0) {  // a line
    const ld n = std::hypot(k.d, k.e);
    if (n == 0) return {kInf, 0, 0};
    const ld s = k.value(px, py) / (n * n);
    return {std::fabs(s) * n, px - s * k.d, py - s * k.e};
  }
  // Principal axes: u1 = c x + s y, u2 = -s x + c y diagonalise the quadratic part.
  const ld th = 0.5L * std::atan2(k.b, k.a - k.c);
  const ld cs = std::cos(th), sn = std::sin(th);
  const ld l1 = k.a * cs * cs + k.b * cs * sn + k.c * sn * sn;
  const ld l2 = k.a * sn * sn - k.b * cs * sn + k.c * cs * cs;
  const ld d1 = k.d * cs + k.e * sn, d2 = -k.d * sn + k.e * cs;
  const ld p1 = cs * px + sn * py, p2 = -sn * px + cs * py;
  // Stationary points of |u - p|^2 on G = 0: u_i = (p_i - t d_i) / (1 + 2 t l_i).
  const Poly a1{p1, -d1}, a2{p2, -d2}, b1{1, 2 * l1}, b2{1, 2 * l2};
  const Poly b1b1 = mul(b1, b1), b2b2 = mul(b2, b2);
  Poly P = scale(mul(mul(a1, a1), b2b2), l1);
  P = add(P, scale(mul(mul(a2, a2), b1b1), l2));
  P = add(P, scale(mul(mul(a1, b1), b2b2), d1));
  P = add(P, scale(mul(mul(a2, b2), b1b1), d2));
  P = add(P, scale(mul(b1b1, b2b2), k.f));
  std::vector<std::pair<ld, ld>> cand;  // in the principal frame
  for (const auto& z : roots(P)) {
    const ld t = z.real();
    const ld e1 = 1 + 2 * t * l1, e2 = 1 + 2 * t * l2;
    if (e1 == 0 || e2 == 0) continue;
    cand.push_back({(p1 - t * d1) / e1, (p2 - t * d2) / e2});
  }
  // Where 1 + 2 t l_i = 0 the other coordinate is fixed and u_i solves G = 0.
  for (int i = 0; i < 2; ++i) {
    const ld li = i ? l2 : l1, lj = i ? l1 : l2, di = i ? d2 : d1, dj = i ? d1 : d2;
    const ld pj = i ? p1 : p2;
    if (li == 0) continue;
    const ld t = -1 / (2 * li), ej = 1 + 2 * t * lj;
    if (ej == 0) continue;
    const ld uj = (pj - t * dj) / ej;
    const ld cst = lj * uj * uj + dj * uj + k.f, disc = di * di - 4 * li * cst;
    if (disc < 0) continue;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      const ld ui = (-di + sgn * std::sqrt(disc)) / (2 * li);
      cand.push_back(i ? std::pair<ld, ld>{uj, ui} : std::pair<ld, ld>{ui, uj});
    }
  }
  Foot best{kInf, 0, 0};
  const auto consider = [&](ld qx, ld qy) {
    if (!polish(k, px, py, qx, qy)) return;
    const ld dist = std::hypot(qx - px, qy - py);
    if (dist < best.distance) best = {dist, qx, qy};
  };
  for (const auto& [u1, u2] : cand) consider(cs * u1 - sn * u2, sn * u1 + cs * u2);
  consider(px, py);  // the local projection from p itself
  return best;
}

Choice nearest_step(const Conic& k, Node p, bool cw, long double tie) {
  const Foot f = nearest(k, ld(p.x), ld(p.y));
  const ld gx = k.gx(f.x, f.y), gy = k.gy(f.x, f.y);
  const ld tx = cw ? gy : -gy, ty = cw ? -gx : gx;
  Choice c;
  c.best_distance = kInf;
  std::vector<std::pair<ld, Node>> all;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy) {
      if ((dx == 0 && dy == 0) || dx * tx + dy * ty <= 0) continue;
      const Node n{p.x + dx, p.y + dy};
      all.push_back({nearest(k, ld(n.x), ld(n.y)).distance, n});
    }
  for (const auto& [d, n] : all)
    if (d < c.best_distance) {
      c.best_distance = d;
      c.best = n;
    }
  for (const auto& [d, n] : all)
    if (!(n == c.best) && d - c.best_distance <= tie) c.ties.push_back(n);
  return c;
}

std::vector<Node> nearest_walk(const Conic& k, Node start, Node end, bool cw, size_t max_moves) {
  std::vector<Node> out;
  Node p = start;
  while (out.size() < max_moves) {
    p = nearest_step(k, p, cw).best;
    out.push_back(p);
    if (p == end) break;
  }
  return out;
}

Node one_axis_step(const Conic& k, Node p, bool cw) {
  const Foot f = nearest(k, ld(p.x), ld(p.y));
  const ld gx = k.gx(f.x, f.y), gy = k.gy(f.x, f.y);
  const ld tx = cw ? gy : -gy, ty = cw ? -gx : gx;
  const Node nx{p.x + (tx >= 0 ? 1 : -1), p.y}, ny{p.x, p.y + (ty >= 0 ? 1 : -1)};
  return nearest(k, ld(nx.x), ld(nx.y)).distance <= nearest(k, ld(ny.x), ld(ny.y)).distance ? nx : ny;
}

}  // namespace cpstep::oracle

// SPDX-License-Identifier: MIT
// Random test conics (docs/CONIC.md "Tests"): axis-aligned and rotated ellipses,
// exact parabolas and hyperbola branches, with integer coefficients, a start node
// near a point of the curve and an end node some moves along the walk.
#pragma once

#include <cmath>
#include <random>

#include "conic_bench.h"

namespace cpstep::tb {

enum class Family { ellipse, rotated_ellipse, parabola, hyperbola };
inline const char* family_name(Family f) {
  switch (f) {
    case Family::ellipse: return "ellipse";
    case Family::rotated_ellipse: return "rotated ellipse";
    case Family::parabola: return "parabola";
    case Family::hyperbola: return "hyperbola branch";
  }
  return "?";
}

// Real coefficients scaled so the largest of |A|, |B|, |C| is 30000, then rounded:
// the rounded conic is the test curve, for the engine and the oracle alike.
inline ConicRequest rounded(long double a, long double b, long double c, long double d, long double e,
                            long double f) {
  const long double k = 30000 / std::max({std::fabs(a), std::fabs(b), std::fabs(c)});
  ConicRequest rq;
  rq.a = std::llround(a * k); rq.b = std::llround(b * k); rq.c = std::llround(c * k);
  rq.d = std::llround(d * k); rq.e = std::llround(e * k); rq.f = std::llround(f * k);
  return rq;
}

// max_moves: the end is at most this many moves from the start.
inline ConicRequest random_conic(Family fam, std::mt19937_64& rng, size_t max_moves) {
  std::uniform_real_distribution<long double> U(0, 1);
  const auto uni = [&](long double lo, long double hi) { return lo + (hi - lo) * U(rng); };
  for (;;) {
    ConicRequest rq;
    long double px = 0, py = 0;
    const long double cx = std::round(uni(-80, 80)) / 4, cy = std::round(uni(-80, 80)) / 4;
    if (fam == Family::ellipse || fam == Family::rotated_ellipse || fam == Family::hyperbola) {
      const long double ea = uni(2, fam == Family::hyperbola ? 40 : 80);
      const long double eb = uni(2, fam == Family::hyperbola ? 40 : 80);
      const long double phi = fam == Family::ellipse ? 0 : uni(0, M_PI);
      const long double cs = std::cos(phi), sn = std::sin(phi);
      const long double s2 = fam == Family::hyperbola ? -1 : 1;  // sign of the y'^2 term
      const long double A = cs * cs / (ea * ea) + s2 * sn * sn / (eb * eb);
      const long double B = 2 * cs * sn * (1 / (ea * ea) - s2 / (eb * eb));
      const long double C = sn * sn / (ea * ea) + s2 * cs * cs / (eb * eb);
      rq = rounded(A, B, C, -2 * A * cx - B * cy, -B * cx - 2 * C * cy, A * cx * cx + B * cx * cy + C * cy * cy - 1);
      long double u, v;
      if (fam == Family::hyperbola) {
        const long double t = uni(-2, 2);
        u = (U(rng) < 0.5 ? -1 : 1) * ea * std::cosh(t);
        v = eb * std::sinh(t);
      } else {
        const long double t = uni(0, 2 * M_PI);
        u = ea * std::cos(t);
        v = eb * std::sin(t);
      }
      px = cx + cs * u - sn * v;
      py = cy + sn * u + cs * v;
    } else {
      // (u x + v y - s0)^2 = m (-v x + u y - w0): exactly a parabola (B^2 = 4AC).
      std::uniform_int_distribution<int> small(-4, 4), off(-30, 30), mm(1, 40);
      const int u = small(rng), v = small(rng);
      if (u == 0 && v == 0) continue;
      const int s0 = off(rng), w0 = off(rng), m = mm(rng) * (U(rng) < 0.5 ? -1 : 1);
      rq.a = int64_t(u) * u; rq.b = 2 * int64_t(u) * v; rq.c = int64_t(v) * v;
      rq.d = -2 * int64_t(u) * s0 + int64_t(m) * v;
      rq.e = -2 * int64_t(v) * s0 - int64_t(m) * u;
      rq.f = int64_t(s0) * s0 + int64_t(m) * w0;
      const long double xi = uni(-30, 30), eta = xi * xi / m, n2 = u * u + v * v;
      px = (u * (xi + s0) - v * (eta + w0)) / n2;
      py = (v * (xi + s0) + u * (eta + w0)) / n2;
    }
    rq.cw = U(rng) < 0.5;
    rq.start = nearest_node(rq.conic(), px, py);
    if (!node_on_curve(rq, rq.start)) continue;
    const size_t n = std::uniform_int_distribution<size_t>(10, max_moves)(rng);
    const std::vector<Node> nodes = walk(rq, {INT64_MAX, INT64_MAX}, n);
    // The end: the last node of the first n that passes the eight-point test.
    size_t at = nodes.size();
    while (at > 0 && !node_on_curve(rq, nodes[at - 1])) --at;
    if (at == 0) continue;
    rq.end = nodes[at - 1];
    return rq;
  }
}

}  // namespace cpstep::tb

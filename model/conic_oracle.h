// SPDX-License-Identifier: MIT
// Untimed oracle for the conic engine (docs/CONIC.md "The oracle"). Written from
// geometry, not from the engine's recurrences: distances to the true curve in long
// double, and the nearest-node walk (from a node, of the eight neighbours that
// advance along the curve, take the one closest to it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cpstep::oracle {

// A x^2 + B xy + C y^2 + D x + E y + F = 0.
struct Conic {
  long double a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  long double value(long double x, long double y) const {
    return a * x * x + b * x * y + c * y * y + d * x + e * y + f;
  }
  long double gx(long double x, long double y) const { return 2 * a * x + b * y + d; }
  long double gy(long double x, long double y) const { return b * x + 2 * c * y + e; }
};

// The circle (x - cx)^2 + (y - cy)^2 = r^2 as a conic (A = C = 1).
Conic circle(long double cx, long double cy, long double r);

struct Foot {
  long double distance;  // geometric distance to the curve; +inf when it has no real point
  long double x, y;      // the nearest point of the curve
};

// The nearest point of the curve to (px, py). Circles and lines in closed form;
// other conics by the Lagrange condition (a quartic in the multiplier, roots by
// Durand-Kerner, each polished by Newton on the foot-point equations).
Foot nearest(const Conic& k, long double px, long double py);

struct Node {
  int64_t x = 0, y = 0;
  bool operator==(const Node&) const = default;
};

// One step of the nearest-node walk from p: the neighbours n with (n - p) . T > 0,
// T the direction of travel at p's foot point (clockwise: (Gy, -Gx), counter-
// clockwise: (-Gy, Gx)); `best` gets the one nearest the curve, `ties` every other
// candidate within `tie` of it.
struct Choice {
  Node best;
  long double best_distance = 0;
  std::vector<Node> ties;
};
Choice nearest_step(const Conic& k, Node p, bool cw, long double tie = 1e-9L);

// The nearest-node walk from `start` until it reaches `end` (after at least one
// move) or makes `max_moves` moves; the nodes after start, in order.
std::vector<Node> nearest_walk(const Conic& k, Node start, Node end, bool cw, size_t max_moves);

// One axis at a time (the classic evaluation-function method, for comparison):
// from p, of the two axial neighbours that advance, the one nearer the curve.
Node one_axis_step(const Conic& k, Node p, bool cw);

}  // namespace cpstep::oracle

// SPDX-License-Identifier: MIT
// docs/CONIC.md's figure: for circles of radius r = 1 .. RMAX steps (centre on a
// node, quarter circle from (r, 0) to (0, r), counter-clockwise), the largest
// distance of a node from the circle and the moves per quarter, for the combined-
// step engine (model::CpConic's rule) and for one-axis-at-a-time stepping (the
// better of the two axial neighbours, oracle::one_axis_step).
//
//   conic_figures [--rmax R] [--csv FILE]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "model/conic_oracle.h"
#include "model/cp_conic.h"

using namespace cpstep;

struct Quarter {
  long double max_distance = 0;
  long moves = 0, diagonal = 0;
};

static Quarter combined(long r) {
  const model::CpConic::Coeffs k{1, 0, 1, 0, 0, -model::i128(r) * r};
  const oracle::Conic c = oracle::circle(0, 0, r);
  model::CpConic::Node n{0, 2 * model::i128(r), 0};  // at (r, 0)
  long x = r, y = 0;
  Quarter q;
  while (!(x == 0 && y == r)) {
    int dx = 0, dy = 0;
    model::CpConic::rule(k, n, false, dx, dy);
    n = model::CpConic::advance(k, n, dx, dy);
    x += dx;
    y += dy;
    ++q.moves;
    q.diagonal += dx != 0 && dy != 0;
    q.max_distance = std::max(q.max_distance, oracle::nearest(c, x, y).distance);
  }
  return q;
}

static Quarter one_axis(long r) {
  const oracle::Conic c = oracle::circle(0, 0, r);
  oracle::Node p{r, 0};
  Quarter q;
  while (!(p.x == 0 && p.y == r) && q.moves < 4 * r + 8) {
    p = oracle::one_axis_step(c, p, false);
    ++q.moves;
    q.max_distance = std::max(q.max_distance, oracle::nearest(c, p.x, p.y).distance);
  }
  return q;
}

int main(int argc, char** argv) {
  long rmax = 4096;
  const char* csv = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--rmax") && i + 1 < argc) rmax = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else {
      std::fprintf(stderr, "usage: conic_figures [--rmax R] [--csv FILE]\n");
      return 2;
    }
  }
  FILE* out = csv ? std::fopen(csv, "w") : nullptr;
  if (out) std::fprintf(out, "r,combined_max,combined_moves,combined_diagonal,one_axis_max,one_axis_moves\n");
  long double worst_c = 0, worst_a = 0;
  long at_c = 0, at_a = 0;
  std::printf("| r | combined: max distance | moves per quarter (diagonal) | one axis: max distance | moves per quarter |\n");
  std::printf("|---|---|---|---|---|\n");
  for (long r = 1; r <= rmax; ++r) {
    const Quarter a = combined(r), b = one_axis(r);
    if (a.max_distance > worst_c) { worst_c = a.max_distance; at_c = r; }
    if (b.max_distance > worst_a) { worst_a = b.max_distance; at_a = r; }
    if (out)
      std::fprintf(out, "%ld,%.6Lf,%ld,%ld,%.6Lf,%ld\n", r, a.max_distance, a.moves, a.diagonal, b.max_distance,
                   b.moves);
    if (r <= 4 || r == 8 || r == 16 || r == 64 || r == 256 || r == 1000 || r == 1024 || r == rmax)
      std::printf("| %ld | %.5Lf | %ld (%ld) | %.5Lf | %ld |\n", r, a.max_distance, a.moves, a.diagonal,
                  b.max_distance, b.moves);
  }
  std::printf("\nr = 1 .. %ld: combined steps worst %.5Lf (r = %ld); one axis at a time worst %.5Lf (r = %ld)\n",
              rmax, worst_c, at_c, worst_a, at_a);
  if (out) std::fclose(out);
  return 0;
}

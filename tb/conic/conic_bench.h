// SPDX-License-Identifier: MIT
// Helpers shared by the conic engine's benches (docs/CONIC.md "Tests"): the two
// Verilated configurations, a request run through any stepper (RTL and model in
// lockstep, or the model alone) with the move stream's contract checked, the test
// curves, and the oracle's judgement of a path.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <random>
#include <vector>

#include "common/lockstep.h"
#include "model/conic_oracle.h"
#include "model/cp_conic.h"
#include "sim/conic_configs.h"

namespace cpstep::tb {

using sim::ConicDefault;
using sim::ConicSmall;

using Coeffs = model::CpConic::Coeffs;
using oracle::Node;

struct ConicRequest {
  int64_t a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  Node start, end;
  bool cw = false;
  oracle::Conic conic() const {
    return {(long double)a, (long double)b, (long double)c, (long double)d, (long double)e, (long double)f};
  }
  Coeffs coeffs() const { return {a, b, c, d, e, f}; }
};

struct ConicRun {
  uint32_t err_code = 0;
  std::vector<Node> nodes;  // after each move
  std::vector<std::pair<int, int>> moves;
  uint64_t accept_cycle = 0, first_move_cycle = 0;
};

// ready_pct: the consumer takes a move with this probability (100: always).
template <class Stepper>
ConicRun run_conic(Stepper& dut, const ConicRequest& rq, unsigned ready_pct = 100, uint64_t seed = 1,
                   uint64_t max_cycles = 0) {
  if (max_cycles == 0) max_cycles = 200 + 40 * 64 + 20000;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<unsigned> pct(0, 99);
  StreamContract contract("move stream");
  model::CpConicIn in;
  in.in_a = rq.a; in.in_b = rq.b; in.in_c = rq.c; in.in_d = rq.d; in.in_e = rq.e; in.in_f = rq.f;
  in.in_x0 = int32_t(rq.start.x); in.in_y0 = int32_t(rq.start.y);
  in.in_x1 = int32_t(rq.end.x); in.in_y1 = int32_t(rq.end.y);
  in.in_cw = rq.cw;
  ConicRun run;
  bool accepted = false, done = false, have_first = false;
  for (uint64_t n = 0; n < max_cycles && !done; ++n) {
    in.in_valid = !accepted;
    in.move_ready = ready_pct >= 100 || pct(rng) < ready_pct;
    const uint64_t cycle = dut.cycle();
    const model::CpConicOut o = dut.step(in);
    contract.check(cycle, o.move_valid, in.move_ready,
                   (uint64_t(o.move_dx & 3) << 2) | uint64_t(o.move_dy & 3) | (uint64_t(o.move_last) << 4));
    if (!o.move_valid && (o.move_dx || o.move_dy || o.move_last || o.move_x || o.move_y))
      ADD_FAILURE() << "move outputs not zero while not valid at cycle " << cycle;
    if (in.in_valid && o.in_ready) {
      accepted = true;
      run.accept_cycle = cycle;
    }
    if (o.err) {
      run.err_code = o.err_code;
      if (o.err_code != uint32_t(model::ConicError::end_missed)) done = true;
    }
    if (o.move_valid && !have_first) {
      have_first = true;
      run.first_move_cycle = cycle;
    }
    if (o.move_valid && in.move_ready) {
      run.moves.push_back({o.move_dx, o.move_dy});
      run.nodes.push_back({o.move_x, o.move_y});
      if (o.move_last) {
        // Let a pending END_MISSED pulse show.
        model::CpConicIn idle = in;
        idle.in_valid = false;
        const model::CpConicOut o2 = dut.step(idle);
        if (o2.err) run.err_code = o2.err_code;
        done = true;
      }
    }
  }
  if (!done) ADD_FAILURE() << "request did not finish in " << max_cycles << " cycles";
  return run;
}

// The walk without timing, from the model's rule: the nodes after `start`, until
// it returns to `stop` or makes `max_moves` moves.
inline std::vector<Node> walk(const ConicRequest& rq, Node stop, size_t max_moves) {
  const Coeffs k = rq.coeffs();
  std::vector<Node> out;
  Node p = rq.start;
  model::CpConic::Node n = model::CpConic::at(k, p.x, p.y);
  while (out.size() < max_moves) {
    int dx = 0, dy = 0;
    model::CpConic::rule(k, n, rq.cw, dx, dy);
    n = model::CpConic::advance(k, n, dx, dy);
    p = {p.x + dx, p.y + dy};
    out.push_back(p);
    if (p == stop) break;
  }
  return out;
}

inline bool node_on_curve(const ConicRequest& rq, Node p) {
  const Coeffs k = rq.coeffs();
  return model::CpConic::on_curve(k, model::CpConic::at(k, p.x, p.y));
}

// The circle with centre (p/4, q/4) and radius s/4, times 16:
// 16x^2 + 16y^2 - 8p x - 8q y + p^2 + q^2 - s^2.
inline ConicRequest circle(int p, int q, int s, bool cw) {
  ConicRequest rq;
  rq.a = 16; rq.c = 16; rq.d = -8 * p; rq.e = -8 * q;
  rq.f = int64_t(p) * p + int64_t(q) * q - int64_t(s) * s;
  rq.cw = cw;
  return rq;
}

// Of the four nodes around the curve point (px, py), the one nearest the curve.
inline Node nearest_node(const oracle::Conic& k, long double px, long double py) {
  const int64_t bx = int64_t(std::floor(px)), by = int64_t(std::floor(py));
  Node best{bx, by};
  long double bd = INFINITY;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const long double d = oracle::nearest(k, bx + i, by + j).distance;
      if (d < bd) { bd = d; best = {bx + i, by + j}; }
    }
  return best;
}

// The oracle's judgement of a path (docs/CONIC.md "The oracle"): at every node but
// the last, the engine's next node is the oracle's nearest advancing neighbour
// (`same`), tied with it (`tie`), or farther from the curve by `excess`.
struct Judgement {
  size_t steps = 0, same = 0, tie = 0, other = 0;
  long double max_excess = 0;    // largest distance beyond the oracle's choice
  long double max_distance = 0;  // largest node distance from the curve
};
inline Judgement judge(const ConicRequest& rq, const std::vector<Node>& nodes) {
  const oracle::Conic k = rq.conic();
  Judgement j;
  Node p = rq.start;
  for (const Node& n : nodes) {
    const long double d = oracle::nearest(k, n.x, n.y).distance;
    j.max_distance = std::max(j.max_distance, d);
    const oracle::Choice c = oracle::nearest_step(k, p, rq.cw);
    ++j.steps;
    bool tie = false;
    for (const Node& t : c.ties) tie = tie || t == n;
    if (c.best == n) ++j.same;
    else if (tie) ++j.tie;
    else {
      ++j.other;
      j.max_excess = std::max(j.max_excess, d - c.best_distance);
    }
    p = n;
  }
  return j;
}

inline uint64_t seed_from_env() {
  const char* s = std::getenv("CPSTEP_SEED");
  return s ? std::strtoull(s, nullptr, 0) : 20261122;
}

}  // namespace cpstep::tb

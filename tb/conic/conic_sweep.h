// SPDX-License-Identifier: MIT
// The circle sweep (docs/CONIC.md "Tests"): circles with centres on the quarter-step
// grid and radii on the quarter-step grid, every start/end octant pair, both
// directions, RTL and model in lockstep, every node judged by the oracle.
#pragma once

#include <cmath>
#include <map>

#include "conic_bench.h"

namespace cpstep::tb {

struct SweepStats {
  size_t requests = 0, moves = 0, diagonal = 0, open_loops = 0;
  Judgement j;  // summed
  long double max_excess_r = 0;  // largest excess times the radius
};

// Radii s/4 for s in `radii`; start/end targets at angles (i + phase) * 45 degrees.
template <class P>
SweepStats circle_sweep(const std::vector<int>& radii, const std::vector<double>& phases,
                        bool lockstep = true) {
  SweepStats st;
  for (const int s : radii)
    for (int p = 0; p < 4; ++p)
      for (int q = 0; q < 4; ++q)
        for (int cw = 0; cw < 2; ++cw) {
          std::unique_ptr<Lockstep<P>> ls;
          std::unique_ptr<sim::ModelDut<P>> md;
          if (lockstep) {
            ls = std::make_unique<Lockstep<P>>();
            ls->reset();
          } else {
            md = std::make_unique<sim::ModelDut<P>>();
          }
          ConicRequest rq = circle(p, q, s, cw != 0);
          const oracle::Conic k = rq.conic();
          const long double cx = p / 4.0L, cy = q / 4.0L, r = s / 4.0L;
          const auto target = [&](double a) {
            return std::pair<long double, long double>{cx + r * std::cos((long double)a),
                                                       cy + r * std::sin((long double)a)};
          };
          for (const double phase : phases)
            for (int i = 0; i < 8; ++i) {
              const auto [sx, sy] = target((i + phase) * M_PI / 4);
              rq.start = nearest_node(k, sx, sy);
              SCOPED_TRACE(testing::Message() << "circle centre (" << p << "/4, " << q << "/4) radius "
                                              << s << "/4 cw " << cw << " start (" << rq.start.x << ","
                                              << rq.start.y << ")");
              if (!node_on_curve(rq, rq.start)) {
                ADD_FAILURE() << "start node fails the eight-point test";
                continue;
              }
              const std::vector<Node> loop = walk(rq, rq.start, size_t(16 * s + 64));
              const bool closed = loop.back() == rq.start;
              if (!closed) ++st.open_loops;
              for (int j = 0; j < 8; ++j) {
                const auto [ex, ey] = target((j + phase) * M_PI / 4);
                // The end: the start for a full circle, else the loop's node nearest the target.
                size_t at = loop.size() - 1;
                if (i != j || !closed) {
                  long double bd = INFINITY;
                  for (size_t n = 0; n + 1 < loop.size() || (!closed && n < loop.size()); ++n) {
                    const long double d = std::hypot(loop[n].x - ex, loop[n].y - ey);
                    if (d < bd) { bd = d; at = n; }
                  }
                }
                rq.end = loop[at];
                const std::vector<Node> want(loop.begin(), loop.begin() + long(at) + 1);
                const unsigned ready = (i + j + s) % 5 == 0 ? 60u : 100u;
                const ConicRun run = lockstep ? run_conic(*ls, rq, ready, uint64_t(s * 64 + i * 8 + j))
                                              : run_conic(*md, rq, ready, uint64_t(s * 64 + i * 8 + j));
                ++st.requests;
                EXPECT_EQ(run.err_code, 0u) << "end (" << rq.end.x << "," << rq.end.y << ")";
                EXPECT_EQ(run.nodes, want) << "end (" << rq.end.x << "," << rq.end.y << ")";
                if (::testing::Test::HasFailure()) return st;
                st.moves += run.moves.size();
                for (const auto& [dx, dy] : run.moves) st.diagonal += dx != 0 && dy != 0;
                // Judge the path once per (circle, start): the same nodes again otherwise.
                if (j == (i + 7) % 8 || (!closed && j == i)) {
                  const Judgement jd = judge(rq, run.nodes);
                  st.j.steps += jd.steps;
                  st.j.same += jd.same;
                  st.j.tie += jd.tie;
                  st.j.other += jd.other;
                  st.j.max_excess = std::max(st.j.max_excess, jd.max_excess);
                  st.max_excess_r = std::max(st.max_excess_r, jd.max_excess * r);
                  st.j.max_distance = std::max(st.j.max_distance, jd.max_distance);
                  if (s >= 4) {
                    EXPECT_LE(jd.max_distance, 0.5L + 1e-12L) << "a node farther than 1/2 step";
                    EXPECT_LE(jd.max_excess * r, 0.25L + 1e-9L) << "disagrees with the oracle";
                    for (const Node& n : run.nodes)
                      EXPECT_TRUE(node_on_curve(rq, n)) << "node (" << n.x << "," << n.y << ") fails the eight-point test";
                  }
                }
              }
            }
        }
  return st;
}

inline void print(const char* what, const SweepStats& st) {
  std::printf("%s: %zu requests, %zu moves (%zu diagonal), %zu open loops; judged %zu steps: %zu same, "
              "%zu tie, %zu other (max excess %.6Lf, x r %.6Lf); max distance %.6Lf\n",
              what, st.requests, st.moves, st.diagonal, st.open_loops, st.j.steps, st.j.same, st.j.tie,
              st.j.other, st.j.max_excess, st.max_excess_r, st.j.max_distance);
}

}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The conic engine in lockstep (CI): circles over every octant pair at a few radii,
// the refusals, back-pressure, the setup latency, and a few other conics.
#include <gtest/gtest.h>

#include "conic_random.h"
#include "conic_sweep.h"

namespace cpstep::tb {
namespace {

TEST(ConicCircles, OctantPairsSmallRadii) {
  const auto st = circle_sweep<ConicDefault>({4, 5, 6, 7, 9, 13, 16, 23, 32}, {0.5});
  print("circles r = 1 .. 8", st);
}

TEST(ConicCircles, OctantPairsSmallConfig) {
  const auto st = circle_sweep<ConicSmall>({4, 11, 40, 101}, {0.0});
  print("circles, small configuration", st);
}

TEST(ConicCircles, FirstMoveAfterTwoPwPlusThreeCycles) {
  Lockstep<ConicDefault> ls;
  ls.reset();
  ConicRequest rq = circle(0, 0, 40, false);  // radius 10 about the origin
  rq.start = {10, 0};
  rq.end = {0, 10};
  const ConicRun run = run_conic(ls, rq);
  ASSERT_EQ(run.err_code, 0u);
  EXPECT_EQ(run.first_move_cycle - run.accept_cycle, 2u * 20 + 3);
  EXPECT_EQ(run.nodes.back(), rq.end);
  // A quarter circle of radius 10: every node within 1/2 step, moves combined.
  EXPECT_LT(run.moves.size(), 20u);
}

// Refused: no move, the code one clock later, and the engine takes the next request.
template <class P>
void expect_refused(Lockstep<P>& ls, const ConicRequest& rq, model::ConicError code) {
  const ConicRun run = run_conic(ls, rq);
  EXPECT_EQ(run.err_code, uint32_t(code));
  EXPECT_TRUE(run.moves.empty());
}

TEST(ConicRefusals, EveryCodeAndTheEngineStaysUsable) {
  Lockstep<ConicDefault> ls;
  ls.reset();
  ConicRequest ok = circle(0, 0, 40, true);
  ok.start = {0, 10};
  ok.end = {10, 0};
  using E = model::ConicError;
  ConicRequest r = ok;
  r.a = 1 << 15;  // QW = 16: A <= 32767
  expect_refused(ls, r, E::coef_range);
  r = ok;
  r.b = -(1 << 15) - 1;
  expect_refused(ls, r, E::coef_range);
  r = ok;
  r.f = int64_t(1) << 47;  // FW = 48
  expect_refused(ls, r, E::coef_range);
  r = ok;
  r.d = int64_t(1) << 31;  // LW = 32
  expect_refused(ls, r, E::coef_range);
  r = ok;
  r.start.x = 1 << 19;  // PW = 20
  expect_refused(ls, r, E::point_range);
  r = ok;
  r.end.y = -(1 << 19) - 1;
  expect_refused(ls, r, E::point_range);
  r = circle(0, 0, 0, false);  // a point circle: no gradient at its centre
  r.start = r.end = {0, 0};
  expect_refused(ls, r, E::degenerate);
  r = ConicRequest{};  // all zero
  expect_refused(ls, r, E::degenerate);
  r = ok;
  r.start = {0, 0};  // the centre: no gradient there, so degenerate before off
  expect_refused(ls, r, E::degenerate);
  r = ok;
  r.start = {3, 3};
  expect_refused(ls, r, E::start_off);
  r = ok;
  r.start = {0, 11};  // 1 step outside: refused
  expect_refused(ls, r, E::start_off);
  r = ok;
  r.end = {1, 1};
  expect_refused(ls, r, E::end_off);
  // Accepted at the edges of the ranges.
  r = ok;
  r.f = -(int64_t(1) << 47);  // the lowest F accepted: in range, so refused as off the curve
  expect_refused(ls, r, E::start_off);
  const ConicRun run = run_conic(ls, ok);
  EXPECT_EQ(run.err_code, 0u);
  EXPECT_EQ(run.nodes.back(), ok.end);
}

TEST(ConicRefusals, EndMissedAfterNmaxMoves) {
  Lockstep<ConicSmall> ls;
  ls.reset();
  // Radius 1 about (0, 1/2): the walk from (1, 0) falls into the cycle (1,1), (0,1),
  // (-1,0), (0,0) and never returns to (1, 0) (docs/CONIC.md "Below one step").
  ConicRequest rq = circle(0, 2, 4, false);
  rq.start = rq.end = {1, 0};
  const ConicRun run = run_conic(ls, rq, 100, 1, 20000);
  EXPECT_EQ(run.err_code, uint32_t(model::ConicError::end_missed));
  EXPECT_EQ(run.moves.size(), 5000u);
  // The engine takes the next request.
  ConicRequest ok = circle(0, 0, 40, true);
  ok.start = {0, 10};
  ok.end = {10, 0};
  const ConicRun run2 = run_conic(ls, ok);
  EXPECT_EQ(run2.err_code, 0u);
  EXPECT_EQ(run2.nodes.back(), ok.end);
}

TEST(ConicBackpressure, StreamHoldsWhileNotReady) {
  Lockstep<ConicDefault> ls;
  ls.reset();
  for (unsigned pct : {10u, 35u, 70u}) {
    ConicRequest rq = circle(1, 3, 117, pct % 2 == 0);
    rq.start = nearest_node(rq.conic(), 0.25L + 29.25L, 0.75L);
    rq.end = rq.start;
    const ConicRun run = run_conic(ls, rq, pct, pct, 200000);
    EXPECT_EQ(run.err_code, 0u);
    EXPECT_EQ(run.nodes, walk(rq, rq.start, 100000));
  }
}

TEST(ConicOthers, RandomEllipsesParabolasHyperbolasInLockstep) {
  const uint64_t seed = seed_from_env();
  SCOPED_TRACE("CPSTEP_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  Lockstep<ConicDefault> ls;
  ls.reset();
  for (int family = 0; family < 4; ++family)
    for (int i = 0; i < 6; ++i) {
      const ConicRequest rq = random_conic(Family(family), rng, 300);
      const ConicRun run = run_conic(ls, rq, 80, rng(), 100000);
      ASSERT_EQ(run.err_code, 0u) << family_name(Family(family));
      ASSERT_EQ(run.nodes, walk(rq, rq.end, 100000));
    }
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// Engine sweeps: RTL vs model on every cycle (Lockstep), and the moves against
// the untimed oracle. SPEC §1 and §5.3.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "engine_bench.h"

namespace cpstep::tb {
namespace {

// All u <= umax, all v <= u, k in [0, kmax]; back-pressure varies with the case.
template <class P>
void exhaustive(unsigned umax, unsigned kmax) {
  Lockstep<P> ls;
  ls.reset();
  unsigned n = 0;
  for (unsigned u = 1; u <= umax; ++u)
    for (unsigned v = 0; v <= u; ++v)
      for (unsigned k = 0; k <= kmax; ++k, ++n) {
        const Backpressure bp{n % 3 == 0 ? 100u : 40u + n % 60, n};
        std::vector<uint64_t> pends;
        const auto run = run_lockstep(ls, {u, v, k, 1}, bp, &pends);
        ASSERT_EQ(run.err_code, 0u) << u << "," << v << "," << k;
        ASSERT_EQ(run.moves, oracle::doubled(u, v, k)) << "u=" << u << " v=" << v << " k=" << k;
        // move_pend_o ends every period: the moves u/gcd(u, v), 2u/gcd(u, v), ...
        const uint64_t period = u / gcd(u, v);
        ASSERT_EQ(pends.size(), run.moves.size() / period) << "u=" << u << " v=" << v << " k=" << k;
        for (size_t i = 0; i < pends.size(); ++i)
          ASSERT_EQ(pends[i], (i + 1) * period) << "u=" << u << " v=" << v << " k=" << k;
      }
}

TEST(EngineSweep, AllUpTo64AllVKUpTo3_W1024) { exhaustive<sim::EngineDefault>(64, 3); }
TEST(EngineSweep, AllUpTo64AllVKUpTo3_W64) { exhaustive<sim::EngineW64>(64, 3); }
TEST(EngineSweep, AllUpTo100AllVKUpTo2_W100) { exhaustive<sim::EngineW100>(100, 2); }

uint64_t seed_from_env() {
  const char* s = std::getenv("CPSTEP_SEED");
  return s ? std::strtoull(s, nullptr, 0) : 20261121;
}

TEST(EngineRandom, UpToCapacityWithRandomKAndRep) {
  const uint64_t seed = seed_from_env();
  SCOPED_TRACE("CPSTEP_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  for (int i = 0; i < 60; ++i) {
    const unsigned u = std::uniform_int_distribution<unsigned>(1, 1024)(rng);
    const unsigned v = std::uniform_int_distribution<unsigned>(0, u)(rng);
    unsigned k = std::uniform_int_distribution<unsigned>(0, 8)(rng);
    while (k > 0 && (uint64_t(u) << k) > 40000) --k;  // keeps CI's run short
    const unsigned rep = std::uniform_int_distribution<unsigned>(1, 3)(rng);
    const unsigned pct = std::uniform_int_distribution<unsigned>(30, 100)(rng);
    const auto run = run_lockstep(ls, {u, v, k, rep}, {pct, rng()});
    ASSERT_EQ(run.err_code, 0u);
    ASSERT_EQ(run.moves, repeat(oracle::doubled(u, v, k), rep))
        << "u=" << u << " v=" << v << " k=" << k << " rep=" << rep;
  }
}

TEST(EngineCorners, EdgesOfTheRange) {
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  struct Case { unsigned u, v, k; };
  for (const Case c : {Case{1, 0, 0}, Case{1, 1, 0}, Case{1, 1, 8}, Case{2, 1, 0}, Case{1024, 0, 0},
                       Case{1024, 1024, 0}, Case{1024, 1, 0}, Case{1024, 1023, 0},
                       Case{1024, 512, 0}, Case{1024, 3, 2}, Case{1023, 1, 0}, Case{7, 3, 8},
                       Case{1024, 633, 0} /* near the golden ratio: the most swaps */}) {
    const auto run = run_lockstep(ls, {c.u, c.v, c.k, 1}, {60, c.u + c.v});
    EXPECT_EQ(run.err_code, 0u);
    EXPECT_EQ(run.moves, oracle::doubled(c.u, c.v, c.k)) << c.u << "," << c.v << "," << c.k;
  }
}

TEST(EngineCorners, RefusedRequestsMakeNoMoveAndLeaveTheEngineUsable) {
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  struct Case { sim::EngineRequest req; model::EngineError err; };
  for (const Case c : {Case{{0, 0, 0, 1}, model::EngineError::u_zero},
                       Case{{5, 6, 0, 1}, model::EngineError::v_gt_u},
                       Case{{1025, 1, 0, 1}, model::EngineError::u_gt_umax},
                       Case{{1025, 2000, 0, 1}, model::EngineError::v_gt_u},
                       Case{{10, 3, 9, 1}, model::EngineError::k_gt_kmax},
                       Case{{10, 3, 0, 0}, model::EngineError::rep_zero}}) {
    const auto run = run_lockstep(ls, c.req);
    EXPECT_EQ(run.err_code, uint32_t(c.err)) << c.req.u << "," << c.req.v;
    EXPECT_TRUE(run.moves.empty());
    // The engine takes the next request normally.
    EXPECT_EQ(run_lockstep(ls, {13, 5, 1, 1}).moves, oracle::doubled(13, 5, 1));
  }
}

TEST(EngineCorners, CapacityOfSmallConfigurations) {
  Lockstep<sim::EngineW64> ls64;
  ls64.reset();
  EXPECT_EQ(run_lockstep(ls64, {64, 1, 3, 1}).moves, oracle::doubled(64, 1, 3));
  EXPECT_EQ(run_lockstep(ls64, {65, 1, 0, 1}).err_code, uint32_t(model::EngineError::u_gt_umax));
  EXPECT_EQ(run_lockstep(ls64, {64, 1, 4, 1}).err_code, uint32_t(model::EngineError::k_gt_kmax));
  EXPECT_EQ(run_lockstep(ls64, {64, 9, 3, 15}).moves, repeat(oracle::doubled(64, 9, 3), 15));
  Lockstep<sim::EngineW100> ls100;
  ls100.reset();
  EXPECT_EQ(run_lockstep(ls100, {100, 37, 2, 1}).moves, oracle::doubled(100, 37, 2));
  EXPECT_EQ(run_lockstep(ls100, {101, 37, 0, 1}).err_code, uint32_t(model::EngineError::u_gt_umax));
}

// UMAX > W: u need not be reduced; the loop reduces it, and a pattern longer
// than W is refused during the build, with no move, leaving the engine usable.
TEST(EngineUnreduced, AllUpTo200AgainstCapacity32) {
  Lockstep<sim::EngineW32U> ls;
  ls.reset();
  unsigned n = 0, refused = 0;
  for (unsigned u = 1; u <= 200; ++u)
    for (unsigned v = 0; v <= u; ++v)
      for (unsigned k = 0; k <= 1; ++k, ++n) {
        const auto run = run_lockstep(ls, {u, v, k, 1}, {n % 2 ? 100u : 60u, n});
        if (u / gcd(u, v) > 32) {
          ++refused;
          ASSERT_EQ(run.err_code, uint32_t(model::EngineError::pattern_gt_w)) << u << "," << v;
          ASSERT_TRUE(run.moves.empty());
        } else {
          ASSERT_EQ(run.err_code, 0u) << u << "," << v;
          ASSERT_EQ(run.moves, oracle::doubled(u, v, k)) << u << "," << v << " k=" << k;
        }
      }
  EXPECT_GT(refused, 0u);
  EXPECT_EQ(run_lockstep(ls, {201, 1, 0, 1}).err_code, uint32_t(model::EngineError::u_gt_umax));
}

// CP(u·2^j, v·2^j) == CP(u, v) replayed 2^j times, with the same loop.
TEST(EngineDoubling, ScaledSegmentEqualsReplayWithSameIterations) {
  std::mt19937_64 rng(seed_from_env() + 1);
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  for (int i = 0; i < 40; ++i) {
    const unsigned u = std::uniform_int_distribution<unsigned>(2, 128)(rng);
    const unsigned v = std::uniform_int_distribution<unsigned>(1, u - 1)(rng);
    const unsigned j = std::uniform_int_distribution<unsigned>(1, 3)(rng);
    const auto base = run_lockstep(ls, {u, v, j, 1});
    const auto scaled = run_lockstep(ls, {u << j, v << j, 0, 1});
    EXPECT_EQ(scaled.moves, base.moves) << u << "," << v << " j=" << j;
    ASSERT_EQ(scaled.iterations.size(), base.iterations.size());
    for (size_t n = 0; n < base.iterations.size(); ++n) {
      EXPECT_EQ(scaled.iterations[n].m1, base.iterations[n].m1);
      EXPECT_EQ(scaled.iterations[n].m2, base.iterations[n].m2);
      EXPECT_EQ(scaled.iterations[n].x, base.iterations[n].x << j);
    }
    EXPECT_EQ(scaled.build_cycles(), base.build_cycles());
  }
}

// docs/ENGINE.md: build = accept cycle + (u/g - 2) copy cycles + 1 landing cycle,
// then one cycle to issue the first move; replay one move per clock.
TEST(EngineTiming, BuildLinearInReducedLengthAndOneMovePerClock) {
  std::mt19937_64 rng(seed_from_env() + 2);
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  for (int i = 0; i < 40; ++i) {
    const unsigned u = std::uniform_int_distribution<unsigned>(3, 1024)(rng);
    const unsigned v = std::uniform_int_distribution<unsigned>(1, u - 1)(rng);
    if (2 * v == u) continue;
    const unsigned k = std::uniform_int_distribution<unsigned>(0, 2)(rng);
    const auto run = run_lockstep(ls, {u, v, k, 1});
    const uint64_t reduced = u / gcd(u, v);
    EXPECT_EQ(run.build_cycles(), (reduced - 2) + 3) << u << "," << v;
    EXPECT_EQ(run.last_move_cycle - run.first_move_cycle + 1, uint64_t(u) << k);
  }
  // No loop iteration: the first move is valid two cycles after the handshake.
  for (const sim::EngineRequest req : {sim::EngineRequest{1024, 512, 0, 1}, {1024, 0, 0, 1},
                                       {1024, 1024, 3, 1}, {1, 1, 0, 1}, {2, 1, 1, 2}})
    EXPECT_EQ(run_lockstep(ls, req).build_cycles(), 2u) << req.u << "," << req.v;
}

TEST(EngineReset, ResetAtRandomCyclesThenServesNormally) {
  std::mt19937_64 rng(seed_from_env() + 3);
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  for (int i = 0; i < 30; ++i) {
    const unsigned u = std::uniform_int_distribution<unsigned>(2, 600)(rng);
    const unsigned v = std::uniform_int_distribution<unsigned>(0, u)(rng);
    const unsigned cut = std::uniform_int_distribution<unsigned>(0, 2 * u)(rng);
    model::CpEngineIn in;
    in.in_valid = true;
    in.in_u = u;
    in.in_v = v;
    in.in_rep = 1;
    for (unsigned c = 0; c < cut; ++c) {
      in.move_ready = (c & 3) != 0;
      const auto o = ls.step(in);
      if (o.in_ready) in.in_valid = false;
    }
    ls.reset(1 + i % 2);
    // Reset leaves the outputs idle.
    const auto idle = ls.step({});
    EXPECT_TRUE(idle.in_ready);
    EXPECT_FALSE(idle.move_valid);
    EXPECT_FALSE(idle.err);
    EXPECT_EQ(run_lockstep(ls, {u, v, 1, 1}, {50, rng()}).moves, oracle::doubled(u, v, 1));
  }
}

}  // namespace
}  // namespace cpstep::tb

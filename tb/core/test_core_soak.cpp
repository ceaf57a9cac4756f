// SPDX-License-Identifier: MIT
// cp_core soak (label long): at least 10,000 random segments and 1,000,000 moves,
// RTL vs model in lockstep on every cycle with the pin checker on, a fresh lockstep
// pair per batch. Seed: CPSTEP_SEED. Figures printed at the end.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

#include "core/core_bench.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

TEST(CoreSoak, TenThousandSegmentsAMillionMoves) {
  const uint64_t seed = core_seed(90000);
  const auto t0 = std::chrono::steady_clock::now();
  uint64_t segments = 0, moves = 0, cycles = 0, late = 0, batches = 0;
  JobShape shape;
  shape.max_moves = 1500;
  shape.max_delay = 14;
  shape.max_chunks = 16;
  while (segments < 10000 || moves < 1000000) {
    CoreHarness<sim::CoreDefault> h("core_soak", seed + batches);
    for (unsigned j = 0; j < 4; ++j) {
      const uint32_t timings[] = {1, 3, 6, 20};
      h.configure_random(timings[h.gen.uniform(0, 3)]);
      h.word_gap = h.gen.chance(0.5) ? 0.0 : 0.2;
      h.play(h.gen.job(h.gen.uniform(5, 20), shape));
      h.expect_consistent("soak batch " + std::to_string(batches) + " (seed " +
                          std::to_string(seed + batches) + ") job " + std::to_string(j));
      ASSERT_FALSE(HasFailure());
    }
    segments += h.chk.segments_done();
    moves += h.chk.moves();
    late += h.chk.late_moves();
    cycles += h.cycles;
    ++batches;
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("core soak: seed %llu, %llu batches, %llu segments, %llu moves, %llu cycles, "
              "%llu stretched moves, %.1f s, 0 mismatches\n",
              (unsigned long long)seed, (unsigned long long)batches, (unsigned long long)segments,
              (unsigned long long)moves, (unsigned long long)cycles, (unsigned long long)late, s);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// X discipline (label long, scripts/nightly): each board's core built with random
// initial values in every register and memory (--x-initial unique, X assigned
// randomly: rtl/CMakeLists.txt XINIT), reset, then driven with random host-like
// jobs in lockstep with the model, which starts from its own fixed values. Any
// output that depended on a register's value before reset or on an X would show
// as a mismatch. Seeds: CPSTEP_SEED for the jobs, and the initial values' seed
// advances per DUT from it.
#include <gtest/gtest.h>

#include "Vcp_core_hx8k_xinit.h"
#include "Vcp_core_icebreaker_xinit.h"
#include "core/core_bench.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

// Outputs before the first reset edge are not part of the contract (docs/CORE.md):
// the random-initialized core starts after one (AfterOneResetEdge, core_bench.h).
template <const builds::Build& B, class V>
struct CoreXinit : sim::CoreOf<B, AfterOneResetEdge<V>> {
  static constexpr bool kRandomInit = true;
};

template <class P>
void random_init_jobs(const char* name, uint64_t seed, unsigned batches) {
  sim::random_init_seed_state() = seed;
  uint64_t moves = 0;
  for (unsigned b = 0; b < batches; ++b) {
    CoreHarness<P> h(name, seed + b);
    JobShape shape;
    shape.max_chunks = 12;
    for (unsigned j = 0; j < 3; ++j) {
      const uint32_t timings[] = {2, 8, 40};
      h.configure_random(timings[h.gen.uniform(0, 2)]);
      h.word_gap = h.gen.chance(0.5) ? 0.0 : 0.3;
      h.play(h.gen.job(10, shape));
      h.expect_consistent(std::string(name) + " seed " + std::to_string(seed + b) + " job " + std::to_string(j));
      ASSERT_FALSE(::testing::Test::HasFailure());
    }
    moves += h.chk.moves();
  }
  EXPECT_GT(moves, 0u);
}

TEST(CoreXInit, IcebreakerWithRandomInitialValues) {
  random_init_jobs<CoreXinit<builds::icebreaker, Vcp_core_icebreaker_xinit>>("xinit_icebreaker",
                                                                              core_seed(70000), 40);
}

TEST(CoreXInit, Hx8kWithRandomInitialValues) {
  random_init_jobs<CoreXinit<builds::hx8k, Vcp_core_hx8k_xinit>>("xinit_hx8k", core_seed(71000), 40);
}

}  // namespace
}  // namespace cpstep::tb

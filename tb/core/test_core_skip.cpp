// SPDX-License-Identifier: MIT
// cp_core's event skipping (CpCore::quiet_for and skip, docs/SIM.md "The fast
// engine") against the RTL: the model skips every run of quiet clocks it finds —
// the move timer waiting for the next move, pulse timers counting, queues full —
// and is compared with the RTL on every cycle all the same (sim::Skipping,
// SkippingModelDut). The same executable runs the fault, refusal and add2 benches
// against the skipping model (CPSTEP_TB_CORE_SKIP, core_validated.h).
#include <gtest/gtest.h>

#include <cstdio>

#include "core/core_bench.h"
#include "core/core_random.h"
#include "core/core_small.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

// Jobs whose moves are far apart (delays up to max_delay cycles) and whose
// pulses are long: most clocks are quiet. A model that never skipped would pass
// the lockstep, so the share it skipped is asserted too.
template <class P>
void skipping_jobs(const char* name, uint64_t seed, unsigned max_chunks) {
  JobShape shape;
  shape.max_chunks = max_chunks;
  shape.max_delay = 600;
  shape.max_timing = 120;
  shape.max_moves = 400;
  uint64_t skipped = 0;
  const uint64_t cycles = random_jobs<sim::Skipping<P>>(name, seed, 6, 3, 8, shape, &skipped);
  std::printf("%s: %llu of %llu clocks skipped\n", name, (unsigned long long)skipped,
              (unsigned long long)cycles);
  EXPECT_GT(skipped, cycles / 2) << "the model skipped too little to prove anything";
}

TEST(CoreSkip, StreamedJobsDefaultCore) { skipping_jobs<sim::CoreDefault>("skip_default", core_seed(5000), 16); }
TEST(CoreSkip, StreamedJobsIcebreakerCore) {
  skipping_jobs<sim::CoreIcebreaker>("skip_icebreaker", core_seed(6000), 16);
}
TEST(CoreSkip, StreamedJobsSmallCore) { skipping_jobs<sim::CoreSmall>("skip_small", core_seed(7000), 4); }

// The jobs of test_core_random.cpp as they are (short delays, tight timing): few
// quiet clocks, many edges between them.
TEST(CoreSkip, DenseJobsDefaultCore) {
  JobShape shape;
  random_jobs<sim::Skipping<sim::CoreDefault>>("skip_dense", core_seed(8000), 4, 3, 12, shape);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// cp_core, RTL vs model in lockstep on every cycle, with random host-like jobs
// streamed to a running core and the independent pin checker on every cycle.
#include <gtest/gtest.h>

#include "core/core_bench.h"
#include "core/core_random.h"
#include "core/core_small.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

// The default core: the HX8K's build.
TEST(CoreRandom, StreamedJobsDefaultCore) {
  JobShape shape;
  shape.max_chunks = 16;
  random_jobs<sim::CoreDefault>("core_default", core_seed(1000), 12, 3, 12, shape);
}

// The shipped builds (rtl/builds.json): the HX8K's is the default core above.
TEST(CoreRandom, StreamedJobsIcebreakerCore) {
  JobShape shape;
  shape.max_chunks = 16;
  random_jobs<sim::CoreIcebreaker>("core_icebreaker", core_seed(3000), 12, 3, 12, shape);
}

TEST(CoreRandom, StreamedJobsSmallCore) {
  JobShape shape;
  shape.max_chunks = 4;
  random_jobs<sim::CoreSmall>("core_small", core_seed(2000), 12, 3, 12, shape);
}

}  // namespace
}  // namespace cpstep::tb

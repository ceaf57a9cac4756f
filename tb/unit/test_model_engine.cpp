// SPDX-License-Identifier: MIT
// The golden model alone against the oracle: a wider sweep than the lockstep
// benches can afford, at the default capacity.
#include <gtest/gtest.h>

#include "model/oracle.h"
#include "sim/engine_configs.h"
#include "sim/engine_session.h"

namespace cpstep {
namespace {

TEST(ModelEngine, AllUpTo256AllVAgainstOracle) {
  sim::ModelDut<sim::EngineDefault> dut;
  const unsigned aw = sim::EngineDefault::model_params().aw();
  model::CpEngineIn reset{};
  reset.rst = true;
  dut.step(reset);
  for (uint32_t u = 1; u <= 256; ++u)
    for (uint32_t v = 0; v <= u; ++v)
      ASSERT_EQ(sim::run_request(dut, aw, {u, v, 0, 1}).moves, oracle::closed_form(u, v))
          << u << "," << v;
}

TEST(ModelEngine, FullCapacityWorstCaseBuild) {
  sim::ModelDut<sim::EngineDefault> dut;
  const unsigned aw = sim::EngineDefault::model_params().aw();
  for (uint32_t v : {1u, 2u, 511u, 633u, 1023u}) {
    const auto run = sim::run_request(dut, aw, {1024, v, 2, 1});
    ASSERT_EQ(run.moves, oracle::doubled(1024, v, 2)) << v;
  }
}

TEST(ModelEngine, RejectsBadParameters) {
  EXPECT_THROW(model::CpEngine({1, 8, 16}), std::invalid_argument);
  EXPECT_THROW(model::CpEngine({1024, 25, 16}), std::invalid_argument);
  EXPECT_THROW(model::CpEngine({1024, 8, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace cpstep

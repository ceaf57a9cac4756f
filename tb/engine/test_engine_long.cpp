// SPDX-License-Identifier: MIT
// The long sweep (ctest label `long`, run by scripts/nightly): every u up to the
// default capacity W = 1024, every v, in lockstep and against the oracle.
#include <gtest/gtest.h>

#include "engine_bench.h"

namespace cpstep::tb {
namespace {

// Long label: every u <= 1024 (W), every v, k = 0, in lockstep.
TEST(EngineLong, AllUpToW) {
  for (unsigned u = 1; u <= 1024; ++u) {
    Lockstep<sim::EngineDefault> ls;  // one per u keeps the replay history short
    ls.reset();
    for (unsigned v = 0; v <= u; ++v) {
      const auto run = run_lockstep(ls, {u, v, 0, 1}, {u % 2 ? 100u : 70u, u * 4096ull + v});
      ASSERT_EQ(run.moves, oracle::closed_form(u, v)) << "u=" << u << " v=" << v;
    }
  }
}

}  // namespace
}  // namespace cpstep::tb

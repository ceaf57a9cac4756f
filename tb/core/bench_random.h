// SPDX-License-Identifier: MIT
// The random draws of the unit benches (tb/core/test_ptimer.cpp, test_div.cpp).
#pragma once

#include <cstdint>
#include <random>

namespace cpstep::tb::unit_random {

using Rng = std::mt19937_64;
// A uniform draw in [lo, hi].
inline uint64_t pick(Rng& rng, uint64_t lo, uint64_t hi) { return std::uniform_int_distribution<uint64_t>(lo, hi)(rng); }
// True with probability pct / 100.
inline bool chance(Rng& rng, unsigned pct) { return pick(rng, 0, 99) < pct; }

}  // namespace cpstep::tb::unit_random

// SPDX-License-Identifier: MIT
// cp_pulse under a random core: random configurations (1s, large values, both
// polarities), step_i whenever ready_o (or after a wait), dir_i changed at random
// times, polarities flipped at random while STEP is inactive, random resets, an
// occasional step_i while not ready (which must be ignored). RTL vs model on every
// cycle, and the pin checker (raw pin levels) on every cycle.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <iostream>
#include <random>

#include "pulse_bench.h"

namespace cpstep::tb {
namespace {

template <class P>
class RandomCore {
 public:
  explicit RandomCore(uint64_t seed) : rng_(seed) {}

  uint32_t field(bool at_least_one) {
    const uint32_t max = P::tw >= 32 ? ~0u : (1u << P::tw) - 1;
    const uint32_t lo = at_least_one ? 1 : 0;
    switch (pick(0, 9)) {
      case 0: case 1: case 2: return lo;              // the minimum
      case 3: case 4: case 5: return pick(lo, 4);     // small
      case 6: case 7: return pick(lo, std::min(max, 40u));
      case 8: return pick(lo, std::min(max, 300u));
      default: return pick(0, 49) == 0 ? max : pick(lo, std::min(max, 20u));  // rarely the largest
    }
  }

  void new_config(PulseBench<P>& b) {
    auto& in = b.in;
    in.cfg_step_high = field(true);
    in.cfg_step_low = field(true);
    in.cfg_dir_setup = field(false);
    in.cfg_dir_hold = field(false);
  }

  // One or both polarities flipped (a CONFIG polarity word changes both fields).
  void new_polarity(PulseBench<P>& b) {
    switch (pick(0, 2)) {
      case 0: b.in.cfg_step_pol = !b.in.cfg_step_pol; break;
      case 1: b.in.cfg_dir_pol = !b.in.cfg_dir_pol; break;
      default:
        b.in.cfg_step_pol = pick(0, 1);
        b.in.cfg_dir_pol = pick(0, 1);
    }
    ++polarity_changes_;
  }

  // A run of `cycles` clocks on bench b, with a fresh driving style.
  void run(PulseBench<P>& b, uint64_t cycles) {
    auto& in = b.in;
    in.cfg_step_pol = pick(0, 1);
    in.cfg_dir_pol = pick(0, 1);
    new_config(b);
    b.reset(pick(1, 3));
    const unsigned fire_pct = std::array<unsigned, 4>{100, 100, 70, 20}[pick(0, 3)];
    const unsigned dir_permille = std::array<unsigned, 3>{2, 20, 200}[pick(0, 2)];
    const unsigned pol_permille = std::array<unsigned, 4>{0, 1, 5, 50}[pick(0, 3)];
    for (uint64_t i = 0; i < cycles; ++i) {
      const auto o = b.peek_outputs();
      if (o.ready) {
        in.step = pick(0, 99) < fire_pct;
      } else {
        in.step = pick(0, 999) < 5;  // a core breaking the contract: ignored
        ignored_ += in.step;
      }
      if (pick(0, 999) < dir_permille) in.dir = !in.dir;  // between segments
      // The configuration changes only while STEP is inactive (busy_o low: the core
      // refuses CONFIG while a pulse is high), timing and polarities alike, also
      // right after a trailing edge, while a DIR change or setup time is pending.
      if (!o.busy && !o.ready && pick(0, 999) < 3) new_config(b);
      if (o.ready && !in.step && pick(0, 999) < 3) new_config(b);
      if (!o.busy && !in.step && pick(0, 999) < pol_permille) new_polarity(b);
      if (pick(0, 9999) < 5) {  // reset, sometimes with new polarities
        if (pick(0, 1)) {
          in.cfg_step_pol = pick(0, 1);
          in.cfg_dir_pol = pick(0, 1);
        }
        new_config(b);
        b.reset(pick(1, 3));
        ++resets_;
        continue;
      }
      b.cycle();
    }
  }

  uint64_t resets() const { return resets_; }
  uint64_t polarity_changes() const { return polarity_changes_; }
  uint64_t ignored() const { return ignored_; }

 private:
  uint32_t pick(uint32_t lo, uint32_t hi) { return std::uniform_int_distribution<uint32_t>(lo, hi)(rng_); }

  std::mt19937_64 rng_;
  uint64_t resets_ = 0, ignored_ = 0, polarity_changes_ = 0;
};

// `runs` runs of `cycles` clocks, each on a fresh bench (so a mismatch's waveform
// replays one run only) and starting with a reset.
template <class P>
void random_lockstep(uint64_t seed, int runs, uint64_t cycles) {
  SCOPED_TRACE("CPSTEP_SEED=" + std::to_string(seed));
  RandomCore<P> core(seed);
  uint64_t n = 0, pulses = 0, dir_edges = 0, step_pol_edges = 0;
  for (int r = 0; r < runs && !::testing::Test::HasFailure(); ++r) {
    SCOPED_TRACE("run " + std::to_string(r));
    PulseBench<P> b;
    core.run(b, cycles);
    b.expect_pins_clean();
    n += b.now();
    pulses += b.checker().pulses();
    dir_edges += b.dir_edges.size();
    step_pol_edges += b.step_pol_edges.size();
  }
  // The runs did what they are for: many pulses, reversals, resets, bad requests.
  std::cout << "[ coverage ] " << n << " cycles, " << pulses << " pulses, " << dir_edges
            << " DIR edges, " << core.polarity_changes() << " polarity changes, " << step_pol_edges
            << " STEP polarity edges, " << core.resets() << " resets, " << core.ignored()
            << " requests while not ready\n";
  EXPECT_GT(pulses, uint64_t(runs) * 100);
  EXPECT_GT(dir_edges, uint64_t(runs) * 10);
  EXPECT_GT(core.resets(), uint64_t(runs));
  EXPECT_GT(core.ignored(), uint64_t(runs) * 10);
  EXPECT_GT(core.polarity_changes(), uint64_t(runs) * 10);
  EXPECT_GT(step_pol_edges, uint64_t(runs) * 2);
}

TEST(PulseRandom, RandomCoreDefault_TW16_PW32) {
  random_lockstep<sim::PulseDefault>(seed_from_env(20261121), 200, 20'000);
}

TEST(PulseRandom, RandomCoreSmall_TW4_PW8) {
  random_lockstep<sim::PulseSmall>(seed_from_env(20261121) + 1, 200, 20'000);
}

}  // namespace
}  // namespace cpstep::tb

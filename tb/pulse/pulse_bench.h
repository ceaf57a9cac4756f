// SPDX-License-Identifier: MIT
// The cp_pulse bench: RTL and model in lockstep (every output, every cycle), the
// independent pin checker on every cycle, and the pin edges recorded for the
// directed tests' measurements.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/lockstep.h"
#include "pin_checker.h"
#include "sim/pulse_configs.h"

namespace cpstep::tb {

template <class P>
class PulseBench {
 public:
  using In = model::CpPulseIn;
  using Out = model::CpPulseOut;

  PulseBench()
      : checker_(P::pw, P::model_params().step_pol_reset, P::model_params().dir_pol_reset) {}

  // Inputs held from cycle to cycle; step is cleared after each cycle (a request
  // is one cycle long).
  In in;

  // One clock with `in`. Returns the outputs of the cycle (before the edge).
  // cfg_new is the bench's, not the test's: high when the configuration differs
  // from the previous cycle's, as cp_core raises it after a CONFIG write.
  Out cycle() {
    const uint64_t c = ls_.cycle();
    in.cfg_new = config_changed();
    prev_cfg_ = in;
    have_cfg_ = true;
    const Out o = ls_.step(in);
    checker_.check(c, in, o);
    if (!in.rst) {
      // Edges as the checker classifies them (raw pins, the polarity the edge was
      // clocked with); a DIR edge is any change of the raw DIR pin.
      const bool active = checker_.active();
      if (have_prev_) {
        if (checker_.leading()) leading.push_back(c);
        if (!active && prev_active_) trailing.push_back(c);
        if (o.step != prev_step_ && !active && !prev_active_) step_pol_edges.push_back(c);
        if (o.dir != prev_dir_) dir_edges.push_back(c);
      }
      prev_active_ = active;
      prev_step_ = o.step;
      prev_dir_ = o.dir;
      have_prev_ = true;
    } else {
      have_prev_ = false;
    }
    last = o;
    in.step = false;
    return o;
  }

  void run(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) cycle();
  }

  void reset(unsigned cycles = 2) {
    in.rst = true;
    in.step = false;
    run(cycles);
    in.rst = false;
  }

  // Clock until ready_o (checked before the cycle's edge); returns that cycle's
  // index, with `in.step` applied in it when `fire`. Fails after `limit` cycles.
  uint64_t until_ready(bool fire, uint64_t limit = 1'000'000) {
    for (uint64_t i = 0; i < limit; ++i) {
      const uint64_t c = ls_.cycle();
      // outputs are combinational in state and inputs: look before deciding.
      const Out peek = peek_outputs();
      if (peek.ready) {
        in.step = fire;
        cycle();
        return c;
      }
      cycle();
    }
    ADD_FAILURE() << "ready_o never rose";
    return ls_.cycle();
  }

  // The model's outputs for the current inputs (without a clock edge).
  Out peek_outputs() {
    in.cfg_new = config_changed();
    ls_.model().in = in;
    return ls_.model().outputs();
  }

  uint64_t now() const { return ls_.cycle(); }
  const PinChecker& checker() const { return checker_; }
  void expect_pins_clean() const {
    for (const auto& e : checker_.errors()) ADD_FAILURE() << "pin checker: " << e;
  }

  Out last;
  // The cycle of the first new level: leading and trailing edges of pulses, STEP
  // polarity edges (the pin moving between two gaps), raw DIR pin edges.
  std::vector<uint64_t> leading, trailing, step_pol_edges, dir_edges;

 private:
  bool config_changed() const {
    const In& p = prev_cfg_;
    return have_cfg_ && (in.cfg_step_high != p.cfg_step_high || in.cfg_step_low != p.cfg_step_low ||
                         in.cfg_dir_setup != p.cfg_dir_setup || in.cfg_dir_hold != p.cfg_dir_hold ||
                         in.cfg_step_pol != p.cfg_step_pol || in.cfg_dir_pol != p.cfg_dir_pol);
  }

  Lockstep<P> ls_{"pulse"};
  In prev_cfg_;
  bool have_cfg_ = false;
  PinChecker checker_;
  bool have_prev_ = false, prev_active_ = false, prev_step_ = false, prev_dir_ = false;
};

inline uint64_t seed_from_env(uint64_t fallback) {
  const char* s = std::getenv("CPSTEP_SEED");
  return s ? std::strtoull(s, nullptr, 0) : fallback;
}

}  // namespace cpstep::tb

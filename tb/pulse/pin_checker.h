// SPDX-License-Identifier: MIT
// An independent checker of the STEP/DIR pin timing (docs/PULSE.md, "Pin-level
// consequences"). It reads only the pins (step_o, dir_o, position_o), rst and the
// configuration in force — never ready_o, busy_o or the model — so it holds the
// RTL and the model alike to SPEC §2, and catches a rule both got wrong the same way.
//
// It judges the raw pin levels. Every change of a pin is an edge, whatever its
// cause (a pulse, a direction change, a polarity change). A STEP level run is
// classified once, where it begins, with the STEP polarity in force at that edge —
// the configuration of the cycle before the pin changed, the one the edge was
// clocked with: a run at the active level is a pulse, any other run is a gap. So:
//
// - a pulse lasts exactly step_high (in force at its leading edge); it ends only
//   at a trailing edge (the pin back at the inactive level of that polarity);
// - a gap that ends, in a leading edge or in a STEP polarity edge (the pin going
//   to the inactive level of a new polarity), lasted at least step_low, and DIR was
//   stable for at least dir_setup (and at least 1) cycles before that edge;
// - a DIR edge happens only inside a gap, at least dir_hold (and at least 1) cycles
//   after the STEP pin's last edge (a trailing edge, or a polarity edge);
// - position_o is the signed count of leading edges (direction read through the
//   DIR polarity in force at the edge), mod 2^PW;
// - in rst the pins sit at the reset idle levels; the reset period counts as
//   "long ago" for every rule.
#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "model/cp_pulse.h"

namespace cpstep::tb {

class PinChecker {
 public:
  PinChecker(unsigned pw, bool step_pol_reset, bool dir_pol_reset)
      : pos_mask_(pw >= 64 ? ~uint64_t(0) : (uint64_t(1) << pw) - 1),
        step_pol_reset_(step_pol_reset),
        dir_pol_reset_(dir_pol_reset) {}

  // One cycle: `in` supplies rst and the configuration only; `pins` the outputs
  // as they were in this cycle (before the rising edge).
  void check(uint64_t cycle, const model::CpPulseIn& in, const model::CpPulseOut& pins) {
    cycle_ = cycle;
    leading_ = false;
    if (in.rst) {
      if (pins.step != !step_pol_reset_) fail("STEP not at its reset idle level during rst");
      if (pins.dir != !dir_pol_reset_) fail("DIR not at its reset idle level during rst");
      fresh_ = true;
      run_active_ = false;
      return;
    }
    if (fresh_) {
      // After a reset (and at power-up): the pins were at the reset idle levels, a
      // gap long ago.
      fresh_ = false;
      prev_step_ = !step_pol_reset_;
      prev_dir_ = !dir_pol_reset_;
      run_active_ = false;
      last_step_edge_ = "reset";
      step_run_ = dir_run_ = kLongAgo;
      count_ = 0;
      prev_cfg_ = in;
    }
    const model::CpPulseIn& at = prev_cfg_;  // the configuration the edges of this cycle were clocked with
    const bool step_edge = pins.step != prev_step_, dir_edge = pins.dir != prev_dir_;

    if (dir_edge) {
      if (run_active_)
        fail("DIR changes while STEP is active");
      else if (step_edge)
        fail(std::string("DIR changes at a STEP ") + (pins.step == at.cfg_step_pol ? "leading" : "polarity") +
             " edge");
      else if (step_run_ < at.cfg_dir_hold)
        fail("DIR changes " + std::to_string(step_run_) + " cycles after a " + last_step_edge_ +
             " edge, dir_hold " + std::to_string(at.cfg_dir_hold));
    }

    if (step_edge) {
      const bool active = pins.step == at.cfg_step_pol;
      if (run_active_) {  // a pulse ends
        if (active)
          fail("STEP changes level while active (the STEP polarity changed under a pulse): a pulse of " +
               std::to_string(step_run_) + " cycles");
        else if (step_run_ != want_high_)
          fail("STEP active for " + std::to_string(step_run_) + " cycles, step_high " + std::to_string(want_high_));
        last_step_edge_ = "trailing";
      } else {  // a gap ends: a leading edge, or the pin moves to a new polarity's inactive level
        const std::string what = active ? "a pulse" : "a STEP polarity edge";
        if (step_run_ < at.cfg_step_low)
          fail("STEP inactive for " + std::to_string(step_run_) + " cycles before " + what + ", step_low " +
               std::to_string(at.cfg_step_low));
        if (!dir_edge && dir_run_ < at.cfg_dir_setup)
          fail("DIR stable for " + std::to_string(dir_run_) + " cycles before " +
               (active ? std::string("a leading edge") : what) + ", dir_setup " + std::to_string(at.cfg_dir_setup));
        if (active) {
          leading_ = true;
          positive_ = pins.dir == at.cfg_dir_pol;
          count_ += positive_ ? 1 : -1;
          want_high_ = at.cfg_step_high;
          ++pulses_;
        } else {
          last_step_edge_ = "STEP polarity";
          ++polarity_edges_;
        }
      }
      run_active_ = active;
    } else if (run_active_ && step_run_ >= want_high_) {
      fail("STEP active longer than step_high " + std::to_string(want_high_));
    }

    if (pins.position != (uint64_t(count_) & pos_mask_))
      fail("position_o " + std::to_string(pins.position) + " but " + std::to_string(count_) +
           " signed leading edges seen");

    step_run_ = step_edge ? 1 : sat(step_run_);
    dir_run_ = dir_edge ? 1 : sat(dir_run_);
    prev_step_ = pins.step;
    prev_dir_ = pins.dir;
    prev_cfg_ = in;
  }

  const std::vector<std::string>& errors() const { return errors_; }
  uint64_t pulses() const { return pulses_; }                  // leading edges seen, over all resets
  uint64_t polarity_edges() const { return polarity_edges_; }  // STEP polarity edges seen
  // After check(): the STEP pin is at the active level of its pulse in this cycle.
  bool active() const { return run_active_; }
  // After check(): a pulse's leading edge is in this cycle, and its direction.
  bool leading() const { return leading_; }
  bool positive() const { return positive_; }

 private:
  static constexpr uint64_t kLongAgo = uint64_t(1) << 62;
  static uint64_t sat(uint64_t n) { return n >= kLongAgo ? n : n + 1; }

  void fail(const std::string& what) {
    if (errors_.size() < 8) errors_.push_back("cycle " + std::to_string(cycle_) + ": " + what);
  }

  uint64_t pos_mask_;
  bool step_pol_reset_, dir_pol_reset_;
  bool fresh_ = true;
  bool prev_step_ = false, prev_dir_ = false;  // raw pin levels in the previous cycle
  bool run_active_ = false;                    // the STEP run in progress is a pulse
  bool leading_ = false, positive_ = false;
  std::string last_step_edge_ = "reset";        // what ended the last STEP run
  uint64_t step_run_ = kLongAgo;  // cycles the STEP pin has held its level, up to the previous cycle
  uint64_t dir_run_ = kLongAgo;   // the same for DIR
  uint64_t want_high_ = 0;
  int64_t count_ = 0;
  uint64_t pulses_ = 0, polarity_edges_ = 0;
  uint64_t cycle_ = 0;
  model::CpPulseIn prev_cfg_;
  std::vector<std::string> errors_;
};

}  // namespace cpstep::tb

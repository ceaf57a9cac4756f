// An independent checker of the STEP/DIR pin timing (docs/PULSE.md, "Pin-level
// consequences"). It reads only the pins (step_o, dir_o, position_o), rst and the
// configuration in force — never ready_o, busy_o or the model — so it holds the
// RTL and the model alike to SPEC §2, and catches a rule both got wrong the same way.
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
    if (in.rst) {
      if (pins.step != !step_pol_reset_) fail("STEP not at its reset idle level during rst");
      if (pins.dir != !dir_pol_reset_) fail("DIR not at its reset idle level during rst");
      fresh_ = true;
      return;
    }
    const bool active = pins.step == in.cfg_step_pol;
    const bool dir = pins.dir == in.cfg_dir_pol;
    if (fresh_) {
      // After a reset (and at power-up): STEP idle, DIR logical 0, both long ago.
      fresh_ = false;
      prev_active_ = false;
      prev_dir_ = false;
      step_run_ = dir_run_ = kLongAgo;
      count_ = 0;
      prev_cfg_ = in;
    }

    if (active && !prev_active_) {  // leading edge
      if (step_run_ < prev_cfg_.cfg_step_low)
        fail("STEP inactive for " + std::to_string(step_run_) + " cycles before a pulse, step_low " +
             std::to_string(prev_cfg_.cfg_step_low));
      if (dir != prev_dir_)
        fail("DIR changes at a STEP leading edge");
      else if (dir_run_ < prev_cfg_.cfg_dir_setup)
        fail("DIR stable for " + std::to_string(dir_run_) + " cycles before a leading edge, dir_setup " +
             std::to_string(prev_cfg_.cfg_dir_setup));
      count_ += dir ? 1 : -1;
      want_high_ = prev_cfg_.cfg_step_high;
      ++pulses_;
    }
    if (active && prev_active_ && step_run_ >= want_high_)
      fail("STEP active longer than step_high " + std::to_string(want_high_));
    if (!active && prev_active_ && step_run_ != want_high_)
      fail("STEP active for " + std::to_string(step_run_) + " cycles, step_high " +
           std::to_string(want_high_));
    if (dir != prev_dir_) {
      if (active || prev_active_)
        fail("DIR changes while STEP is active");
      else if (step_run_ < prev_cfg_.cfg_dir_hold)
        fail("DIR changes " + std::to_string(step_run_) + " cycles after a trailing edge, dir_hold " +
             std::to_string(prev_cfg_.cfg_dir_hold));
    }
    if (pins.position != (uint64_t(count_) & pos_mask_))
      fail("position_o " + std::to_string(pins.position) + " but " + std::to_string(count_) +
           " signed leading edges seen");

    step_run_ = active == prev_active_ ? sat(step_run_) : 1;
    dir_run_ = dir == prev_dir_ ? sat(dir_run_) : 1;
    prev_active_ = active;
    prev_dir_ = dir;
    prev_cfg_ = in;
  }

  const std::vector<std::string>& errors() const { return errors_; }
  uint64_t pulses() const { return pulses_; }  // leading edges seen, over all resets

 private:
  static constexpr uint64_t kLongAgo = uint64_t(1) << 62;
  static uint64_t sat(uint64_t n) { return n >= kLongAgo ? n : n + 1; }

  void fail(const std::string& what) {
    if (errors_.size() < 8) errors_.push_back("cycle " + std::to_string(cycle_) + ": " + what);
  }

  uint64_t pos_mask_;
  bool step_pol_reset_, dir_pol_reset_;
  bool fresh_ = true;
  bool prev_active_ = false, prev_dir_ = false;
  uint64_t step_run_ = kLongAgo;  // cycles the STEP level has held, up to the previous cycle
  uint64_t dir_run_ = kLongAgo;   // the same for DIR
  uint64_t want_high_ = 0;
  int64_t count_ = 0;
  uint64_t pulses_ = 0;
  uint64_t cycle_ = 0;
  model::CpPulseIn prev_cfg_;
  std::vector<std::string> errors_;
};

}  // namespace cpstep::tb

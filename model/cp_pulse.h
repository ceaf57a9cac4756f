// SPDX-License-Identifier: MIT
// cp_pulse — cycle-accurate, bit-exact model of rtl/cp_pulse.v.
//
// Written from docs/PULSE.md (the pulse timer's cycle contract), not from the RTL.
// Same ports as the RTL; the bench sets `in`, reads outputs() (the pins before the
// rising edge, combinational in the state and inputs), then calls tick() (the edge).
#pragma once

#include <cstdint>

namespace cpstep::model {

struct CpPulseParams {
  unsigned tw = 16;             // width of the timing fields, 1..32
  unsigned pw = 32;             // width of the position counter, 1..64
  bool step_pol_reset = true;   // STEP polarity on the pins while rst is high
  bool dir_pol_reset = true;    // DIR polarity on the pins while rst is high
};

struct CpPulseIn {
  bool rst = false;
  uint32_t cfg_step_high = 1, cfg_step_low = 1, cfg_dir_setup = 0, cfg_dir_hold = 0;
  bool cfg_step_pol = true, cfg_dir_pol = true;
  bool cfg_new = false;  // the configuration was written at the last edge: no STEP edge now
  bool dir = false;
  bool step = false;
};

struct CpPulseOut {
  bool ready = false;
  bool step = false;
  bool dir = false;
  uint64_t position = 0;
  bool busy = false;
};

class CpPulse {
 public:
  using Params = CpPulseParams;
  using In = CpPulseIn;
  using Out = CpPulseOut;

  explicit CpPulse(CpPulseParams params = {});

  CpPulseIn in;

  CpPulseOut outputs() const;
  void tick();

  // Event skipping (CpCore::quiet_for): how many clocks with inputs `i` change
  // nothing but the timer's counters — no pulse starts or ends, no pin moves —
  // before a counter reaches a threshold that can change what the timer does.
  // 0: clock it normally; kForever: nothing here ends the quiet.
  static constexpr uint64_t kForever = ~uint64_t(0);
  uint64_t quiet_for(const CpPulseIn& i) const;
  // Advances that many quiet clocks at once.
  void skip(uint64_t cycles);

  const CpPulseParams& params() const { return p_; }

 private:
  // docs/PULSE.md, "State"; the constructor leaves the reset state.
  struct Regs {
    bool active = false;
    uint32_t high_cnt = 0;
    uint32_t low_cnt = 0;    // set to saturated by reset_state()
    bool step_pol = true;    // the STEP polarity on the pin; reset_state(): the parameter
    bool dir_pin = false;    // the DIR pin level; reset_state(): logical 0 in the parameter polarity
    uint32_t setup_cnt = 0;  // set to saturated by reset_state()
    uint64_t position = 0;
  };
  Regs reset_state() const;
  uint32_t sat_inc(uint32_t x) const { return x == sat_ ? x : x + 1; }
  uint32_t sat_add(uint32_t x, uint64_t k) const { return k >= uint64_t(sat_ - x) ? sat_ : uint32_t(x + k); }
  static bool want_dir(const CpPulseIn& i) { return i.cfg_dir_pol ? i.dir : !i.dir; }
  bool quiet(const CpPulseIn& i) const;
  bool ready(const CpPulseIn& i) const;

  CpPulseParams p_;
  uint32_t sat_;       // 2^TW - 1, also the mask of a timing field
  uint64_t pos_mask_;  // 2^PW - 1
  Regs r_;
};

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
// cp_inputs — cycle-accurate, bit-exact model of rtl/cp_inputs.v: the limit
// switches and the probe, filtered (three samples in a row that agree, one sample
// every max(P, 1) clocks, P from CONFIG field 6) and made active by their
// configured polarity and enables (fields 7 and 8); the seek (field 10: a run that
// ends when the probe or a limit trips); docs/CORE.md "Inputs".
// outputs() before the edge, tick() the edge.
#pragma once

#include <cstdint>

namespace cpstep::model {

// The inputs as one word, {probe, max[N], min[N]} (rtl/cp_inputs.v's `pins`, cp_card's
// synchronizer).
inline uint32_t pack_inputs(unsigned n, uint32_t lim_min, uint32_t lim_max, bool probe) {
  const uint32_t m = (1u << n) - 1;
  return (lim_min & m) | (lim_max & m) << n | uint32_t(probe) << (2 * n);
}

struct CpInputsIn {
  bool rst = false;
  uint32_t lim_min = 0, lim_max = 0;  // bit a: axis a's synchronized pin
  bool probe = false;
  bool cfg_write = false;
  uint32_t cfg_word = 0;
  bool running = false;  // the run is on (cp_run)
  bool lim_hit = false;  // the runner hits an active limit (cp_run)
};

struct CpInputsOut {
  uint32_t lim_min = 0, lim_max = 0;  // active (enabled, at their active level)
  bool probe = false;
  bool seek_stop = false;  // modes 1-2: armed and the probe trips (the runner stops)
  bool seek_lim = false;   // mode 3: a limit hit is the trip, not LIMIT
  uint32_t seek = 0;       // {tripped, mode[1:0]}: READ 0x27 [19:17]
  bool operator==(const CpInputsOut&) const = default;
};

class CpInputs {
 public:
  using In = CpInputsIn;
  using Out = CpInputsOut;

  using Params = unsigned;  // N, the axes
  explicit CpInputs(unsigned n = 4);
  In in;
  Out outputs() const;  // registered only: no input reaches them
  void tick();
  // The clocks from now, with inputs `i` held, in which nothing changes but the
  // sample counter (at most `limit`): every level agrees with its samples and its
  // pin. skip(n) advances them.
  uint64_t quiet_for(const In& i, uint64_t limit) const;
  void skip(uint64_t cycles);

 private:
  struct Regs {
    uint32_t filter = 0, count = 0;
    uint32_t s1 = 0, s2 = 0, level = 0;  // bits: min[N], max[N], probe
    uint32_t min_hi = 0, max_hi = 0, min_en = 0, max_en = 0;
    bool probe_hi = true;
    uint32_t seek = 0;  // the seek's mode
    bool tripped = false;
  };
  bool probe_trips(const Regs& q) const;
  Regs reset_state() const;
  uint32_t pins(const In& i) const;

  unsigned n_;
  uint32_t mask_;  // N bits
  Regs r_;
};

}  // namespace cpstep::model

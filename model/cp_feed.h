// SPDX-License-Identifier: MIT
// cp_feed — cycle-accurate, bit-exact model of rtl/cp_feed.v: feed hold, resume
// and override, the scale s of the move timer's time, following its target through
// two first-order stages in series (u += (target - u) / 2^10, s += (u - s) / 2^10 once
// a ramp tick, every max(T, 1) clocks, T from CONFIG field 9); docs/CORE.md "Feed hold
// and override". outputs() before the edge, tick() the edge.
#pragma once

#include <cstdint>

namespace cpstep::model {

struct CpFeedIn {
  bool rst = false;
  bool cfg_write = false;
  uint32_t cfg_word = 0;
  // URGENT bits (rtl/cp_spi.v), in the cycle of the frame's CS rise.
  bool hold = false, resume = false, ovr = false;
  uint32_t ovr_val = 0;  // Q2.14, 16 bits
};

struct CpFeedOut {
  uint32_t scale = 0x10000;  // the timer's scale, Q2.16 (18 bits)
  uint32_t feed = 0;         // READ 0x29: {held, settled, 14'b0, s in Q2.14}
  uint32_t override = 0;     // READ 0x2A
  bool operator==(const CpFeedOut&) const = default;
};

struct CpFeedParams {};  // none: the module has no parameters

class CpFeed {
 public:
  using In = CpFeedIn;
  using Out = CpFeedOut;
  using Params = CpFeedParams;

  static constexpr uint32_t kOne = 1u << 30;  // s = 1 in Q2.30
  static constexpr unsigned kShift = 10;      // each stage moves 2^-10 of its distance a tick

  explicit CpFeed(Params = {}) {}
  In in;
  Out outputs() const;  // registered only
  void tick();
  // The clocks from now, with inputs `i` held, in which nothing changes but the tick
  // counter (at most `limit`): s is settled on its target, or up to the next tick.
  uint64_t quiet_for(const In& i, uint64_t limit) const;
  void skip(uint64_t cycles);

  // For the benches: the scale and the first stage in Q2.30, the target.
  uint32_t s() const { return r_.s; }
  uint32_t u() const { return r_.u; }
  bool tick_now() const { return r_.count == 0; }  // the ramp moves at this clock's edge
  uint32_t target() const;

 private:
  struct Regs {
    uint32_t period = 0, count = 0;
    uint32_t ovr = 0x4000;
    bool held = false;
    uint32_t u = kOne, s = kOne;  // Q2.30
  };
  bool settled() const;
  Regs r_;
};

}  // namespace cpstep::model

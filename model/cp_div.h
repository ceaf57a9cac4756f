// SPDX-License-Identifier: MIT
// cp_div — cycle-accurate, bit-exact model of rtl/cp_div.v: a serial divider,
// q = floor(k / d), one quotient bit a clock (issue 13: the conic length rule's
// division; a unit on its own, not yet part of cp_core).
//
// start while idle takes k and d; a quotient that does not fit QW bits (k >> QW
// >= d) or d = 0 is refused (done the next clock with err, q = 0); otherwise QW
// clocks of restoring division, then done pulses with q, which holds until the
// next start. A start while busy is ignored. outputs() before the edge, tick() the
// edge.
#pragma once

#include <cstdint>

namespace cpstep::model {

struct CpDivIn {
  bool rst = false;
  bool start = false;
  uint64_t k = 0;   // KW bits
  uint64_t d = 0;   // DW bits
};

struct CpDivOut {
  bool busy = false;
  bool done = false;
  bool err = false;
  uint64_t q = 0;   // QW bits
  bool operator==(const CpDivOut&) const = default;
};

struct CpDivParams {
  unsigned kw = 64, dw = 42, qw = 32;   // QW < KW <= 64, KW - QW <= DW < 64
};

class CpDiv {
 public:
  using In = CpDivIn;
  using Out = CpDivOut;
  using Params = CpDivParams;
  explicit CpDiv(Params p = {}) : p_(p) {}
  In in;
  Out outputs() const;
  void tick();

 private:
  struct Regs {
    bool busy = false, done = false, err = false;
    unsigned left = 0;
    uint64_t rem = 0, d = 0, sr = 0;
  };
  Params p_;
  Regs r_;
};

}  // namespace cpstep::model

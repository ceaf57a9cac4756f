// SPDX-License-Identifier: MIT
// cp_div — cycle-accurate, bit-exact model of rtl/cp_div.v: the conic length
// rule's serial divider, q = floor(k * 2^s / D), D = d + d_inc, saturated to
// 2^QW - 1 when it does not fit.
//
// start while idle starts the division of the KW + s bits of k * 2^s, one a clock
// (restoring; the inputs are read every clock of it), then done pulses with q,
// which holds until the next start. A start while busy is ignored. outputs()
// before the edge, tick() the edge.
#pragma once

#include <cstdint>

namespace cpstep::model {

struct CpDivIn {
  bool rst = false;
  bool start = false;
  uint64_t k = 0;   // KW bits
  unsigned s = 0;   // SW bits
  uint64_t d = 0;   // DW bits
  bool d_inc = false;
};

struct CpDivOut {
  bool busy = false;
  bool done = false;
  uint64_t q = 0;   // QW bits
  bool operator==(const CpDivOut&) const = default;
};

struct CpDivParams {
  unsigned dw = 40, kw = 27, sw = 5, qw = 32;   // rtl/cp_div.v's ranges
};

class CpDiv {
 public:
  using In = CpDivIn;
  using Out = CpDivOut;
  using Params = CpDivParams;
  explicit CpDiv(Params p = {});
  In in;
  Out outputs() const;
  void tick();

 private:
  struct Regs {
    bool busy = false, done = false, ovf = false;
    unsigned left = 0;
    uint64_t rem = 0, q = 0;
  };
  Params p_;
  Regs r_;
};

}  // namespace cpstep::model

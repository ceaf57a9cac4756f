// SPDX-License-Identifier: MIT
#include "model/cp_div.h"

#include <stdexcept>

#include "model/bits.h"

namespace cpstep::model {

namespace {
uint64_t low(uint64_t x, unsigned w) { return x & bits::mask64(w); }
}  // namespace

CpDiv::CpDiv(Params p) : p_(p) {
  if (p_.kw < 2 || p_.sw > 5 || p_.qw < 2 || p_.qw > 62 || p_.dw < 2 || p_.dw > 62 || p_.kw + (1u << p_.sw) - 1 >= 64)
    throw std::invalid_argument("cp_div: parameters out of range");
}

CpDivOut CpDiv::outputs() const {
  Out o;
  o.busy = r_.busy;
  o.done = r_.done;
  o.q = r_.ovf ? bits::mask64(p_.qw) : r_.q;
  return o;
}

void CpDiv::tick() {
  const Regs o = r_;
  Regs n = r_;
  if (o.busy) {
    // Bit left - 1 of k 2^s into the remainder, less D where it fits; the quotient
    // bit in, the one leaving the quotient remembered.
    const unsigned s = in.s & ((1u << p_.sw) - 1);
    const int idx = int(o.left) - int(s) - 1;
    const uint64_t bit = idx >= 0 ? (low(in.k, p_.kw) >> idx & 1) : 0;
    const uint64_t t = (o.rem << 1) | bit;   // DW + 1 bits
    const uint64_t divisor = low(in.d, p_.dw) + uint64_t(in.d_inc);
    const bool fits = t >= divisor;
    n.rem = low(fits ? t - divisor : t, p_.dw);
    n.q = low(o.q << 1 | uint64_t(fits), p_.qw);
    n.ovf = o.ovf || (o.q >> (p_.qw - 1) & 1) != 0;
  } else if (in.start) {
    n.rem = n.q = 0;
    n.ovf = false;
  }
  if (in.rst) {
    n.busy = n.done = false;
    n.left = 0;
  } else {
    n.done = false;
    if (o.busy) {
      n.left = o.left - 1;
      if (o.left == 1) {
        n.busy = false;
        n.done = true;
      }
    } else if (in.start) {
      n.busy = true;
      n.left = (in.s & ((1u << p_.sw) - 1)) + p_.kw;
    }
  }
  r_ = n;
}

}  // namespace cpstep::model

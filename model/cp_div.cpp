// SPDX-License-Identifier: MIT
#include "model/cp_div.h"

#include "model/bits.h"

namespace cpstep::model {

namespace {
uint64_t low(uint64_t x, unsigned w) { return x & bits::mask64(w); }
}  // namespace

CpDivOut CpDiv::outputs() const {
  Out o;
  o.busy = r_.busy;
  o.done = r_.done;
  o.err = r_.err;
  o.q = r_.sr;
  return o;
}

void CpDiv::tick() {
  if (in.rst) {
    r_ = Regs{};
    return;
  }
  const Regs o = r_;
  Regs n = r_;
  n.done = false;
  if (o.busy) {
    // The remainder with k's next bit, less d where it fits.
    const uint64_t t = (o.rem << 1) | (o.sr >> (p_.qw - 1) & 1);   // DW + 1 < 64 bits
    const bool fits = t >= o.d;
    n.rem = fits ? t - o.d : low(t, p_.dw);
    n.sr = low(o.sr << 1 | uint64_t(fits), p_.qw);
    n.left = o.left - 1;
    if (o.left == 1) {
      n.busy = false;
      n.done = true;
    }
  } else if (in.start) {
    const uint64_t k = low(in.k, p_.kw), d = low(in.d, p_.dw);
    const uint64_t k_hi = k >> p_.qw;
    const bool bad = d == 0 || k_hi >= d;
    n.err = bad;
    n.d = d;
    if (bad) {
      n.done = true;
      n.sr = 0;
    } else {
      n.busy = true;
      n.left = p_.qw;
      n.rem = k_hi;
      n.sr = low(k, p_.qw);
    }
  }
  r_ = n;
}

}  // namespace cpstep::model

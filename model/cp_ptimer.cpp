// SPDX-License-Identifier: MIT
#include "model/cp_ptimer.h"

#include <algorithm>

#include "model/bits.h"

namespace cpstep::model {

namespace {

// The low `w` bits of x as a signed value.
int64_t sx(int64_t x, unsigned w) {
  const uint64_t m = bits::mask64(w);
  uint64_t v = uint64_t(x) & m;
  if (w < 64 && (v >> (w - 1) & 1)) v |= ~m;
  return int64_t(v);
}

// The low `w` bits of x as a signed value (w < 128).
bits::i128 sx128(bits::i128 x, unsigned w) {
  const bits::u128 m = (static_cast<bits::u128>(1) << w) - 1;
  bits::u128 v = static_cast<bits::u128>(x) & m;
  if (v >> (w - 1) & 1) v |= ~m;
  return static_cast<bits::i128>(v);
}

}  // namespace

bits::i128 CpPtimer::threshold() const {
  const uint64_t len = in.len & bits::mask64(p_.lw);
  return bits::i128(len) << p_.s;
}

CpPtimerOut CpPtimer::outputs() const {
  Out o;
  o.due = r_.tdue || r_.bdue || (!r_.owe && r_.r >= 0);  // (also in a timed phase: rtl/cp_ptimer.v)
  o.active = r_.active;
  o.ready = !r_.nvalid;
  o.starved = r_.starved;
  o.kind = r_.kind;
  return o;
}

void CpPtimer::tick() {
  if (in.rst || in.clear) {
    r_ = Regs{};
    return;
  }
  const Regs o = r_;
  Regs n = r_;
  const bool due = o.tdue || o.bdue || (!o.owe && o.r >= 0);
  // The next phase's buffer: written while free, W0 last.
  if (in.wr && !o.nvalid) {
    switch (in.sel & 7) {
      case 0:
        n.nkind = in.data >> 28;   // {load S and H, rest, timed, load r}
        n.nticks = in.data & ((uint32_t{1} << p_.tw) - 1);
        n.nvalid = true;
        break;
      case 1: n.nu = int64_t(int32_t(in.data)); break;
      case 2: n.np = (o.np & ~uint64_t{0xFFFFFFFF}) | in.data; break;
      case 3: n.np = (o.np & 0xFFFFFFFF) | uint64_t{in.data} << 32; break;
      case 4: n.ns = (o.ns & ~uint64_t{0xFFFFFFFF}) | in.data; break;
      case 5: n.ns = (o.ns & 0xFFFFFFFF) | uint64_t{in.data} << 32; break;
      case 6: n.nh = (o.nh & ~uint64_t{0xFFFFFFFF}) | in.data; break;
      default: n.nh = (o.nh & 0xFFFFFFFF) | uint64_t{in.data} << 32; break;
    }
  }
  // The due move fires (a timed one clears its flag): r takes off the length of
  // the move now pending, the next one, if it is known, else owes it. (A length
  // owed, after a start from rest or such a fire, is taken off when known.)
  bits::i128 r = o.r;
  if (in.fire && due && o.tdue) n.tdue = false;
  if (in.fire && o.bdue) n.bdue = false;
  // (A bdue move's fire takes nothing off: the r that replaced it is the next move's.)
  const bool take = (in.fire && due && !o.bdue) || o.owe;
  n.owe = take && !in.len_valid;
  if (take && in.len_valid) r -= threshold();
  bool phase_end = false;
  if (o.active && in.adv) {
    if (o.timed) {
      if (o.tleft == 1) {
        n.tdue = true;
        r = 0;   // p = 0, the timed move's fire takes off the next one's length
        n.owe = false;
        phase_end = true;
      } else {
        n.tleft = o.tleft - 1;
      }
    } else {
      r += o.step;
      n.tcnt = (o.tcnt + 1) & ((uint32_t{1} << p_.s) - 1);
      if (o.tcnt == (uint32_t{1} << p_.s) - 1) {
        n.step = sx(o.step + 2 * o.h + 6 * o.u, p_.vw);
        n.h = sx(o.h + 3 * o.u, p_.hw);
        if (o.tleft == 1) phase_end = true;
        else n.tleft = o.tleft - 1;
      }
    }
  }
  // A jerk phase ending with its pending move due (nothing owed after this clock) while
  // the next phase replaces r (rest, load r): the move stays due (rtl/cp_ptimer.v, bdue_q).
  if (phase_end && !o.timed && o.nvalid && (o.nkind & 5) != 0 && sx128(r, rw()) >= 0 && !n.owe) n.bdue = true;
  if (phase_end || (!o.active && o.nvalid)) {
    if (o.nvalid) {
      const int64_t u = sx(o.nu, p_.uw);
      n.nvalid = false;
      n.active = true;
      ++loads_;
      n.starved = false;
      n.kind = o.nkind;
      n.timed = (o.nkind & 2) != 0;
      n.u = u;
      n.tleft = o.nticks == 0 ? 1 : o.nticks;
      n.tcnt = 0;
      if (o.nkind & 4) {   // from rest: p = 0, r = 0, the pending move's length owed
        n.step = n.h = 0;
        r = 0;
        n.owe = !n.tdue;   // (a timed move still to fire takes off the next's)
      }
      if (o.nkind & 8) {   // load S and H
        n.step = sx(int64_t(o.ns), p_.vw);
        n.h = sx(int64_t(o.nh), p_.hw);
      }
      if (o.nkind & 1) {   // load r (its top 64 bits)
        r = bits::i128(int64_t(o.np)) << (rw() - 64);
        n.owe = false;
      }
    } else {
      n.active = false;
      n.starved = true;
    }
  }
  n.r = sx128(r, rw());
  r_ = n;
}

std::optional<uint64_t> CpPtimer::quiet_advs(bool len_valid, uint64_t limit) const {
  const Regs& q = r_;
  if (q.tdue || q.bdue || (!q.owe && q.r >= 0)) return std::nullopt;   // due now
  if (q.owe && len_valid) return std::nullopt;                          // taken off now
  if (!q.active) {
    if (q.nvalid) return std::nullopt;                                  // loads now
    return kForever;
  }
  if (q.timed) return std::min<uint64_t>(limit, q.tleft - 1);          // its last clock is due
  // A jerk phase: r rises by the step each advancing clock, the step and H change at
  // each tick's end; the phase's last clock ends it. Due when r >= 0 (not while owed).
  const uint64_t tick = uint64_t(1) << p_.s;
  const bits::i128 lo = -(bits::i128(1) << (rw() - 1)), hi = (bits::i128(1) << (rw() - 1)) - 1;
  // A flat phase (a rest: step, H and u 0) changes nothing until its last clock.
  if (q.step == 0 && q.h == 0 && q.u == 0)
    return std::min<uint64_t>(limit, (tick - q.tcnt) + (uint64_t(q.tleft) - 1) * tick - 1);
  bits::i128 r = q.r;
  int64_t step = q.step, h = q.h;
  uint64_t tleft = q.tleft, tcnt = q.tcnt, n = 0;
  while (n < limit) {
    const uint64_t rest = tick - tcnt;                  // clocks to the tick's end
    const bool last = tleft == 1;
    const uint64_t quiet = std::min<uint64_t>(last ? rest - 1 : rest, limit - n);
    if (!q.owe && step > 0) {
      const bits::i128 need = (-r + step - 1) / step;      // the first clock after which r >= 0
      if (need <= bits::i128(quiet)) return n + uint64_t(need) - 1;
    }
    const bits::i128 end = r + bits::i128(quiet) * step;
    if (end < lo || end > hi) return n;                 // (r would wrap: clocked one by one)
    n += quiet;
    if (last || quiet < rest) return n;
    r = end;
    step = sx(step + 2 * h + 6 * q.u, p_.vw);
    h = sx(h + 3 * q.u, p_.hw);
    --tleft;
    tcnt = 0;
  }
  return n;
}

void CpPtimer::skip_advs(uint64_t n) {
  if (!r_.active || n == 0) return;
  if (r_.timed) {
    r_.tleft -= uint32_t(n);
    return;
  }
  const uint64_t tick = uint64_t(1) << p_.s;
  if (r_.step == 0 && r_.h == 0 && r_.u == 0) {   // flat: whole ticks at once, r kept
    const uint64_t at = r_.tcnt + n;
    r_.tleft -= uint32_t(at / tick);
    r_.tcnt = uint32_t(at % tick);
    return;
  }
  while (n > 0) {
    const uint64_t k = std::min<uint64_t>(n, tick - r_.tcnt);
    r_.r = sx128(r_.r + bits::i128(k) * r_.step, rw());
    n -= k;
    if (r_.tcnt + k == tick) {
      r_.tcnt = 0;
      r_.step = sx(r_.step + 2 * r_.h + 6 * r_.u, p_.vw);
      r_.h = sx(r_.h + 3 * r_.u, p_.hw);
      --r_.tleft;
    } else {
      r_.tcnt = uint32_t(r_.tcnt + k);
    }
  }
}

}  // namespace cpstep::model

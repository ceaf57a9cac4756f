// SPDX-License-Identifier: MIT
#include "model/cp_feed.h"

#include <algorithm>

#include "model/bits.h"

namespace cpstep::model {

namespace {

// One stage: x moves 2^-kShift of its distance to `to` (an arithmetic shift of the
// 33-bit difference), or takes `to` within 2^kShift units.
uint32_t stage(uint32_t x, uint32_t to) {
  const int64_t d = int64_t(to) - int64_t(x);
  if (d > -(int64_t(1) << CpFeed::kShift) - 1 && d < (int64_t(1) << CpFeed::kShift)) return to;
  return uint32_t(int64_t(x) + (d >> CpFeed::kShift));
}

}  // namespace

uint32_t CpFeed::target() const { return r_.held ? 0 : r_.ovr << 16; }

bool CpFeed::settled() const { return r_.s == target() && r_.u == target(); }

CpFeed::Out CpFeed::outputs() const {
  Out o;
  o.scale = r_.s >> 14 & 0x3FFFF;
  o.feed = uint32_t(r_.held) << 31 | uint32_t(settled()) << 30 | (r_.s >> 16 & 0xFFFF);
  o.override = r_.ovr;
  return o;
}

void CpFeed::tick() {
  const In& i = in;
  if (i.rst) {
    r_ = Regs{};
    return;
  }
  const Regs q = r_;
  Regs& d = r_;
  const uint32_t field = i.cfg_word >> 20 & 0xF;
  const bool cfg_period = i.cfg_write && field == 9;
  d.count = bits::tick_next(q.count, q.period, cfg_period);
  const uint32_t t = q.held ? 0 : q.ovr << 16;
  if (q.count == 0) {
    d.u = stage(q.u, t);
    d.s = stage(q.s, q.u);
  }
  // A new period: s takes its target.
  if (cfg_period) {
    d.u = d.s = t;
    d.period = i.cfg_word & 0xFFFF;
  }
  if (i.ovr) d.ovr = std::min<uint32_t>(i.ovr_val & 0xFFFF, 0x8000);
  if (i.resume) d.held = false;
  if (i.hold) d.held = true;
}

uint64_t CpFeed::quiet_for(const In& i, uint64_t limit) const {
  if (i.rst || i.cfg_write || i.hold || i.resume || i.ovr) return 0;
  if (settled()) return limit;
  return std::min<uint64_t>(limit, r_.count);  // the ramp moves at the tick (count == 0)
}

void CpFeed::skip(uint64_t cycles) { r_.count = bits::tick_skip(r_.count, r_.period, cycles); }

}  // namespace cpstep::model

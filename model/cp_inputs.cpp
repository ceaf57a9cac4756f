// SPDX-License-Identifier: MIT
#include "model/cp_inputs.h"

#include <algorithm>

#include "model/bits.h"

namespace cpstep::model {

CpInputs::CpInputs(unsigned n) : n_(n), mask_((1u << n) - 1) { r_ = reset_state(); }

CpInputs::Regs CpInputs::reset_state() const {
  Regs r;
  r.min_hi = r.max_hi = mask_;
  r.probe_hi = true;
  return r;
}

uint32_t CpInputs::pins(const In& i) const {
  return pack_inputs(n_, i.lim_min, i.lim_max, i.probe);
}

// Modes 1 and 2: the probe active, the probe inactive.
bool CpInputs::probe_trips(const Regs& q) const {
  const bool on = ((q.level >> (2 * n_) & 1) != 0) == q.probe_hi;
  return (q.seek == 1 && on) || (q.seek == 2 && !on);
}

CpInputs::Out CpInputs::outputs() const {
  const Regs& q = r_;
  Out o;
  o.lim_min = q.min_en & ~(q.level ^ q.min_hi) & mask_;
  o.lim_max = q.max_en & ~((q.level >> n_) ^ q.max_hi) & mask_;
  o.probe = ((q.level >> (2 * n_) & 1) != 0) == q.probe_hi;
  o.seek_stop = probe_trips(q);
  o.seek_lim = q.seek == 3;
  o.seek = uint32_t(q.tripped) << 2 | q.seek;
  return o;
}

void CpInputs::tick() {
  const In& i = in;
  if (i.rst) {
    r_ = reset_state();
    return;
  }
  Regs& q = r_;
  const Regs was = q;
  const bool tick = was.count == 0;
  const uint32_t field = i.cfg_word >> 20 & 0xF;
  const bool cfg_filter = i.cfg_write && field == 6;
  q.count = bits::tick_next(was.count, was.filter, cfg_filter);
  if (tick) {
    const uint32_t p = pins(i);
    q.s1 = p;
    q.s2 = was.s1;
    q.level = (p & was.s1 & was.s2) | (was.level & (p | was.s1 | was.s2));
  }
  if (cfg_filter) q.filter = i.cfg_word & 0xFFFF;
  if (i.cfg_write && field == 8) q.probe_hi = (i.cfg_word & 1) != 0;
  if ((i.running && probe_trips(was)) || (was.seek == 3 && i.lim_hit)) {
    q.seek = 0;
    q.tripped = true;
  }
  if (i.cfg_write && field == 10) {
    q.seek = i.cfg_word & 3;
    q.tripped = false;
  }
  if (i.cfg_write && field == 7) {
    const uint32_t axis = i.cfg_word >> 24 & 0xF;
    if (axis < n_) {
      const uint32_t bit = 1u << axis;
      const auto put = [&](uint32_t& reg, unsigned b) { reg = (reg & ~bit) | ((i.cfg_word >> b & 1) ? bit : 0); };
      put(q.min_hi, 0);
      put(q.max_hi, 1);
      put(q.min_en, 2);
      put(q.max_en, 3);
    }
  }
}

uint64_t CpInputs::quiet_for(const In& i, uint64_t limit) const {
  if (i.rst || i.cfg_write) return 0;
  if ((i.running && probe_trips(r_)) || (r_.seek == 3 && i.lim_hit)) return 0;  // the seek trips
  const uint32_t p = pins(i);
  return (r_.s1 == p && r_.s2 == p && r_.level == p) ? limit : 0;
}

void CpInputs::skip(uint64_t cycles) {
  r_.count = bits::tick_skip(r_.count, r_.filter, cycles);
}

}  // namespace cpstep::model

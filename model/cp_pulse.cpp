// SPDX-License-Identifier: MIT
#include "cp_pulse.h"

#include <algorithm>
#include <stdexcept>

namespace cpstep::model {

CpPulse::CpPulse(CpPulseParams params)
    : p_(params),
      sat_(p_.tw >= 32 ? ~0u : (1u << p_.tw) - 1),
      pos_mask_(p_.pw >= 64 ? ~uint64_t(0) : (uint64_t(1) << p_.pw) - 1) {
  if (p_.tw < 1 || p_.tw > 32) throw std::invalid_argument("cp_pulse: TW must be 1 to 32");
  if (p_.pw < 1 || p_.pw > 64) throw std::invalid_argument("cp_pulse: PW must be 1 to 64");
  r_ = reset_state();
}

CpPulse::Regs CpPulse::reset_state() const {
  Regs s;
  s.low_cnt = sat_;    // "long ago": ready at once after reset
  s.setup_cnt = sat_;
  s.step_pol = p_.step_pol_reset;  // the pins stay at the reset idle levels
  s.dir_pin = !p_.dir_pol_reset;
  return s;
}

// quiet: a STEP edge (leading or polarity) may happen now —
//   !cfg_new && !active && low_cnt >= step_low && dir_pin == want_dir && setup_cnt >= dir_setup
// (none in the cycle after a configuration write).
bool CpPulse::quiet(const CpPulseIn& i) const {
  return !i.cfg_new && !r_.active && r_.low_cnt >= (i.cfg_step_low & sat_) && r_.dir_pin == want_dir(i) &&
         r_.setup_cnt >= (i.cfg_dir_setup & sat_);
}

// ready_o = !rst && quiet && step_pol == cfg_step_pol
bool CpPulse::ready(const CpPulseIn& i) const { return !i.rst && quiet(i) && r_.step_pol == i.cfg_step_pol; }

CpPulseOut CpPulse::outputs() const {
  CpPulseOut o;
  o.ready = ready(in);
  // In reset: the parameter polarities' idle levels (STEP inactive, DIR logical 0).
  o.step = in.rst ? !p_.step_pol_reset : r_.step_pol == r_.active;
  o.dir = in.rst ? !p_.dir_pol_reset : r_.dir_pin;
  o.position = r_.position;
  o.busy = r_.active;
  return o;
}

void CpPulse::tick() {
  if (in.rst) {
    r_ = reset_state();
    return;
  }
  const Regs& q = r_;
  Regs d = q;
  const bool start = in.step && ready(in);
  // A new STEP polarity moves the pin where a pulse could start instead.
  const bool pol_change = quiet(in) && q.step_pol != in.cfg_step_pol;
  // The DIR pin moves once STEP has been inactive for dir_hold cycles; never together
  // with a STEP edge (a leading or polarity edge needs the DIR pin settled).
  const bool dir_change = !q.active && q.dir_pin != want_dir(in) && q.low_cnt >= (in.cfg_dir_hold & sat_);

  d.active = start || (q.active && q.high_cnt > 1);
  d.high_cnt = start ? (in.cfg_step_high & sat_) : ((q.high_cnt - 1) & sat_);
  d.low_cnt = d.active ? 0 : pol_change ? 1 : sat_inc(q.low_cnt);
  if (pol_change) d.step_pol = in.cfg_step_pol;
  if (dir_change) {
    d.dir_pin = want_dir(in);
    d.setup_cnt = 1;
  } else {
    d.setup_cnt = sat_inc(q.setup_cnt);
  }
  if (start) d.position = (q.position + (in.dir ? 1 : pos_mask_)) & pos_mask_;
  r_ = d;
}

uint64_t CpPulse::quiet_for(const CpPulseIn& i) const {
  const Regs& q = r_;
  if (i.rst || i.cfg_new) return 0;
  // This clock starts a pulse, moves the STEP polarity or the DIR pin: an event.
  if ((i.step && ready(i)) || (quiet(i) && q.step_pol != i.cfg_step_pol)) return 0;
  if (!q.active && q.dir_pin != want_dir(i) && q.low_cnt >= (i.cfg_dir_hold & sat_)) return 0;
  // A pulse under way: it ends in the clock high_cnt == 1.
  if (q.active) return q.high_cnt > 1 ? q.high_cnt - 1 : 0;
  // STEP inactive: low_cnt and setup_cnt count up to the thresholds that make
  // the timer ready or let DIR move.
  uint64_t h = kForever;
  const auto until = [&](uint32_t count, uint32_t threshold) {
    threshold &= sat_;
    if (count < threshold) h = std::min<uint64_t>(h, threshold - count);
  };
  until(q.low_cnt, i.cfg_step_low);
  until(q.low_cnt, i.cfg_dir_hold);
  until(q.setup_cnt, i.cfg_dir_setup);
  return h;
}

void CpPulse::skip(uint64_t cycles) {
  if (r_.active) r_.high_cnt = uint32_t(r_.high_cnt - cycles) & sat_;
  else r_.low_cnt = sat_add(r_.low_cnt, cycles);
  r_.setup_cnt = sat_add(r_.setup_cnt, cycles);
}

}  // namespace cpstep::model

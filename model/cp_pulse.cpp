#include "cp_pulse.h"

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
  return s;
}

// ready_o = !rst && !active && low_cnt >= step_low && dir_q == dir_i
//           && setup_cnt >= dir_setup
bool CpPulse::ready() const {
  return !in.rst && !r_.active && r_.low_cnt >= (in.cfg_step_low & sat_) && r_.dir == in.dir &&
         r_.setup_cnt >= (in.cfg_dir_setup & sat_);
}

CpPulseOut CpPulse::outputs() const {
  CpPulseOut o;
  o.ready = ready();
  // In reset: the parameter polarities' idle levels (STEP inactive, DIR logical 0).
  const bool step_pol = in.rst ? p_.step_pol_reset : in.cfg_step_pol;
  const bool dir_pol = in.rst ? p_.dir_pol_reset : in.cfg_dir_pol;
  const bool active = !in.rst && r_.active;
  const bool dir = !in.rst && r_.dir;
  o.step = step_pol ? active : !active;
  o.dir = dir_pol ? dir : !dir;
  o.position = r_.position;
  o.busy = r_.active || r_.dir != in.dir;
  return o;
}

void CpPulse::tick() {
  if (in.rst) {
    r_ = reset_state();
    return;
  }
  const Regs& q = r_;
  Regs d = q;
  const bool start = in.step && ready();
  // A DIR change needs the pin inactive for dir_hold cycles; it excludes start
  // (start needs dir_q == dir_i).
  const bool dir_change = !q.active && q.dir != in.dir && q.low_cnt >= (in.cfg_dir_hold & sat_);

  d.active = start || (q.active && q.high_cnt > 1);
  d.high_cnt = start ? (in.cfg_step_high & sat_) : ((q.high_cnt - 1) & sat_);
  d.low_cnt = d.active ? 0 : sat_inc(q.low_cnt);
  if (dir_change) {
    d.dir = in.dir;
    d.setup_cnt = 1;
  } else {
    d.setup_cnt = sat_inc(q.setup_cnt);
  }
  if (start) d.position = (q.position + (q.dir ? 1 : pos_mask_)) & pos_mask_;
  r_ = d;
}

}  // namespace cpstep::model

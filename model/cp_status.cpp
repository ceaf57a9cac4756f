// SPDX-License-Identifier: MIT
#include "model/cp_status.h"

#include <algorithm>

#include "model/bits.h"

namespace cpstep::model {
namespace {

constexpr uint32_t kCardId = 0x43505331;  // "CPS1"
// The command set, register map and SPI frames version (READ 0x23 [23:16]).
constexpr uint32_t kProtocolVersion = 2;

}  // namespace

FaultPick pick_fault(bool estop, bool abort, bool watchdog, bool limit, bool underrun, bool pattern,
                     bool cmd_fault, uint32_t cmd_code, bool run_conic) {
  if (estop) return {true, uint32_t(CoreError::estop)};
  if (abort) return {true, uint32_t(CoreError::abort)};
  if (watchdog) return {true, uint32_t(CoreError::watchdog)};
  if (limit) return {true, uint32_t(CoreError::limit)};
  if (underrun) return {true, uint32_t(run_conic ? CoreError::conic_end : CoreError::underrun)};
  if (pattern) return {true, uint32_t(CoreError::seg_pattern)};
  if (cmd_fault) return {true, cmd_code & 0xFF};
  return {};
}

CpStatus::CpStatus(Params p) : p_(p), mask_tw_(bits::mask(p.tw)) { r_ = reset_state(); }

CpStatus::Regs CpStatus::reset_state() const {
  Regs r;
  for (PulseConfig& c : r.cfg) {
    c.step_high = p_.step_high_reset & mask_tw_;
    c.step_low = p_.step_low_reset & mask_tw_;
    c.dir_setup = p_.dir_setup_reset & mask_tw_;
    c.dir_hold = p_.dir_hold_reset & mask_tw_;
    c.step_pol = p_.step_pol_reset;
    c.dir_pol = p_.dir_pol_reset;
  }
  return r;
}

uint32_t CpStatus::status_word(const In& i) const {
  const Regs& q = r_;
  const uint32_t chunks = std::min<uint32_t>(i.ch_level & bits::mask(p_.caw + 1), 255);
  const unsigned sqw = p_.saw + bits::clog2(p_.n + 1 + (p_.ptimer ? 1 : 0));
  const uint32_t segments =
      ((i.segq & bits::mask(sqw + 1)) + uint32_t(i.build_busy) + (i.run_level & 3) + uint32_t(i.cur_valid)) &
      0xFF;
  return chunks << 24 | segments << 16 | (q.err & 0xFF) << 8 | uint32_t(p_.feed && !(i.feed >> 30 & 1)) << 7 | (i.feed >> 31 & 1) << 6 |
         uint32_t(i.torch) << 5 | uint32_t(q.enable) << 4 |
         uint32_t(i.estop) << 3 | uint32_t(q.stretched) << 2 | uint32_t(q.fault) << 1 |
         uint32_t(i.running);
}

uint32_t CpStatus::read(const In& i, uint32_t reg) const {
  const Regs& q = r_;
  switch (reg & 0xFF) {
    case 0x00: return status_word(i);
    case 0x01: return q.stretch_count;
    case 0x02: return q.moves_done;
    case 0x03: return q.segments_done;
    case 0x1F: return kCardId;
    case 0x20: return (p_.tw & 0x1F) << 24 | (p_.saw & 0xF) << 20 | (p_.caw & 0xF) << 16 | (p_.kmax & 0xFF) << 8 |
                      (p_.n & 0xFF);
    case 0x21: return p_.w;
    case 0x22: return p_.umax;
    case 0x23: return uint32_t(p_.ptimer) << 26 | uint32_t(p_.feed) << 25 | uint32_t(p_.inputs) << 24 | kProtocolVersion << 16 | (p_.cbuf_aw & 0xFF) << 8 | (p_.pw & 0xFF);
    case 0x24: return p_.clock_hz;
    case 0x25: return p_.build_id;
    case 0x26: return p_.conic ? p_.ciw : 0;
    case 0x27: return (i.seek & 7) << 17 | uint32_t(i.probe) << 16 | (i.lim_max & 0xFF) << 8 | (i.lim_min & 0xFF);
    case 0x28: return (q.lim_max_at & 0xFF) << 8 | (q.lim_min_at & 0xFF);
    case 0x29: return i.feed;
    case 0x2A: return i.override & 0xFFFF;
    default: {
      const uint32_t r = reg & 0xFF;
      if (r >= 0x10 && r < 0x10 + p_.n) return uint32_t(i.position[r - 0x10]);
      return 0;
    }
  }
}

CpStatus::Out CpStatus::eval_outputs(const In& i) const {
  const Regs& q = r_;
  Out o;
  o.rd_data0 = read(i, i.rd_addr0);
  o.rd_data1 = read(i, i.rd_addr1);
  o.fault = q.fault;
  o.err = q.err;
  o.flush = flush(i);
  o.stretched = q.stretched;
  o.enable = q.enable;
  o.status = status_word(i);
  o.stretch_count = q.stretch_count;
  o.moves_done = q.moves_done;
  o.segments_done = q.segments_done;
  o.cfg = q.cfg;
  o.cfg_new = q.cfg_new;
  o.wd_trip = wd_trip(i.kick);
  return o;
}

uint64_t CpStatus::quiet_for(const In& i, uint64_t limit) const {
  if (i.rst || i.kick || i.cfg_write) return 0;
  Regs n = next(i);
  n.wd_count = r_.wd_count;
  if (!(n == r_)) return 0;
  // Off, or tripped and holding: the count stays. Else it counts up to the trip,
  // whose clock is clocked.
  if (r_.wd_limit == 0 || wd_at()) return limit;
  return std::min<uint64_t>(limit, (uint64_t(r_.wd_limit) << 12) - r_.wd_count);
}

void CpStatus::skip(uint64_t cycles) {
  if (r_.wd_limit != 0) r_.wd_count = uint32_t(std::min<uint64_t>(r_.wd_count + cycles, uint64_t(r_.wd_limit) << 12));
}

void CpStatus::tick() { r_ = in.rst ? reset_state() : next(in); }

CpStatus::Regs CpStatus::next(const In& i) const {
  const Regs& q = r_;
  Regs d = q;
  d.stretched = q.stretched || i.stretch;
  d.stretch_count = q.stretch_count + uint32_t(i.stretch);
  d.moves_done = q.moves_done + uint32_t(i.fire);
  d.segments_done = q.segments_done + uint32_t(i.seg_done);
  // The watchdog: no kick for its timeout trips it (the count holds there).
  const bool trip = wd_trip(i.kick);
  const bool wd_cfg = i.cfg_write && (i.cfg_word >> 20 & 0xF) == 5;
  if (i.kick || wd_cfg) d.wd_count = 1;
  else if (q.wd_limit != 0 && !wd_at()) d.wd_count = q.wd_count + 1;
  if (wd_cfg) d.wd_limit = i.cfg_word & 0xFFFF;
  // Drivers: off wins over on; E-stop and a tripped watchdog hold them off.
  if (i.drivers_on) d.enable = true;
  if (i.drivers_off || i.estop || trip) d.enable = false;
  // CLEAR drops what was latched before this cycle (a stretch in this very cycle
  // stays); then the first fault latches.
  // CLEAR does not clear an E-stop: only the out-of-band ACK does (input released).
  // Neither clears a fault whose flush is still pending (the segment under way has not
  // ended): the queues are flushed before the core takes segments again.
  const bool flush_pending = q.fault && !flush(i);
  const bool clearing =
      !i.estop && !flush_pending && ((i.clear && (q.err & 0xFF) != uint32_t(CoreError::estop)) || i.ack);
  if (clearing) {
    d.fault = false;
    d.err = 0;
    d.stretched = i.stretch;
  }
  const FaultPick f =
      pick_fault(i.estop, i.abort, trip, i.lim_hit, i.run_fault, i.build_fault, i.cmd_fault, i.cmd_code,
                 i.run_conic);
  if (f.set && (!q.fault || clearing)) {
    d.fault = true;
    d.err = f.code;
  }
  // The limits that stopped the run, kept while LIMIT is latched.
  if (f.set && (!q.fault || clearing) && f.code == uint32_t(CoreError::limit)) {
    d.lim_min_at = i.lim_min;
    d.lim_max_at = i.lim_max;
  } else if (clearing) {
    d.lim_min_at = d.lim_max_at = 0;
  }
  d.cfg_new = i.cfg_write;
  if (i.cfg_write) {
    const uint32_t word = i.cfg_word;
    const uint32_t axis = word >> 24 & 0xF;
    if (axis < p_.n) {
      PulseConfig& c = d.cfg[axis];
      const uint32_t value = word & mask_tw_;
      switch (word >> 20 & 0xF) {
        case 0: c.step_high = value; break;
        case 1: c.step_low = value; break;
        case 2: c.dir_setup = value; break;
        case 3: c.dir_hold = value; break;
        case 4:
          c.step_pol = (word & 1) != 0;
          c.dir_pol = (word >> 1 & 1) != 0;
          break;
        default: break;  // card-wide fields (5: the watchdog)
      }
    }
  }
  return d;
}

}  // namespace cpstep::model

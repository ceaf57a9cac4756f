// SPDX-License-Identifier: MIT
#include "model/cp_card.h"

#include <stdexcept>

namespace cpstep::model {

CpCard::CpCard(Params p) : p_(p), spi_({p.core.n, p.core.cbuf_aw, p.core.conic, p.core.ptimer}), core_(p.core) {
  if (p_.core.pw != 32) throw std::invalid_argument("cp_card: the card's positions are 32 bits (PW = 32)");
}

const CpCoreOut& CpCard::core_outputs() const {
  if (core_valid_ && core_.in.rst == in.rst) {
    if (rd_stale_) {
      // clock_front_end moved the read port's address; the rest holds.
      core_.in.rd_addr = spi_.rd_addr();
      core_out_.rd_data = core_.read_port(core_.in.rd_addr);
      rd_stale_ = false;
    }
    return core_out_;
  }
  CpCoreIn& c = core_.in;
  c.rst = in.rst;
  c.cmd_valid = spi_.cmd_valid();
  c.cmd_data = spi_.cmd_data();
  c.rsp_ready = true;  // cp_spi takes every READ reply
  c.estop = estop_synced();
  {
    const unsigned n = p_.core.n;
    const uint32_t m = (1u << n) - 1;
    c.lim_min = in_q1_ & m;
    c.lim_max = in_q1_ >> n & m;
    c.probe = (in_q1_ >> (2 * n) & 1) != 0;
  }
  const uint32_t ctl = spi_.ctl();  // an URGENT frame's START / STOP, at its CS rise
  c.ctl_start = (ctl & 1) != 0;
  c.ctl_stop = (ctl & 2) != 0;
  c.ctl_flush = (ctl & 4) != 0;
  c.ctl_ack = (ctl & 8) != 0;
  c.kick = (ctl & 16) != 0;
  c.ctl_hold = (ctl & 32) != 0;
  c.ctl_resume = (ctl & 64) != 0;
  c.ctl_ovr = (ctl & 128) != 0;
  c.ctl_ovr_val = spi_.ctl_ovr_val();
  c.rd_addr = spi_.rd_addr();
  core_out_ = core_.outputs();
  core_valid_ = true;
  rd_stale_ = false;
  return core_out_;
}

CpCard::Out CpCard::outputs() const {
  const CpCoreOut& c = core_outputs();
  Out o;
  o.miso = spi_.miso();
  o.miso_oe = !in.cs_n;
  o.step = c.step;
  o.dir = c.dir;
  o.torch = c.torch;
  o.enable = c.enable;
  o.running = c.running;
  o.fault = c.fault;
  o.stretched = c.stretched;
  o.err_code = c.err_code;
  for (unsigned a = 0; a < p_.core.n; ++a) o.position[a] = int32_t(uint32_t(c.position[a]));
  return o;
}

uint64_t CpCard::quiet_for(uint64_t limit) const {
  if (in.rst || !pins_settled() || !spi_.buffer_settled()) return 0;
  if (core_outputs().rsp_valid) return 0;  // cp_spi counts the reply and keeps its register
  // core_outputs() left the core's inputs as this clock has them.
  return core_.quiet_for(limit);
}

void CpCard::skip(uint64_t cycles) {
  core_.skip(cycles);
  core_valid_ = false;
}

bool CpCard::clock_front_end(uint64_t cycles, bool* miso) {
  if (in.rst || in.cs_n || cycles == 0 || !spi_.cs_low_settled() || !slow_pins_settled(in) ||
      !spi_.buffer_settled())
    return false;
  const CpCoreOut& c = core_outputs();
  if (c.rsp_valid || core_.quiet_for(cycles) < cycles) return false;
  if (miso) *miso = spi_.miso();
  CpSpiIn& s = spi_.in;
  s.rst = false;
  s.sck = in.sck;
  s.cs_n = in.cs_n;
  s.mosi = in.mosi;
  s.cmd_ready = c.cmd_ready;
  s.rsp_valid = false;
  s.rsp_addr = c.rsp_addr;
  s.estop = estop_synced();
  s.enable = c.enable;
  for (uint64_t k = 0; k < cycles; ++k) {
    // Once the synchronizers hold the pins, nothing in the front end moves.
    if (spi_.pins_settled(false, in.sck, in.cs_n, in.mosi)) break;
    if (spi_.tick_synchronizers_only()) continue;
    if (spi_.loads_rd_data()) s.rd_data = core_.read_port(spi_.rd_addr());
    spi_.tick();
  }
  core_.skip(cycles);
  // Still quiet with the same inputs: the same outputs, but for the read port,
  // whose address the front end has moved (read when asked: core_outputs()).
  if (core_.quiet_for(1) > 0) rd_stale_ = true;
  else core_valid_ = false;
  return true;
}

size_t CpCard::clock_front_end(const CpPinPhase* phases, size_t n, uint8_t* miso) {
  if (n == 0) return 0;
  in = phases[0].pins;
  if (in.rst || in.cs_n || !spi_.cs_low_settled() || !slow_pins_settled(in) || !spi_.buffer_settled())
    return 0;
  const CpCoreOut& c = core_outputs();
  if (c.rsp_valid) return 0;
  const uint64_t budget = core_.quiet_for(~uint64_t(0));
  CpSpiIn& s = spi_.in;
  s.rst = false;
  s.cs_n = false;
  s.cmd_ready = c.cmd_ready;
  s.rsp_valid = false;
  s.rsp_addr = c.rsp_addr;
  s.estop = estop_synced();
  s.enable = c.enable;
  const CpCardIn slow = in;  // its E-stop and inputs: a phase that changes them ends the run of phases
  uint64_t total = 0;
  size_t k = 0;
  for (; k < n; ++k) {
    const CpPinPhase& ph = phases[k];
    if (ph.pins.rst || ph.pins.cs_n || ph.pins.estop != slow.estop || ph.pins.lim_min != slow.lim_min ||
        ph.pins.lim_max != slow.lim_max || ph.pins.probe != slow.probe || ph.cycles > budget - total)
      break;
    const bool settled = spi_.pins_settled(false, s.sck, false, s.mosi);
    miso[k] = spi_.miso();
    if (settled && ph.cycles >= 3 && spi_.settled_phase(ph.pins.sck, ph.pins.mosi)) {
      total += ph.cycles;  // (the phase at once: no word ends in it)
      continue;
    }
    s.sck = ph.pins.sck;
    s.mosi = ph.pins.mosi;
    if (settled && ph.cycles >= 3) {
      // Pins that change after settling: two clocks that only move the
      // synchronizers, then the one the change reaches the frame logic in; then
      // every stage holds the pins, and the rest of the phase changes nothing.
      spi_.shift_synchronizers(2);
      if (!spi_.tick_synchronizers_only() && !spi_.tick_shift_only()) {
        if (spi_.loads_rd_data()) s.rd_data = core_.read_port(spi_.rd_addr());
        spi_.tick();
      }
      total += ph.cycles;
      continue;
    }
    for (uint64_t i = 0; i < ph.cycles; ++i) {
      if (spi_.pins_settled(false, s.sck, false, s.mosi)) break;
      if (spi_.tick_synchronizers_only()) continue;
      if (spi_.loads_rd_data()) s.rd_data = core_.read_port(spi_.rd_addr());
      spi_.tick();
    }
    total += ph.cycles;
  }
  if (k == 0) return 0;
  in = phases[k - 1].pins;
  core_.skip(total);
  if (core_.quiet_for(1) > 0) rd_stale_ = true;
  else core_valid_ = false;
  return k;
}

void CpCard::tick() {
  const CpCoreOut& c = core_outputs();
  CpSpiIn& s = spi_.in;
  s.rst = in.rst;
  s.sck = in.sck;
  s.cs_n = in.cs_n;
  s.mosi = in.mosi;
  s.cmd_ready = c.cmd_ready;
  s.rsp_valid = c.rsp_valid;
  s.rsp_addr = c.rsp_addr;
  s.rd_data = c.rd_data;
  s.estop = estop_synced();
  s.enable = c.enable;
  core_.tick();
  spi_.tick();
  estop_q_ = (estop_q_ << 1 | uint32_t(in.estop)) & 3;
  in_q1_ = in_q0_;
  in_q0_ = in_word(in);
  core_valid_ = false;
}

}  // namespace cpstep::model

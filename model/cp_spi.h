// SPDX-License-Identifier: MIT
// cp_spi — cycle-accurate, bit-exact model of rtl/cp_spi.v, the card's SPI front
// end: the pin synchronizers, the frame receiver (phases, CRC, command tracking),
// the reply shifter and the command buffer (a CpFifo, as the RTL's cp_fifo) with
// its commit or rollback at CS rise (docs/PROTOCOL.md).
// Same ports as the RTL; the bench sets `in`, reads outputs() (before the rising
// edge), then calls tick() (the edge).
#pragma once

#include <cstdint>

#include "model/cp_fifo.h"

namespace cpstep::model {

struct CpSpiParams {
  unsigned n = 4;        // axes: the reply carries n positions, a SEGMENT 2 + n + ... words
  unsigned cbuf_aw = 9;  // command buffer address width: it holds 2^cbuf_aw words
  bool conic = false;    // CONIC commands (opcode 5) framed whole; else refused (BAD_COMMAND)
  // Moves timed by the phase timer (rtl/cp_spi.v's PTIMER): segments carry their axis
  // form's v words and L, no chunks; PHASE (opcode 6) framed whole; else refused.
  bool ptimer = false;
};

struct CpSpiIn {
  bool rst = false;
  // The SPI pins (asynchronous to the clock).
  bool sck = false, cs_n = true, mosi = false;
  // The core's command port and read port.
  bool cmd_ready = false;
  bool rsp_valid = false;
  uint32_t rsp_addr = 0;  // 8 bits
  uint32_t rd_data = 0;   // the core's register rd_addr, now
  // What the reply reports (estop already synchronized).
  bool estop = false, enable = false;
};

struct CpSpiOut {
  bool miso = false, miso_oe = false;
  bool cmd_valid = false;
  uint32_t cmd_data = 0;
  bool rsp_ready = false;
  uint32_t rd_addr = 0;  // 8 bits
  // An URGENT frame accepted at this CS rise: its START and STOP (docs/PROTOCOL.md).
  bool ctl_start = false, ctl_stop = false, ctl_flush = false, ctl_ack = false;
  // Its HOLD, RESUME, OVERRIDE (FEED builds), and the override's value (Q2.14, the
  // last URGENT word's [31:16]).
  bool ctl_hold = false, ctl_resume = false, ctl_ovr = false;
  uint32_t ctl_ovr_val = 0;
  // A whole frame with a good CRC ended at this CS rise: the core's watchdog kick.
  bool frame_ok = false;
};

class CpSpi {
 public:
  using Params = CpSpiParams;
  using In = CpSpiIn;
  using Out = CpSpiOut;

  explicit CpSpi(Params p = {});
  In in;
  Out outputs() const;
  void tick();

  const Params& params() const { return p_; }

  // Registered outputs (no input reaches them), for the card's settle order.
  bool miso() const { return (r_.sr >> 31 & 1) != 0; }
  bool cmd_valid() const { return cbuf_.out_valid(); }
  uint32_t cmd_data() const { return uint32_t(cbuf_.out_word0()); }
  uint32_t rd_addr() const;
  // An URGENT frame's word [3:0] in the cycle its CS rise accepts it, bit 4 in the
  // cycle of the CS rise ending any whole frame with a good CRC, and the word's
  // [6:4] (HOLD, RESUME, OVERRIDE) as bits 7:5 when accepted, else 0 (registered
  // state only: rtl/cp_spi.v ctl_start_o .. ctl_ovr_o, frame_ok_o).
  uint32_t ctl() const;
  // The last URGENT word's [31:16] (rtl/cp_spi.v ctl_ovr_val_o).
  uint32_t ctl_ovr_val() const { return r_.uw >> 7 & 0xFFFF; }
  // Every synchronizer stage holds what the current inputs load into it: another
  // cycle with the same pins changes no synchronizer (with rst: the reset values).
  bool pins_settled() const { return pins_settled(in.rst, in.sck, in.cs_n, in.mosi); }
  // The same for the pins given (a parent's inputs before it sets `in`).
  bool pins_settled(bool rst, bool sck, bool cs_n, bool mosi) const {
    const uint32_t sck_q = rst ? 0 : (sck ? 7 : 0);
    const uint32_t cs_q = rst ? 7 : (cs_n ? 7 : 0);
    return r_.sck == sck_q && r_.cs == cs_q && r_.mosi == (mosi ? 3u : 0u);
  }
  // No committed word is on its way to the buffer's head (cp_fifo's prefetch):
  // with the pins settled, no READ reply and no word taken, a clock changes
  // nothing here (the event-skipping card's test, CpCard::quiet_for).
  bool buffer_settled() const { return cbuf_.still(CpFifoIn{}); }
  // The fast engine's frames (CpCard::clock_front_end: no READ reply, no word
  // taken, the buffer settled). tick_synchronizers_only(): when this clock, with
  // the pins in `in`, reaches the frame logic with no CS edge and no SCK rise, it
  // only moves the synchronizers: done so, cheaply, and true; false (nothing
  // done) when it needs tick(). loads_rd_data(): a tick() now ends a word and
  // loads rd_data as the next reply word.
  bool tick_synchronizers_only();
  // A clock that shifts a bit in and out without ending a word (31 of 32), done
  // cheaply: true; false (nothing done) for any other clock. For the same callers
  // (no reply, no word taken, the buffer settled): nothing else happens in it.
  bool tick_shift_only();
  // `clocks` such clocks at once, for a caller that knows none of them brings a
  // CS edge or an SCK rise to the frame logic (pins settled before they changed).
  void shift_synchronizers(unsigned clocks);
  // A whole phase of 3 clocks or more with the pins `sck`, `mosi` (CS low), for
  // the same callers, from synchronizers settled with CS low: the first two
  // clocks only move the synchronizers, the third brings the change to the
  // frame logic, the rest change nothing. Done at once, with the synchronizers
  // left settled, and true, when the third clock is an SCK rise that shifts a
  // bit without ending a word or no SCK rise at all; false (nothing done) when
  // it ends a word (tick() then). The fast engine's step for one SCK phase.
  bool settled_phase(bool sck, bool mosi) {
    const bool rise = sck && r_.sck == 0;
    if (rise) {
      if (r_.bit == 31) return false;
      shift_in(mosi);  // the new MOSI: both its synchronizer stages hold it by then
    }
    r_.sck = sck ? 7 : 0;
    r_.mosi = mosi ? 3 : 0;
    in.sck = sck;
    in.mosi = mosi;
    return true;
  }
  bool loads_rd_data() const { return (r_.sck & 6) == 2 && (r_.cs & 6) == 0 && r_.bit == 31; }
  // CS has been low through every synchronizer stage: no CS edge is on its way
  // (with the pin held low, no frame can end, so nothing commits).
  bool cs_low_settled() const { return r_.cs == 0; }
  // Words in the command buffer, committed or not (cp_fifo's used_o).
  uint32_t cbuf_used() const { return cbuf_.used(); }

 private:
  // Receive phases (rtl/cp_spi.v): the header word, the command words, the CRC, done.
  static constexpr uint32_t kPhaseHeader = 0, kPhaseWords = 1, kPhaseCrc = 2, kPhaseDone = 3;
  // CRC-16/CCITT-FALSE, one bit: polynomial 0x1021, MSB first.
  static uint32_t crc_bit(uint32_t crc, bool b) {
    const bool top = (crc >> 15 & 1) != 0;
    return ((crc << 1) & 0xFFFF) ^ (top != b ? 0x1021u : 0u);
  }

  // The frame logic's shift of a bit that does not end its word (tick()'s
  // shift branch for bits 0..30), the synchronizers left alone.
  void shift_in(bool bit_in) {
    Regs& q = r_;
    const uint32_t rx_word = q.sr << 1 | uint32_t(bit_in);
    if (q.ph != kPhaseDone) q.crc_rx = crc_bit(q.crc_rx, bit_in);
    if (q.txn <= tx_crc_) q.crc_tx = crc_bit(q.crc_tx, (q.sr >> 31 & 1) != 0);
    if (q.bit == 15) {
      if (q.ph == kPhaseHeader) q.seq = rx_word & 0xFF;
      else if (q.ph == kPhaseCrc) q.ph = kPhaseDone;
    }
    q.sr = rx_word;
    q.bit = q.bit + 1;
  }

  // The registers of rtl/cp_spi.v (the command buffer is cbuf_).
  struct Regs {
    uint32_t sck = 0, cs = 7, mosi = 0;  // synchronizers: [0] first flop, [1] second, [2] previous
    // Control (reset).
    uint32_t seq = 0, result = 0;
    bool fresh = true;
    uint32_t reads = 0;
    uint32_t last_addr = 0xFF;
    // Frame state (initialized at CS fall).
    uint32_t ph = 0, bit = 0, txn = 0, crc_rx = 0, crc_tx = 0, left = 0;
    bool wr_ok = false, bad_type = false, no_room = false, bad_cmd = false;
    uint32_t hdr_left = 0, chunks_left = 0, cw = 0;
    bool seg_add2 = false;
    bool urg = false;  // an URGENT frame: its one word is not a command
    uint32_t uw = 0;   // its word's {[31:16], [6:0]}
    uint32_t sr = 0;
  };

  Params p_;
  uint32_t tx_crc_, tx_zero_;  // reply word indices of the CRC and of the zeros
  Regs r_;
  CpFifo cbuf_;
};

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
#include "model/cp_spi.h"

#include <bit>
#include <stdexcept>

namespace cpstep::model {
namespace {

constexpr uint32_t kMagic = 0xC5;
constexpr uint32_t kTypePoll = 0x00, kTypeCommands = 0x01, kTypeUrgent = 0x02;

// Result codes (docs/PROTOCOL.md).
constexpr uint32_t kOk = 0, kTruncated = 1, kBadCrc = 2, kBadType = 3, kNoRoom = 4, kBadCmd = 5, kSplit = 6;


constexpr uint32_t kTxPos0 = 7;  // reply word of the first position

}  // namespace

CpSpi::CpSpi(Params p) : p_(p), tx_crc_((kTxPos0 + p.n) & 31), tx_zero_((8 + p.n) & 31), cbuf_({32, p.cbuf_aw}) {
  if (p_.n < 1 || p_.n > 8) throw std::invalid_argument("cp_spi: N must be 1 to 8");
  if (p_.cbuf_aw < 1 || p_.cbuf_aw > 14) throw std::invalid_argument("cp_spi: CBUF_AW must be 1 to 14");
}

uint32_t CpSpi::rd_addr() const {
  // Registers 0x00..0x03, the one the last READ named, 0x10 + i; 0xFF reads 0.
  const uint32_t t = r_.txn;
  if (t >= 2 && t <= 5) return t - 2;
  if (t == 6) return r_.last_addr;
  if (t >= kTxPos0 && t < tx_crc_) return (0x10 + ((t - kTxPos0) & 31)) & 0xFF;
  return 0xFF;
}

CpSpi::Out CpSpi::outputs() const {
  const CpFifoOut b = cbuf_.outputs();
  Out o;
  o.miso = miso();
  // The raw pin: released at once when CS rises.
  o.miso_oe = !in.cs_n;
  o.cmd_valid = b.out_valid;
  o.cmd_data = uint32_t(b.out_data[0]);
  o.rsp_ready = true;
  o.rd_addr = rd_addr();
  const uint32_t c = ctl();
  o.ctl_start = (c & 1) != 0;
  o.ctl_stop = (c & 2) != 0;
  o.ctl_flush = (c & 4) != 0;
  o.ctl_ack = (c & 8) != 0;
  o.frame_ok = (c & 16) != 0;
  o.ctl_hold = (c & 32) != 0;
  o.ctl_resume = (c & 64) != 0;
  o.ctl_ovr = (c & 128) != 0;
  o.ctl_ovr_val = ctl_ovr_val();
  return o;
}

uint32_t CpSpi::ctl() const {
  const Regs& q = r_;
  const bool cs_rise = (q.cs >> 1 & 1) && !(q.cs >> 2 & 1);
  if (!cs_rise) return 0;
  // Bit 4: a whole frame with a good CRC (the watchdog's kick), whatever its result.
  const bool whole = q.ph == kPhaseDone && q.crc_rx == 0;
  const uint32_t kick = whole ? 16 : 0;
  if (!q.urg) return kick;
  const bool in_cmd = q.hdr_left != 0 || q.chunks_left != 0;
  const bool ok = whole && !q.bad_type && !q.no_room && !q.bad_cmd && !in_cmd;
  return kick | (ok ? (q.uw & 15) | (q.uw >> 4 & 7) << 5 : 0);
}

bool CpSpi::tick_synchronizers_only() {
  const Regs& q = r_;
  if (in.rst || in.rsp_valid) return false;
  const uint32_t cs12 = q.cs >> 1 & 3;
  if (cs12 == 1 || cs12 == 2) return false;          // a CS edge (fall or rise)
  if ((q.sck & 6) == 2 && cs12 == 0) return false;   // an SCK rise in a frame: a shift
  r_.mosi = (q.mosi << 1 | uint32_t(in.mosi)) & 3;
  r_.sck = (q.sck << 1 | uint32_t(in.sck)) & 7;
  r_.cs = (q.cs << 1 | uint32_t(in.cs_n)) & 7;
  return true;
}

bool CpSpi::tick_shift_only() {
  Regs& q = r_;
  if (in.rst || in.rsp_valid || (q.cs & 6) != 0 || (q.sck & 6) != 2 || q.bit == 31) return false;
  shift_in((q.mosi >> 1 & 1) != 0);
  q.mosi = (q.mosi << 1 | uint32_t(in.mosi)) & 3;
  q.sck = (q.sck << 1 | uint32_t(in.sck)) & 7;
  q.cs = (q.cs << 1 | uint32_t(in.cs_n)) & 7;
  return true;
}

void CpSpi::shift_synchronizers(unsigned clocks) {
  for (unsigned k = 0; k < clocks; ++k) {
    r_.mosi = (r_.mosi << 1 | uint32_t(in.mosi)) & 3;
    r_.sck = (r_.sck << 1 | uint32_t(in.sck)) & 7;
    r_.cs = (r_.cs << 1 | uint32_t(in.cs_n)) & 7;
  }
}

void CpSpi::tick() {
  const Regs& q = r_;
  const uint32_t used = cbuf_.used();
  const uint32_t words = 1u << p_.cbuf_aw;

  const bool cs1 = (q.cs >> 1 & 1) != 0, cs2 = (q.cs >> 2 & 1) != 0;
  const bool cs_fall = !cs1 && cs2;
  const bool cs_rise = cs1 && !cs2;
  const bool shift = (q.sck >> 1 & 1) && !(q.sck >> 2 & 1) && !cs1 && !cs2;
  const bool bit_in = (q.mosi >> 1 & 1) != 0;

  // Free words: 2^CBUF_AW minus every word held (the head included).
  const uint32_t free16 = used >= words ? 0 : words - used;
  const uint32_t rx_word = q.sr << 1 | uint32_t(bit_in);
  const uint32_t crc_tx_next = crc_bit(q.crc_tx, (q.sr >> 31 & 1) != 0);
  const bool in_cmd = q.hdr_left != 0 || q.chunks_left != 0;
  const bool word_end = shift && q.bit == 31;

  // The reply word loaded at the end of the current one.
  uint32_t tx_word;
  if (q.txn == 1) tx_word = free16 << 16 | q.reads;
  else if (q.txn == tx_crc_) tx_word = crc_tx_next << 16;
  else tx_word = in.rd_data;

  Regs d = q;
  d.reads = in.rsp_valid ? (q.reads + 1) & 0xFFFF : q.reads;
  bool buf_wr = false, buf_commit = false, buf_rollback = false;

  if (cs_fall) {
    // A frame begins: the reply's word 0 goes out at once.
    d.sr = kMagic << 24 | q.seq << 16 | q.result << 8 | uint32_t(q.fresh) << 3 | uint32_t(in.enable) << 2 |
           uint32_t(in.estop) << 1 | uint32_t(used != 0);
    d.ph = kPhaseHeader;
    d.bit = 0;
    d.txn = 1;
    d.crc_rx = d.crc_tx = 0xFFFF;
    d.wr_ok = d.bad_type = d.no_room = d.bad_cmd = false;
    d.hdr_left = 0;
    d.chunks_left = 0;
    d.cw = 0;
    d.urg = false;
  } else if (shift) {
    d.bit = (q.bit + 1) & 31;
    if (q.ph != kPhaseDone) d.crc_rx = crc_bit(q.crc_rx, bit_in);
    if (q.txn <= tx_crc_) d.crc_tx = crc_tx_next;
    if (word_end) {
      // The received word comes off the register, the next reply word goes on.
      d.sr = tx_word;
      if (q.txn != tx_zero_) d.txn = (q.txn + 1) & 31;
    } else {
      d.sr = rx_word;
    }

    switch (q.ph) {
      case kPhaseHeader:
        if (q.bit == 15) d.seq = rx_word & 0xFF;
        if (word_end) {
          // {type, seq, nwords}; room is judged against reply word 1's free words.
          const uint32_t type = rx_word >> 24, nwords = rx_word & 0xFFFF;
          d.left = nwords;
          d.bad_type = !(type == kTypeCommands || (type == kTypePoll && nwords == 0) ||
                         (type == kTypeUrgent && nwords == 1));
          d.urg = type == kTypeUrgent;
          d.no_room = type == kTypeCommands && nwords > free16;
          d.wr_ok = type == kTypeCommands && nwords <= free16;
          d.ph = nwords == 0 ? kPhaseCrc : kPhaseWords;
        }
        break;
      case kPhaseWords:
        if (word_end) {
          buf_wr = q.wr_ok;
          d.left = (q.left - 1) & 0xFFFF;
          if (q.left == 1) d.ph = kPhaseCrc;
          if (q.urg) {
            // An URGENT frame's word: not a command, kept for its CS rise.
            d.uw = (rx_word >> 16) << 7 | (rx_word & 0x7F);
          } else if (!in_cmd) {
            // A command starts: a SEGMENT has H1, N v words and its chunks to come,
            // a CONIC also K0..K6 before its chunks.
            switch (rx_word >> 28) {
              case 0x1:
              case 0x5:
                if ((rx_word >> 28) == 0x5 && !p_.conic) {
                  d.bad_cmd = true;
                  break;
                }
                if (p_.ptimer) {
                  // H1, the axis form's v words (every axis's, or those of the mask
                  // H0[7:0] with H0[15]), a CONIC's K words, L; no chunks.
                  const uint32_t v = (rx_word >> 15 & 1) ? uint32_t(std::popcount(rx_word & 0xFFu)) : p_.n;
                  const uint32_t k = (rx_word >> 28) != 0x5 ? 0 : (rx_word >> 18 & 1) ? 2 : 7;
                  d.hdr_left = (2 + v + k) & 31;
                  d.chunks_left = 0;
                } else {
                  // A CONIC also carries K0..K6 (K5, K6 with H0[18], a continuation).
                  d.hdr_left = ((rx_word >> 28) == 0x5 ? ((rx_word >> 18 & 1) ? 3 + p_.n : 8 + p_.n) : 1 + p_.n) & 31;
                  d.chunks_left = rx_word & 0xFFFF;
                }
                d.seg_add2 = (rx_word >> 22 & 1) != 0;
                d.cw = 0;
                break;
              case 0x6:
                // PHASE: u, r's two words with H0[24], S and H's four with H0[27].
                if (p_.ptimer)
                  d.hdr_left = 1 + ((rx_word >> 24 & 1) ? 2 : 0) + ((rx_word >> 27 & 1) ? 4 : 0);
                else
                  d.bad_cmd = true;
                break;
              case 0x2:
              case 0x3:
              case 0x4: break;
              default: d.bad_cmd = true;
            }
          } else if (q.hdr_left != 0) {
            d.hdr_left = q.hdr_left - 1;
          } else if (q.cw == (q.seg_add2 ? 2u : 1u)) {
            d.cw = 0;
            d.chunks_left = (q.chunks_left - 1) & 0xFFFF;
          } else {
            d.cw = (q.cw + 1) & 3;
          }
        }
        break;
      case kPhaseCrc:
        if (q.bit == 15) d.ph = kPhaseDone;
        break;
      default: break;
    }
  }

  if (cs_rise) {
    // The frame ends: the first failing check is its result.
    if (q.ph != kPhaseDone) d.result = kTruncated;
    else if (q.crc_rx != 0) d.result = kBadCrc;
    else if (q.bad_type) d.result = kBadType;
    else if (q.no_room) d.result = kNoRoom;
    else if (q.bad_cmd) d.result = kBadCmd;
    else if (in_cmd) d.result = kSplit;
    else d.result = kOk;
    buf_commit = d.result == kOk;
    buf_rollback = d.result != kOk;
    d.fresh = false;
  }

  // Synchronizers.
  d.mosi = (q.mosi << 1 | uint32_t(in.mosi)) & 3;
  if (in.rst) {
    d.sck = 0;
    d.cs = 7;
    d.seq = 0;
    d.result = kOk;
    d.fresh = true;
    d.reads = 0;
    d.last_addr = 0xFF;
  } else {
    d.sck = (q.sck << 1 | uint32_t(in.sck)) & 7;
    d.cs = (q.cs << 1 | uint32_t(in.cs_n)) & 7;
    if (in.rsp_valid) d.last_addr = in.rsp_addr & 0xFF;
  }

  CpFifoIn& f = cbuf_.in;
  f.rst = in.rst;
  f.clear = (ctl() & 4) != 0;  // an URGENT FLUSH empties the buffer
  f.wr = buf_wr;
  f.wr_data[0] = rx_word;
  f.commit = buf_commit;
  f.rollback = buf_rollback;
  f.out_ready = in.cmd_ready;
  if (!cbuf_.still(f)) cbuf_.tick();  // (a clock that changes nothing there is left out)
  r_ = d;
}

}  // namespace cpstep::model

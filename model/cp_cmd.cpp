// SPDX-License-Identifier: MIT
#include "model/cp_cmd.h"

#include "model/bits.h"

namespace cpstep::model {
namespace {

constexpr uint32_t kOpSegment = 0x1, kOpConfig = 0x2, kOpControl = 0x3, kOpRead = 0x4, kOpConic = 0x5;
constexpr uint32_t kOpPhase = 0x6;
constexpr uint64_t kMask34 = (uint64_t(1) << 34) - 1;  // the count sum's width

// Chunk queue word (81 bits): interval, add, count, add2, and the flag of a
// segment's last chunk.
FifoWord chunk_word(uint32_t interval, uint32_t add, uint32_t count, uint32_t add2, bool last) {
  return {uint64_t(count & 0xFFFF) << 48 | uint64_t(add & 0xFFFF) << 32 | interval,
          uint64_t(add2 & 0xFFFF) | uint64_t(last) << 16, 0, 0};
}

}  // namespace

CpCmd::CpCmd(Params p) : p_(p), mask_tw_(bits::mask(p.tw)) {}

// A ptimer segment's axis form H0[15:0]: 0 (every axis's v sent), or {1, 000,
// major valid, major, sent[7:0]} naming only axes below N, the major one not sent.
bool CpCmd::form_ok(uint32_t form) const {
  if (form == 0) return true;
  const uint32_t sent = form & 0xFF, major = form >> 8 & 7;
  const bool has_major = (form >> 11 & 1) != 0;
  return (form >> 15 & 1) && (form >> 12 & 7) == 0 && (sent >> p_.n) == 0 &&
         !(has_major && (major >= p_.n || (sent >> major & 1)));
}

// In seg_v: whether this axis's v comes as a word (always, but in the compact form).
bool CpCmd::v_sent() const {
  return !(p_.ptimer && (r_.chunks_left >> 15 & 1)) || (r_.chunks_left >> r_.v_index & 1);
}

bool CpCmd::ready(const In& i) const {
  const bool keep = !r_.discard && !i.fault;
  switch (r_.parse) {
    case Parse::command:
    case Parse::chunk_interval: return true;
    case Parse::seg_v: return v_sent() && (!keep || !i.seg_full);
    case Parse::seg_h1:
    case Parse::conic_words:
    case Parse::seg_length: return !keep || !i.seg_full;
    case Parse::phase_words: return !keep || !i.ch_full;
    case Parse::chunk_count: return r_.seg_add2 || !keep || !i.ch_full;
    case Parse::chunk_add2: return !keep || !i.ch_full;
    default: return false;  // checking a chunk, or a reply waits
  }
}

// The chunk check's verdict on a chunk (docs/CORE.md "Chunk check"): the last
// increment add + (count-2)·add2 (no add2 term when count < 2) must not have the
// opposite sign of add; the last delay interval + (count-1)·(add + last
// increment)/2 must be 1 .. 2^32-1. Exact in 64 bits: |products| < 2^47.
CoreError CpCmd::chunk_verdict(const Regs& q) {
  const int64_t add = bits::sext16(q.add);
  const int64_t m1 = q.count < 2 ? 0 : int64_t(q.count) - 2;
  const int64_t m2 = int64_t((q.count - 1) & 0xFFFF);
  const int64_t last_inc = add + m1 * bits::sext16(q.add2);
  if ((add > 0 && last_inc < 0) || (add < 0 && last_inc > 0)) return CoreError::seg_add2;
  const int64_t last_delay = int64_t(q.interval) + m2 * (add + last_inc) / 2;  // the product is even
  if (last_delay <= 0 || last_delay > int64_t(0xFFFFFFFF)) return CoreError::seg_delay;
  return CoreError::none;
}

CpCmd::Out CpCmd::eval(const In& i, Regs& d) const {
  const Regs& q = r_;
  Out o;
  o.cmd_ready = ready(i);
  o.rsp_valid = q.rsp_valid;
  o.rsp_data = q.rsp_valid ? q.rsp_data : 0;
  o.rsp_addr = q.rsp_valid ? q.rsp_addr : 0;
  d.rsp_valid = q.rsp_valid && !i.rsp_ready;

  const bool take = i.cmd_valid && o.cmd_ready;
  const uint32_t word = i.cmd_data;
  const bool keep = !q.discard && !i.fault;  // the segment being read is still good
  auto refuse = [&](CoreError e) {
    o.fault = true;
    o.fault_code = uint32_t(e);
  };
  switch (q.parse) {
    case Parse::command: {
      if (!take) break;
      switch (word >> 28) {
        case kOpConic:
          if (!p_.conic) {
            refuse(CoreError::bad_opcode);
            break;
          }
          [[fallthrough]];
        case kOpSegment:
          // A CONIC header: [26] clockwise, [25:23] axis u, [21:19] axis v; no k.
          d.hdr_conic = (word >> 28) == kOpConic;
          d.hdr_end = (word >> 27 & 1) != 0;
          d.hdr_out = (word >> 16 & 1) != 0;
          d.hdr_k = d.hdr_conic ? 0 : word >> 23 & 0xF;
          d.chunks_left = word & 0xFFFF;
          d.seg_add2 = (word >> 22 & 1) != 0;
          d.hdr_cw = (word >> 26 & 1) != 0;
          d.hdr_au = word >> 23 & 7;
          d.hdr_av = word >> 19 & 7;
          d.hdr_cont = d.hdr_conic && (word >> 18 & 1) != 0;
          d.count_sum = 0;
          d.discard = i.fault;
          if (!i.fault) {
            if (d.hdr_k > p_.kmax) {
              refuse(CoreError::seg_k);
              d.discard = true;
            } else if (!p_.ptimer && (d.chunks_left == 0 || d.chunks_left > (1u << p_.caw))) {
              refuse(CoreError::seg_chunks);
              d.discard = true;
            } else if (p_.ptimer && !form_ok(d.chunks_left)) {
              refuse(CoreError::seg_form);
              d.discard = true;
            } else if (d.hdr_conic && (d.hdr_au == d.hdr_av || d.hdr_au >= p_.n || d.hdr_av >= p_.n)) {
              refuse(CoreError::conic_axes);
              d.discard = true;
            } else if (d.hdr_cont && !(q.lc_valid && q.lc_au == d.hdr_au && q.lc_av == d.hdr_av && q.lc_cw == d.hdr_cw)) {
              refuse(CoreError::conic_cont);
              d.discard = true;
            }
          }
          d.parse = Parse::seg_h1;
          break;
        case kOpPhase:
          if (!p_.ptimer) {
            refuse(CoreError::bad_opcode);
            break;
          }
          // W0 = {kind, 4 zeros, ticks} kept for the end; u next.
          d.interval = (word & 0x0F000000) << 4 | (word & 0xFFFFFF);
          d.v_index = 1;
          d.discard = i.fault;
          d.parse = Parse::phase_words;
          break;
        case kOpConfig: {
          const uint32_t axis = word >> 24 & 0xF, field = word >> 20 & 0xF, value = word & 0xFFFF;
          // Refused while running, and while a STEP pulse is still high (after ABORT,
          // E-stop or the run's last move): a polarity or timing write never cuts it.
          if (i.running || i.pulse_busy) refuse(CoreError::config_busy);
          else if (axis >= p_.n || field > 10 || (field == 9 && !p_.feed) || (field == 10 && !p_.inputs) || (field <= 1 && value == 0) ||
                   (field <= 3 && value > mask_tw_))  // must fit the TW-bit timing field
            refuse(CoreError::config_value);
          else o.cfg_write = true;
          break;
        }
        case kOpControl:
          o.start = (word & 1) != 0;
          o.abort = (word >> 1 & 1) != 0;
          o.clear = (word >> 2 & 1) != 0;
          o.drivers_on = (word >> 3 & 1) != 0;
          o.drivers_off = (word >> 4 & 1) != 0;
          break;
        case kOpRead:
          d.rsp_valid = true;
          d.rsp_data = i.read_data;
          d.rsp_addr = word & 0xFF;
          d.parse = Parse::reply;
          break;
        default: refuse(CoreError::bad_opcode); break;
      }
      break;
    }
    case Parse::seg_h1:
      if (!take) break;
      d.seg_u = word & 0xFFFFFF;
      // The header word {[cont, conic,] out, end, k, dir, U} into the segment queue,
      // uncommitted.
      o.seg_wr = keep;
      o.seg_data = uint64_t(q.hdr_cont) << (31 + p_.n) | uint64_t(q.hdr_conic) << (30 + p_.n) |
                   uint64_t(q.hdr_out) << (29 + p_.n) | uint64_t(q.hdr_end) << (28 + p_.n) |
                   uint64_t(q.hdr_k) << (24 + p_.n) | uint64_t(word >> 24 & bits::mask(p_.n)) << 24 | d.seg_u;
      if (keep && (d.seg_u == 0 || d.seg_u > p_.umax)) {
        refuse(CoreError::seg_u);
        d.discard = true;
      }
      d.v_index = 0;
      d.parse = Parse::seg_v;
      break;
    case Parse::seg_v: {
      // An axis the compact form does not send: its v (U on the major axis, else 0)
      // written without taking a word, when the queue has room.
      const bool sent = v_sent();
      if (sent ? !take : keep && i.seg_full) break;
      const uint32_t form = q.chunks_left;
      const uint32_t v = sent ? word & 0xFFFFFF : (form >> 11 & 1) && (form >> 8 & 7) == q.v_index ? q.seg_u : 0;
      o.seg_wr = keep;
      o.seg_data = v;
      // A conic's plane axes step by the conic engine: their v must be 0.
      if (keep && q.hdr_conic && (q.v_index == q.hdr_au || q.v_index == q.hdr_av) && v != 0) {
        refuse(CoreError::conic_axes);
        d.discard = true;
      } else if (keep && v > q.seg_u) {
        refuse(CoreError::seg_v_gt_u);
        d.discard = true;
      }
      d.v_index = (q.v_index + 1) & 7;
      // A segment announced with no chunk was refused at its header; it ends here.
      if (q.v_index == p_.n - 1) {
        d.v_index = q.hdr_cont ? 5 : 0;  // a continuation has K5, K6 only
        d.parse = q.hdr_conic          ? Parse::conic_words
                  : p_.ptimer          ? Parse::seg_length
                  : q.chunks_left == 0 ? Parse::command
                                       : Parse::chunk_interval;
      }
      break;
    }
    case Parse::conic_words:
      // K0 .. K6 as they come but K1: the header's plane axes and direction go with C
      // to the builder, {cw, u, v, 9 zeros, C}; a continuation's K5 .. K6, its K5 with
      // them as {cw, u, v, 0, du}.
      if (!take) break;
      o.seg_wr = keep;
      o.seg_data = q.v_index == 1 ? (uint32_t(q.hdr_cw) << 31 | q.hdr_au << 28 | q.hdr_av << 25 | (word & 0xFFFF))
                   : q.v_index == 5 && q.hdr_cont
                       ? (uint32_t(q.hdr_cw) << 31 | q.hdr_au << 28 | q.hdr_av << 25 | (word & 0xFFFFFF))
                       : word;
      d.v_index = (q.v_index + 1) & 7;
      if (q.v_index == 6)
        d.parse = p_.ptimer ? Parse::seg_length : q.chunks_left == 0 ? Parse::command : Parse::chunk_interval;
      break;
    case Parse::seg_length:
      // A ptimer segment's last word, its length per move (not 0): committed whole.
      if (!take) break;
      o.seg_wr = keep;
      o.seg_data = word;
      d.parse = Parse::command;
      if (keep && word == 0) {
        refuse(CoreError::seg_length);
        d.discard = true;
      }
      o.seg_rollback = !keep || o.fault;
      o.seg_commit = !o.seg_rollback;
      break;
    case Parse::phase_words: {
      // u (sel 1), r (2, 3) if kind[0], S and H (4 .. 7) if kind[3], then W0.
      if (!take) break;
      const bool load_r = (q.interval >> 28 & 1) != 0, load_sh = (q.interval >> 31 & 1) != 0;
      const uint32_t next = q.v_index == 1 ? (load_r ? 2 : load_sh ? 4 : 0)
                            : q.v_index == 3 ? (load_sh ? 4 : 0)
                            : q.v_index == 7 ? 0
                                             : q.v_index + 1;
      o.ch_wr = keep;
      d.v_index = next;
      if (next == 0) d.parse = Parse::phase_w0;
      break;
    }
    case Parse::phase_w0:
      if (keep && i.ch_full) break;
      o.ch_wr = keep;
      o.ch_commit = keep;
      o.ch_rollback = !keep;
      d.parse = Parse::command;
      break;
    case Parse::chunk_interval:
      if (!take) break;
      d.interval = word;
      d.parse = Parse::chunk_count;
      break;
    case Parse::chunk_count: {
      if (!take) break;
      const uint32_t count = word & 0xFFFF, add = word >> 16;
      d.count = count;
      d.add = add;
      d.count_sum = (q.count_sum + count) & kMask34;
      if (keep && (q.interval == 0 || count == 0)) {
        refuse(CoreError::seg_chunk_zero);
        d.discard = true;
      }
      if (q.seg_add2) {
        d.parse = Parse::chunk_add2;
      } else {
        // The chunk's last word: add2 = 0.
        d.add2 = 0;
        o.ch_wr = keep;
        d.check_clock = 0;
        d.parse = Parse::chunk_check;
      }
      break;
    }
    case Parse::chunk_add2: {
      if (!take) break;
      const uint32_t add2 = word & 0xFFFF;
      d.add2 = add2;
      o.ch_wr = keep;
      d.check_clock = 0;
      d.parse = Parse::chunk_check;
      break;
    }
    case Parse::chunk_check: {
      // The check takes kCheckClocks clocks (the RTL's is bit-serial); its verdict
      // on the last; then, after the segment's last chunk, the count sum and the commit.
      if (q.check_clock + 1 < kCheckClocks) {
        d.check_clock = q.check_clock + 1;
        break;
      }
      if (const CoreError e = chunk_verdict(q); keep && e != CoreError::none) {
        refuse(e);
        d.discard = true;
      }
      d.chunks_left = (q.chunks_left - 1) & 0xFFFF;
      const uint64_t seg_moves = (uint64_t(q.seg_u) << q.hdr_k) & kMask34;
      if (q.chunks_left != 1) {
        d.parse = Parse::chunk_interval;
      } else if (!keep || o.fault) {
        o.ch_rollback = o.seg_rollback = true;
        d.parse = Parse::command;
      } else if (q.count_sum != seg_moves) {
        refuse(CoreError::seg_count_sum);
        o.ch_rollback = o.seg_rollback = true;
        d.parse = Parse::command;
      } else {
        // The whole segment passed: its words and its chunks appear together.
        o.seg_commit = o.ch_commit = true;
        d.parse = Parse::command;
      }
      break;
    }
    case Parse::reply:
      if (!q.rsp_valid || i.rsp_ready) d.parse = Parse::command;
      break;
  }
  // A segment committed: what a continuation may follow (a conic, its axes and way).
  if (o.seg_commit) {
    d.lc_valid = q.hdr_conic;
    d.lc_au = q.hdr_au;
    d.lc_av = q.hdr_av;
    d.lc_cw = q.hdr_cw;
  }
  // A fault (E-stop among them) or an ABORT flushes the walk a continuation would go on from.
  if (i.fault || o.fault || o.abort) d.lc_valid = false;
  o.ch_data = chunk_word(q.interval, d.add, d.count, d.add2, q.chunks_left == 1);
  if (p_.ptimer) {
    // The phase timer's word {sel, data}: W0 (sel 0) the PHASE header kept.
    const bool w0 = q.parse == Parse::phase_w0;
    o.ch_data = {uint64_t(w0 ? 0 : q.v_index & 7) << 32 | (w0 ? q.interval : word), 0, 0, 0};
  }
  // FLUSH: back to a command's first word; what this cycle would have done is not
  // done (the queues are emptied in this cycle).
  if (i.flush) {
    d.parse = Parse::command;
    d.discard = d.rsp_valid = d.lc_valid = false;
    o.seg_wr = o.seg_commit = o.seg_rollback = false;
    o.ch_wr = o.ch_commit = o.ch_rollback = false;
    o.start = o.abort = o.clear = o.drivers_on = o.drivers_off = false;
    o.cfg_write = o.fault = false;
    o.fault_code = 0;
  }
  return o;
}

CpCmd::Out CpCmd::eval_outputs(const In& i) const {
  Regs d = r_;
  return eval(i, d);
}

bool CpCmd::still(const In& i) const {
  if (i.rst) return false;
  Regs d = r_;
  const Out o = eval(i, d);
  return d == r_ && !(i.cmd_valid && o.cmd_ready) && !o.seg_wr && !o.seg_commit && !o.seg_rollback && !o.ch_wr &&
         !o.ch_commit && !o.ch_rollback && !o.start && !o.abort && !o.clear && !o.drivers_on && !o.drivers_off &&
         !o.cfg_write && !o.fault;
}

uint64_t CpCmd::counting_for(const In& i) const {
  if (i.rst || r_.parse != Parse::chunk_check || r_.rsp_valid) return 0;
  return kCheckClocks - 1 - r_.check_clock;
}

void CpCmd::skip(uint64_t cycles) {
  if (r_.parse == Parse::chunk_check) r_.check_clock += uint32_t(cycles);
}

void CpCmd::tick() {
  Regs d = r_;
  eval(in, d);
  if (in.rst) {
    d.parse = Parse::command;
    d.discard = d.rsp_valid = d.lc_valid = false;
  }
  r_ = d;
}

}  // namespace cpstep::model

#include "cp_core.h"

#include <algorithm>
#include <stdexcept>

namespace cpstep::model {
namespace {

constexpr uint32_t kOpSegment = 0x1, kOpConfig = 0x2, kOpControl = 0x3, kOpRead = 0x4;
constexpr uint64_t kMask34 = (uint64_t(1) << 34) - 1;  // the validator's arithmetic width
constexpr uint32_t kCardId = 0x43505331;              // "CPS1"
// The command set, register map and SPI frames version (READ 0x23 [23:16]).
constexpr uint32_t kProtocolVersion = 2;

uint32_t mask(unsigned bits) { return bits >= 32 ? ~0u : (1u << bits) - 1; }

void put_bits(FifoWord& w, unsigned lo, unsigned bits, uint64_t value) {
  for (unsigned b = 0; b < bits; ++b) {
    const unsigned at = lo + b;
    const uint64_t bit = uint64_t(1) << (at % 64);
    if (value >> b & 1) w[at / 64] |= bit;
    else w[at / 64] &= ~bit;
  }
}

uint64_t get_bits(const FifoWord& w, unsigned lo, unsigned bits) {
  uint64_t v = 0;
  for (unsigned b = 0; b < bits; ++b) v |= (w[(lo + b) / 64] >> ((lo + b) % 64) & 1) << b;
  return v;
}

// Chunk queue entry (81 bits, as in the RTL): interval, add, count, add2, and the
// flag of a segment's last chunk.
FifoWord chunk_word(uint32_t interval, uint32_t add, uint32_t count, uint32_t add2, bool last) {
  return {uint64_t(count & 0xFFFF) << 48 | uint64_t(add & 0xFFFF) << 32 | interval,
          uint64_t(add2 & 0xFFFF) | uint64_t(last) << 16, 0, 0};
}

unsigned clog2(uint64_t x) {
  unsigned b = 0;
  while ((uint64_t(1) << b) < x) ++b;
  return b;
}

int64_t sext16(uint32_t x) { return int64_t(int16_t(uint16_t(x))); }

}  // namespace

CpCore::CpCore(Params params)
    : p_(params),
      mask_tw_(mask(params.tw)),
      aw_(CpEngineParams{params.w}.aw()),  // the engine's and the banks' AW
      engine_(CpEngineParams{params.w, 0, 1, params.umax}),
      seg_fifo_({29 + params.n, params.saw + clog2(params.n + 1)}),
      run_fifo_({2 + 2 * params.n, 1}),
      chunk_fifo_({81, params.caw}) {
  if (p_.n < 1 || p_.n > kCoreMaxAxes) throw std::invalid_argument("cp_core: N must be 1 to 8");
  if (p_.umax < p_.w || p_.umax > 16777214)
    throw std::invalid_argument("cp_core: UMAX must be W to 2^24-2");
  if (p_.kmax > 10) throw std::invalid_argument("cp_core: KMAX must be at most 10");
  if (p_.tw < 1 || p_.tw > 16) throw std::invalid_argument("cp_core: TW must be 1 to 16");
  if (p_.pw < 32) throw std::invalid_argument("cp_core: PW must be at least 32");
  if (p_.caw < 1 || p_.caw > 15) throw std::invalid_argument("cp_core: CAW must be 1 to 15");
  banks_.assign(p_.n, std::vector<uint8_t>(size_t(2) << aw_, 0));
  pulses_.assign(p_.n, CpPulse({p_.tw, p_.pw, p_.step_pol_reset, p_.dir_pol_reset}));
  reset_control(r_);
}

// A pulse timer's inputs are the core's configuration and direction registers.
CpPulseIn CpCore::pulse_in(unsigned a, uint32_t step) const {
  const AxisConfig& c = r_.cfg[a];
  CpPulseIn pi;
  pi.rst = in.rst;
  pi.cfg_step_high = c.step_high;
  pi.cfg_step_low = c.step_low;
  pi.cfg_dir_setup = c.dir_setup;
  pi.cfg_dir_hold = c.dir_hold;
  pi.cfg_step_pol = c.step_pol;
  pi.cfg_dir_pol = c.dir_pol;
  pi.dir = (r_.dir >> a & 1) != 0;
  pi.step = (step >> a & 1) != 0;
  return pi;
}

CpCore::Out CpCore::outputs() const {
  const Regs& q = r_;
  Out o;
  o.cmd_ready = cmd_ready();
  o.rsp_valid = q.rsp_valid;
  o.rsp_data = q.rsp_valid ? q.rsp_data : 0;
  o.rsp_addr = q.rsp_valid ? q.rsp_addr : 0;
  o.rd_data = read_register(in.rd_addr & 0xFF);
  for (unsigned a = 0; a < p_.n; ++a) {
    CpPulse pulse = pulses_[a];
    pulse.in = pulse_in(a, 0);
    const CpPulseOut po = pulse.outputs();
    o.step |= uint32_t(po.step) << a;
    o.dir |= uint32_t(po.dir) << a;
    // Sign-extend from PW bits.
    const unsigned shift = 64 - p_.pw;
    o.position[a] = int64_t(po.position << shift) >> shift;
  }
  o.running = q.running;
  o.fault = q.fault;
  o.stretched = q.stretched;
  o.err_code = q.err;
  o.enable = q.enable;
  o.status = read_register(0x00);
  o.stretch_count = q.stretch_count;
  o.moves_done = q.moves_done;
  o.segments_done = q.segments_done;
  return o;
}

// READ's registers, as they are in the cycle the READ word is taken (or the
// read port names them).
uint32_t CpCore::read_register(uint32_t reg) const {
  const Regs& q = r_;
  switch (reg) {
    case 0x00: {
      const uint32_t chunks = std::min<uint32_t>(chunk_fifo_.outputs().level, 255);
      const uint32_t segments = (q.segs_queued + uint32_t(q.build != Build::idle) +
                                 run_fifo_.outputs().level + q.cur_valid) & 0xFF;
      return chunks << 24 | segments << 16 | (q.err & 0xFF) << 8 | uint32_t(q.enable) << 4 | uint32_t(in.estop) << 3 |
             uint32_t(q.stretched) << 2 | uint32_t(q.fault) << 1 | uint32_t(q.running);
    }
    case 0x01: return q.stretch_count;
    case 0x02: return q.moves_done;
    case 0x03: return q.segments_done;
    case 0x1F: return kCardId;
    case 0x20: return (p_.tw & 0x1F) << 24 | (p_.saw & 0xF) << 20 | (p_.caw & 0xF) << 16 | (p_.kmax & 0xFF) << 8 |
                      (p_.n & 0xFF);
    case 0x21: return p_.w;
    case 0x22: return p_.umax;
    case 0x23: return kProtocolVersion << 16 | (p_.cbuf_aw & 0xFF) << 8 | (p_.pw & 0xFF);
    case 0x24: return p_.clock_hz;
    case 0x25: return p_.build_id;
    default:
      if (reg >= 0x10 && reg < 0x10 + p_.n) return uint32_t(pulses_[reg - 0x10].outputs().position);
      return 0;
  }
}

// The command parser and validator: at most one word per cycle.
void CpCore::parse(const View& v, Regs& d, Cycle& c) const {
  const Regs& q = r_;
  const uint32_t word = in.cmd_data;
  const bool keep = !q.discard && !q.fault;  // the segment being read is still good
  switch (q.parse) {
    case Parse::command: {
      if (!c.take) break;
      switch (word >> 28) {
        case kOpSegment: {
          d.hdr_end = (word >> 27 & 1) != 0;
          d.hdr_k = word >> 23 & 0xF;
          d.chunks_left = word & 0xFFFF;
          d.seg_add2 = (word >> 22 & 1) != 0;
          d.count_sum = 0;
          d.discard = q.fault;
          if (!q.fault) {
            if (d.hdr_k > p_.kmax) {
              c.raise(CoreError::seg_k);
              d.discard = true;
            } else if (d.chunks_left == 0 || d.chunks_left > (1u << p_.caw)) {
              c.raise(CoreError::seg_chunks);
              d.discard = true;
            }
          }
          d.parse = Parse::seg_h1;
          break;
        }
        case kOpConfig: {
          const uint32_t axis = word >> 24 & 0xF, field = word >> 20 & 0xF, value = word & 0xFFFF;
          // Refused while running, and while a STEP pulse is still high (after ABORT,
          // E-stop or the run's last move): a polarity or timing write never cuts it.
          bool pulse_high = false;
          for (unsigned a = 0; a < p_.n; ++a) pulse_high = pulse_high || v.pulse[a].busy;
          if (q.running || pulse_high) c.raise(CoreError::config_busy);
          else if (axis >= p_.n || field > 4 || (field <= 1 && value == 0) ||
                   (field <= 3 && value > mask_tw_))  // must fit the TW-bit timing field
            c.raise(CoreError::config_value);
          else c.cfg_write = true;
          break;
        }
        case kOpControl:
          c.start = (word & 1) != 0;
          c.abort = (word >> 1 & 1) != 0;
          c.clear = (word >> 2 & 1) != 0;
          c.drivers_on = (word >> 3 & 1) != 0;
          c.drivers_off = (word >> 4 & 1) != 0;
          break;
        case kOpRead:
          d.rsp_valid = true;
          d.rsp_data = read_register(word & 0xFF);
          d.rsp_addr = word & 0xFF;
          d.parse = Parse::reply;
          break;
        default: c.raise(CoreError::bad_opcode); break;
      }
      break;
    }
    case Parse::seg_h1:
      if (!c.take) break;
      d.seg_u = word & 0xFFFFFF;
      // The header word {end, k, dir, U} into the segment queue, uncommitted.
      c.seg_wr = keep;
      c.seg_data = {uint64_t(q.hdr_end) << (28 + p_.n) | uint64_t(q.hdr_k) << (24 + p_.n) |
                        uint64_t(word >> 24 & mask(p_.n)) << 24 | d.seg_u,
                    0, 0, 0};
      if (keep && (d.seg_u == 0 || d.seg_u > p_.umax)) {
        c.raise(CoreError::seg_u);
        d.discard = true;
      }
      d.v_index = 0;
      d.parse = Parse::seg_v;
      break;
    case Parse::seg_v:
      if (!c.take) break;
      c.seg_wr = keep;
      c.seg_data = {word & 0xFFFFFF, 0, 0, 0};
      if (keep && (word & 0xFFFFFF) > q.seg_u) {
        c.raise(CoreError::seg_v_gt_u);
        d.discard = true;
      }
      d.v_index = (q.v_index + 1) & 7;
      // A segment announced with no chunk was refused at its header; it ends here.
      if (q.v_index == p_.n - 1) d.parse = q.chunks_left == 0 ? Parse::command : Parse::chunk_interval;
      break;
    case Parse::chunk_interval:
      if (!c.take) break;
      d.interval = word;
      d.parse = Parse::chunk_count;
      break;
    case Parse::chunk_count: {
      if (!c.take) break;
      const uint32_t count = word & 0xFFFF, add = word >> 16;
      d.count = count;
      d.add = add;
      d.count_sum = (q.count_sum + count) & kMask34;
      if (keep && (q.interval == 0 || count == 0)) {
        c.raise(CoreError::seg_chunk_zero);
        d.discard = true;
      }
      d.product = 0;
      if (q.seg_add2) {
        d.parse = Parse::chunk_add2;
      } else {
        // The chunk's last word: add2 = 0, straight to pass 2 with 2·add.
        d.add2 = 0;
        c.chunk_wr = keep;
        d.mul_a = (count - 1) & 0xFFFF;
        d.mul_b = 2 * sext16(add);
        d.parse = Parse::chunk_check;
      }
      break;
    }
    case Parse::chunk_add2: {
      if (!c.take) break;
      const uint32_t add2 = word & 0xFFFF;
      d.add2 = add2;
      c.chunk_wr = keep;
      d.product = 0;
      if (add2 == 0) {
        d.mul_a = (q.count - 1) & 0xFFFF;
        d.mul_b = 2 * sext16(q.add);
        d.parse = Parse::chunk_check;
      } else {
        // Pass 1: (count-2)·add2, no multiplier bit when count < 2.
        d.mul_a = q.count < 2 ? 0 : q.count - 2;
        d.mul_b = sext16(add2);
        d.parse = Parse::chunk_inc;
      }
      break;
    }
    case Parse::chunk_inc: parse_check_increment(d, c); break;
    case Parse::chunk_check: parse_check_chunk(v, d, c); break;
    case Parse::reply:
      if (!q.rsp_valid || in.rsp_ready) d.parse = Parse::command;
      break;
  }
}

// The chunk check's bit-serial multiplier: one bit of mul_a a cycle; false when
// no bit is left (the product is complete).
bool CpCore::multiply_step(Regs& d) const {
  const Regs& q = r_;
  if (q.mul_a == 0) return false;
  if (q.mul_a & 1) d.product = q.product + q.mul_b;
  d.mul_a = q.mul_a >> 1;
  d.mul_b = q.mul_b * 2;
  return true;
}

// Pass 1 of a chunk with add2 ≠ 0: its last increment add + (count-2)·add2, one
// multiplier bit per cycle; then the sign rule (no increment of the opposite sign
// to add) and pass 2's multiplicand add + last increment.
void CpCore::parse_check_increment(Regs& d, Cycle& c) const {
  const Regs& q = r_;
  if (multiply_step(d)) return;
  const int64_t add = sext16(q.add), last_inc = add + q.product;
  if (!q.discard && !q.fault && ((add > 0 && last_inc < 0) || (add < 0 && last_inc > 0))) {
    c.raise(CoreError::seg_add2);
    d.discard = true;
  }
  d.product = 0;
  d.mul_a = (q.count - 1) & 0xFFFF;
  d.mul_b = add + last_inc;
  d.parse = Parse::chunk_check;
}

// Pass 2: the chunk's last delay interval + (count-1)·(add + last increment)/2, one
// multiplier bit per cycle; after the segment's last chunk, the count sum and the commit.
void CpCore::parse_check_chunk(const View& /*v*/, Regs& d, Cycle& c) const {
  const Regs& q = r_;
  if (multiply_step(d)) return;
  bool raised = false;
  const int64_t last_delay = int64_t(q.interval) + (q.product >> 1);  // product is even
  if (!q.discard && !q.fault && (last_delay <= 0 || last_delay > int64_t(0xFFFFFFFF))) {
    c.raise(CoreError::seg_delay);
    d.discard = true;
    raised = true;
  }
  d.chunks_left = (q.chunks_left - 1) & 0xFFFF;
  const uint64_t seg_moves = (uint64_t(q.seg_u) << q.hdr_k) & kMask34;
  if (q.chunks_left != 1) {
    d.parse = Parse::chunk_interval;
  } else if (q.discard || q.fault || raised) {
    c.chunk_rollback = c.seg_rollback = true;
    d.parse = Parse::command;
  } else if (q.count_sum != seg_moves) {
    c.raise(CoreError::seg_count_sum);
    c.chunk_rollback = c.seg_rollback = true;
    d.parse = Parse::command;
  } else {
    // The whole segment passed: its words and its chunks appear together.
    c.seg_commit = c.chunk_commit = true;
    d.segs_queued = q.segs_queued + 1;
    d.parse = Parse::command;
  }
}

// The builder: the next committed segment's patterns, one axis after the other,
// into the build lane's banks. A constant pattern (v = 0 or v = U) is one move; any
// other is built by the engine, whose first period is copied move by move.
void CpCore::build(const View& v, Regs& d, Cycle& c) const {
  const Regs& q = r_;
  const uint64_t head = v.seg.out_data[0];
  const uint32_t val = uint32_t(head) & 0xFFFFFF;
  switch (q.build) {
    case Build::idle:
      if (v.seg.out_valid && !q.fault && v.run.level + uint32_t(q.cur_valid) <= 1) {
        c.seg_pop = true;
        d.segs_queued = d.segs_queued - 1;
        d.b_u = val;
        d.b_dir = uint32_t(head >> 24) & mask(p_.n);
        d.b_end = (head >> (28 + p_.n) & 1) != 0;
        d.b_axis = 0;
        d.b_moving = 0;
        d.build = Build::next_axis;
      }
      break;
    case Build::next_axis:
      if (v.seg.out_valid && v.engine.in_ready) {
        c.seg_pop = true;
        d.b_moving = q.b_moving | uint32_t(val != 0) << q.b_axis;
        if (val == 0 || val == q.b_u) {
          c.bank_we = 1u << q.b_axis;
          c.bank_waddr = 0;
          c.bank_wbit = val != 0;
          c.cap_done = true;
        } else {
          c.eng_in_valid = true;
          d.cap_addr = 0;
          d.build = Build::capture;
        }
      }
      break;
    case Build::capture:
      c.eng_move_ready = true;
      if (v.engine.move_valid) {
        c.bank_we = 1u << q.b_axis;
        c.bank_waddr = q.cap_addr;
        c.bank_wbit = v.engine.move;
        d.cap_addr = (q.cap_addr + 1) & mask(aw_);
        c.cap_done = v.engine.move_pend;
      }
      if (v.engine.err) {
        c.raise(CoreError::seg_pattern);
        d.build = Build::idle;
      }
      break;
  }
  if (c.cap_done) {
    d.lm1[q.build_lane][q.b_axis] = q.build == Build::capture ? q.cap_addr : 0;
    if (q.b_axis == p_.n - 1) {
      c.run_wr = true;
      put_bits(c.run_data, 0, p_.n, q.b_dir);
      put_bits(c.run_data, p_.n, p_.n, d.b_moving);
      put_bits(c.run_data, 2 * p_.n, 1, q.b_end);
      put_bits(c.run_data, 2 * p_.n + 1, 1, q.build_lane);
      d.build_lane = 1 - q.build_lane;
      d.build = Build::idle;
    } else {
      d.b_axis = q.b_axis + 1;
      d.build = Build::next_axis;
    }
  }
  c.eng_rst = q.build == Build::capture && c.cap_done;
}

// The timer (chunks), the runner (move events, segment ends, loads) and the CONTROL
// word's start, abort and the E-stop.
void CpCore::run(const View& v, Regs& d, Cycle& c) const {
  const Regs& q = r_;
  const uint32_t lane_move = rbits_ & mask(p_.n);
  uint32_t ready = 0;
  for (unsigned a = 0; a < p_.n; ++a) ready |= uint32_t(v.pulse[a].ready) << a;
  const bool due = q.chunk_loaded && q.elapsed >= q.delay;
  const bool stopping = in.estop || c.abort;
  c.fire = q.running && q.cur_valid && !stopping && due && q.rp_valid && (lane_move & ~ready) == 0;
  c.rp_lane = q.cur_lane;
  c.rp_next = q.rp_ptr;
  c.step = c.fire ? lane_move : 0;

  // A move is counted late once: the first cycle it is due and does not fire, or
  // when it fires after its time without having waited due (its chunk came late).
  c.stretch = q.running && due && !q.late && !stopping && (!c.fire || q.elapsed != q.delay);
  if (c.stretch) {
    d.stretched = true;
    d.stretch_count = q.stretch_count + 1;
    d.late = true;
  }
  if (c.fire) d.late = false;

  d.elapsed = q.elapsed == ~0u ? q.elapsed : q.elapsed + 1;
  auto load_chunk = [&] {
    const uint64_t head = v.chunk.out_data[0];
    c.chunk_pop = true;
    d.delay = uint32_t(head);
    d.timer_inc = uint32_t(sext16(uint32_t(head >> 32)));
    d.moves_left = uint32_t(head >> 48) & 0xFFFF;
    d.timer_add2 = uint32_t(v.chunk.out_data[1]) & 0xFFFF;
    d.timer_last = (v.chunk.out_data[1] >> 16 & 1) != 0;
  };
  if (!q.chunk_loaded && v.chunk.out_valid) {
    load_chunk();
    d.chunk_loaded = true;
  }
  const bool seg_done = c.fire && q.moves_left == 1 && q.timer_last;
  if (c.fire) {
    d.moves_done = q.moves_done + 1;
    d.elapsed = 1;
    if (q.moves_left != 1) {
      d.moves_left = (q.moves_left - 1) & 0xFFFF;
      d.delay = q.delay + q.timer_inc;
      d.timer_inc = q.timer_inc + uint32_t(sext16(q.timer_add2));
    } else if (v.chunk.out_valid) {
      load_chunk();
    } else {
      d.chunk_loaded = false;
    }
    // The replay registers fetch the next move of the running lane's patterns.
    if (!seg_done) {
      c.bank_re = true;
      for (unsigned a = 0; a < p_.n; ++a)
        c.rp_next[a] = q.rp_ptr[a] == q.lm1[q.cur_lane][a] ? 0 : (q.rp_ptr[a] + 1) & mask(aw_);
    }
  }
  if (seg_done) {
    d.segments_done = q.segments_done + 1;
    d.cur_valid = false;
    d.rp_valid = false;
    if (q.cur_end) {
      d.running = false;
    } else if (v.run.level == 0 && q.segs_queued == 0 && q.build == Build::idle && !q.fault) {
      d.running = false;
      c.raise(CoreError::underrun);
    }
  }
  // Load the next built segment; its moving axes take their directions.
  if ((!q.cur_valid || seg_done) && v.run.out_valid && !q.fault) {
    const FifoWord& head = v.run.out_data;
    const uint32_t dir = uint32_t(get_bits(head, 0, p_.n));
    const uint32_t moving = uint32_t(get_bits(head, p_.n, p_.n));
    c.run_pop = true;
    d.cur_valid = true;
    d.cur_lane = unsigned(get_bits(head, 2 * p_.n + 1, 1));
    d.cur_end = get_bits(head, 2 * p_.n, 1) != 0;
    d.dir = (q.dir & ~moving) | (dir & moving);
    // The replay registers fetch each pattern's first move.
    c.bank_re = true;
    c.rp_lane = d.cur_lane;
    d.rp_valid = true;
    c.rp_next.fill(0);
  }
  if (c.start && !q.fault && !q.running) {
    d.running = true;
    d.elapsed = 1;
  }
  if (c.abort) c.raise(CoreError::abort);
  if (in.estop) c.raise(CoreError::estop);
  // Drivers: off wins over on; E-stop holds them off.
  if (c.drivers_on) d.enable = true;
  if (c.drivers_off || in.estop) d.enable = false;
  c.flush = stopping || (q.fault && !(q.running && q.cur_valid && !seg_done));
}

// CLEAR drops what was latched before this cycle; then the first fault latches. A
// latched fault lets the running segment complete unless its own lane refused it;
// otherwise (and at E-stop or abort) everything queued is flushed.
void CpCore::latch_faults(Regs& d, Cycle& c) const {
  const Regs& q = r_;
  const bool clearing = c.clear && !in.estop;
  if (clearing) {
    d.fault = false;
    d.err = 0;
    d.stretched = c.stretch;  // a stretch in this very cycle stays
  }
  if (c.fault_set && (!q.fault || clearing)) {
    d.fault = true;
    d.err = c.fault_code;
  }
  if (c.flush) {
    d.running = false;
    d.cur_valid = false;
    d.chunk_loaded = false;
    d.cur_lane = 0;
    d.build_lane = 0;
    d.late = false;
    d.build = Build::idle;
    d.rp_valid = false;
    d.segs_queued = 0;
  }
}

void CpCore::reset_control(Regs& d) const {
  d.parse = Parse::command;
  d.discard = d.rsp_valid = d.running = d.cur_valid = false;
  d.cur_lane = d.build_lane = 0;
  d.chunk_loaded = d.late = false;
  d.build = Build::idle;
  d.rp_valid = false;
  d.segs_queued = 0;
  d.fault = false;
  d.err = 0;
  d.stretched = false;
  d.enable = false;
  d.stretch_count = d.moves_done = d.segments_done = 0;
  d.dir = 0;
  for (AxisConfig& c : d.cfg) {
    c.step_high = p_.step_high_reset & mask_tw_;
    c.step_low = p_.step_low_reset & mask_tw_;
    c.dir_setup = p_.dir_setup_reset & mask_tw_;
    c.dir_hold = p_.dir_hold_reset & mask_tw_;
    c.step_pol = p_.step_pol_reset;
    c.dir_pol = p_.dir_pol_reset;
  }
}

bool CpCore::cmd_ready() const {
  switch (r_.parse) {
    case Parse::command: return true;
    case Parse::seg_h1:
    case Parse::seg_v: return r_.discard || r_.fault || !seg_fifo_.outputs().full;
    case Parse::chunk_interval: return true;
    case Parse::chunk_count:
      return r_.seg_add2 || r_.discard || r_.fault || !chunk_fifo_.outputs().full;
    case Parse::chunk_add2: return r_.discard || r_.fault || !chunk_fifo_.outputs().full;
    default: return false;  // checking a chunk, or a reply waits
  }
}

void CpCore::tick() {
  const Regs& q = r_;
  const unsigned n = p_.n;

  View v;
  v.seg = seg_fifo_.outputs();
  v.run = run_fifo_.outputs();
  v.chunk = chunk_fifo_.outputs();
  v.engine = engine_.outputs();
  for (unsigned a = 0; a < n; ++a) {
    CpPulse pulse = pulses_[a];
    pulse.in = pulse_in(a, 0);
    v.pulse[a] = pulse.outputs();
  }

  Regs d = q;
  Cycle c;
  c.take = in.cmd_valid && cmd_ready();
  d.rsp_valid = q.rsp_valid && !in.rsp_ready;
  parse(v, d, c);
  build(v, d, c);
  run(v, d, c);
  latch_faults(d, c);

  // The sub-blocks' edge.
  engine_.in.rst = in.rst || c.flush || c.eng_rst;
  engine_.in.in_valid = c.eng_in_valid;
  engine_.in.in_u = q.b_u;
  engine_.in.in_v = uint32_t(v.seg.out_data[0]) & 0xFFFFFF;
  engine_.in.in_k = 0;
  engine_.in.in_rep = 1;
  engine_.in.move_ready = c.eng_move_ready;
  engine_.tick();
  // Pattern banks: the builder writes the build lane, the replay reads the running one.
  const uint32_t half = 1u << aw_;
  if (c.bank_re) {
    uint32_t bits = 0;
    for (unsigned a = 0; a < n; ++a)
      bits |= uint32_t(banks_[a][c.rp_lane * half + c.rp_next[a]]) << a;
    rbits_ = bits;
  }
  for (unsigned a = 0; a < n; ++a)
    if (c.bank_we >> a & 1) banks_[a][q.build_lane * half + c.bank_waddr] = c.bank_wbit;
  for (unsigned a = 0; a < n; ++a) {
    pulses_[a].in = pulse_in(a, c.step);
    pulses_[a].tick();
  }
  auto edge = [&](CpFifo& f, bool wr, const FifoWord& data, bool commit, bool rollback, bool pop) {
    f.in.rst = in.rst;
    f.in.clear = c.flush;
    f.in.wr = wr;
    f.in.wr_data = data;
    f.in.commit = commit;
    f.in.rollback = rollback;
    f.in.out_ready = pop;
    f.tick();
  };
  edge(seg_fifo_, c.seg_wr, c.seg_data, c.seg_commit, c.seg_rollback, c.seg_pop);
  edge(run_fifo_, c.run_wr, c.run_data, true, false, c.run_pop);
  edge(chunk_fifo_, c.chunk_wr, chunk_word(q.interval, d.add, d.count, d.add2, q.chunks_left == 1),
       c.chunk_commit,
       c.chunk_rollback, c.chunk_pop);

  // The core's own registers: reset clears the control state; the datapath loads.
  if (c.bank_re) d.rp_ptr = c.rp_next;
  if (in.rst) {
    reset_control(d);
    r_ = d;
    return;
  }
  if (c.cfg_write) {
    const uint32_t word = in.cmd_data;
    AxisConfig& cfg = d.cfg[word >> 24 & 0xF];
    const uint32_t value = word & mask_tw_;
    switch (word >> 20 & 0xF) {
      case 0: cfg.step_high = value; break;
      case 1: cfg.step_low = value; break;
      case 2: cfg.dir_setup = value; break;
      case 3: cfg.dir_hold = value; break;
      default:
        cfg.step_pol = (word & 1) != 0;
        cfg.dir_pol = (word >> 1 & 1) != 0;
        break;
    }
  }
  r_ = d;
}

}  // namespace cpstep::model

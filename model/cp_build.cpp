// SPDX-License-Identifier: MIT
#include "model/cp_build.h"

#include "model/bits.h"

namespace cpstep::model {

CpBuild::CpBuild(Params p)
    : p_(p),
      aw_(CpEngineParams{p.w}.aw()),
      uw_(bits::clog2(uint64_t(p.umax) + 2)),
      sqw_(p.saw + bits::clog2(p.n + 1 + (p.ptimer ? 1 : 0))),
      engine_(CpEngineParams{p.w, 0, 1, p.umax}) {}

CpBuild::Out CpBuild::eval(const In& i, Regs& d, Engine& e) const {
  const Regs& q = r_;
  const CpEngineOut eo = engine_.outputs();
  const uint32_t seg_mask = bits::mask(sqw_ + 1);
  Out o;
  d.segq = (q.segq + uint32_t(i.seg_commit)) & seg_mask;
  const uint32_t val = uint32_t(i.seg_head) & 0xFFFFFF;
  const uint32_t val_u = val & bits::mask(uw_);  // what the engine and b_u see
  bool cap_done = false;
  switch (q.state) {
    case State::idle:
      if (i.seg_valid && !i.fault && (i.run_level & 3) + uint32_t(i.cur_valid) <= 1) {
        o.seg_pop = true;
        d.segq = (d.segq - 1) & seg_mask;
        d.u = val_u;
        d.dir = uint32_t(i.seg_head >> 24) & bits::mask(p_.n);
        d.end = (i.seg_head >> (28 + p_.n) & 1) != 0;
        d.out = (i.seg_head >> (29 + p_.n) & 1) != 0;
        d.conic = p_.conic && (i.seg_head >> (30 + p_.n) & 1) != 0;
        d.cont = p_.conic && (i.seg_head >> (31 + p_.n) & 1) != 0;
        d.k = uint32_t(i.seg_head >> (24 + p_.n)) & 15;
        d.axis = 0;
        d.moving = 0;
        d.state = State::next_axis;
      }
      break;
    case State::next_axis:
      if (i.seg_valid && eo.in_ready) {
        o.seg_pop = true;
        d.moving = (q.moving | uint32_t(val != 0) << q.axis) & bits::mask(p_.n);
        if (val == 0 || val_u == q.u) {
          // A constant pattern: one move.
          o.bank_we = true;
          o.bank_waddr = 0;
          o.bank_wbit = val != 0;
          cap_done = true;
        } else {
          e.in_valid = true;
          d.cap_addr = 0;
          d.state = State::capture;
        }
      }
      break;
    case State::capture:
      e.move_ready = true;
      if (eo.move_valid) {
        o.bank_we = true;
        o.bank_waddr = q.cap_addr;
        o.bank_wbit = eo.move;
        d.cap_addr = (q.cap_addr + 1) & bits::mask(aw_);
        cap_done = eo.move_pend;
      }
      if (eo.err) {
        o.fault = true;
        d.state = State::idle;
      }
      break;
    case State::conic_words:
      // Once the walker is free: K0 .. K6 into it, the last with its start and the
      // segment into the run queue. K1 carries the plane axes: {cw, u, v, 9 zeros, C};
      // a continuation has K5, K6 only, and K5 carries them: {cw, u, v, 0, du}.
      if (i.seg_valid && i.walker_free) {
        const uint32_t word = uint32_t(i.seg_head);
        o.seg_pop = true;
        o.cw_wr = true;
        if (q.k_index == (q.cont ? 5u : 1u)) {
          d.au = word >> 28 & 7;
          d.av = word >> 25 & 7;
        }
        d.k_index = (q.k_index + 1) & 7;
        if (q.k_index == 6 && p_.ptimer) {
          o.cw_start = true;
          o.cw_cont = q.cont;
          d.state = State::length;
        } else if (q.k_index == 6) {
          o.cw_start = true;
          o.cw_cont = q.cont;
          o.run_wr = true;
          o.run_data = uint64_t(1) << (2 * p_.n + 9) | uint64_t(q.au) << (2 * p_.n + 6) |
                       uint64_t(q.av) << (2 * p_.n + 3) | uint64_t(q.out) << (2 * p_.n + 2) |
                       uint64_t(q.build_lane) << (2 * p_.n + 1) |
                       uint64_t(q.end) << (2 * p_.n) | uint64_t(q.moving) << p_.n | q.dir;
          d.build_lane = !q.build_lane;
          d.state = State::idle;
        }
      }
      break;
    case State::length:
      // ptimer: the segment's last word, its length per move, goes with it into the
      // run queue, with its k and U.
      if (i.seg_valid) {
        o.seg_pop = true;
        o.run_wr = true;
        o.run_data = uint64_t(q.conic) << (2 * p_.n + 9) | uint64_t(q.au) << (2 * p_.n + 6) |
                     uint64_t(q.av) << (2 * p_.n + 3) | uint64_t(q.out) << (2 * p_.n + 2) |
                     uint64_t(q.build_lane) << (2 * p_.n + 1) | uint64_t(q.end) << (2 * p_.n) |
                     uint64_t(q.moving) << p_.n | q.dir;
        if (!p_.conic) o.run_data &= bits::mask64(3 + 2 * p_.n);
        o.run_data_pt = (i.seg_head & 0xFFFFFFFF) << 28 | uint64_t(q.k) << 24 | q.u;
        d.build_lane = !q.build_lane;
        d.state = State::idle;
      }
      break;
  }
  o.cw_sel = q.k_index;
  o.cw_data = uint32_t(i.seg_head);
  if (cap_done) {
    if (q.axis == p_.n - 1 && q.conic) {
      d.k_index = q.cont ? 5 : 0;
      d.state = State::conic_words;
    } else if (q.axis == p_.n - 1 && p_.ptimer) {
      d.state = State::length;
    } else if (q.axis == p_.n - 1) {
      o.run_wr = true;
      o.run_data = uint64_t(q.out) << (2 * p_.n + 2) | uint64_t(q.build_lane) << (2 * p_.n + 1) |
                   uint64_t(q.end) << (2 * p_.n) |
                   uint64_t(d.moving) << p_.n | q.dir;
      d.build_lane = !q.build_lane;
      d.state = State::idle;
    } else {
      d.axis = (q.axis + 1) & 7;
      d.state = State::next_axis;
    }
  }
  if (i.flush) {
    d.state = State::idle;
    d.build_lane = false;
    d.segq = 0;
  }
  // The engine is reset when a pattern's first period is in its bank, and by a flush.
  e.rst = i.flush || (q.state == State::capture && cap_done);
  o.len_we = cap_done;
  o.len_m1 = q.state == State::capture ? q.cap_addr : 0;
  o.bank_axis = q.axis;
  o.build_lane = q.build_lane;
  o.busy = q.state != State::idle;
  o.segq = q.segq;
  return o;
}

CpBuild::Out CpBuild::eval_outputs(const In& i) const {
  Regs d = r_;
  Engine e;
  return eval(i, d, e);
}

bool CpBuild::still(const In& i) const {
  if (i.rst) return false;
  Regs d = r_;
  Engine e;
  const Out o = eval(i, d, e);
  if (!(d == r_) || o.seg_pop || o.run_wr || o.bank_we || o.len_we || o.fault || e.in_valid || o.cw_wr ||
      o.cw_start)
    return false;
  CpEngineIn ei;
  ei.rst = e.rst;
  ei.in_u = r_.u;
  ei.in_v = uint32_t(i.seg_head) & 0xFFFFFF;
  ei.in_rep = 1;
  ei.move_ready = e.move_ready;
  return engine_.still(ei);
}

void CpBuild::tick() {
  Regs d = r_;
  Engine e;
  eval(in, d, e);
  engine_.in.rst = in.rst || e.rst;
  engine_.in.in_valid = e.in_valid;
  engine_.in.in_u = r_.u;
  engine_.in.in_v = uint32_t(in.seg_head) & 0xFFFFFF;
  engine_.in.in_k = 0;
  engine_.in.in_rep = 1;
  engine_.in.move_ready = e.move_ready;
  engine_.tick();
  if (in.rst) {
    d.state = State::idle;
    d.build_lane = false;
    d.segq = 0;
  }
  r_ = d;
}

}  // namespace cpstep::model

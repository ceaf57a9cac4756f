// SPDX-License-Identifier: MIT
#include "cp_engine.h"

#include <bit>
#include <stdexcept>

namespace cpstep::model {
namespace {

unsigned clog2(uint64_t n) { return n <= 1 ? 0 : unsigned(std::bit_width(n - 1)); }
uint32_t mask(unsigned bits) { return bits >= 32 ? ~0u : (1u << bits) - 1; }

}  // namespace

unsigned CpEngineParams::aw() const { return w > 2 ? clog2(w) : 1; }
unsigned CpEngineParams::uw() const { return clog2(uint64_t(u_max()) + 2); }
unsigned CpEngineParams::kw() const { return kmax > 0 ? clog2(uint64_t(kmax) + 2) : 1; }

CpEngine::CpEngine(CpEngineParams params)
    : p_(params), mask_u_(mask(p_.uw())), mask_k_(mask(p_.kw())), mask_rep_(mask(p_.rw)) {
  if (p_.w < 2) throw std::invalid_argument("cp_engine: W must be at least 2");
  if (p_.u_max() < p_.w) throw std::invalid_argument("cp_engine: UMAX must be at least W");
  if (p_.kmax > 24) throw std::invalid_argument("cp_engine: KMAX must be 0 to 24");
  if (p_.rw < 1 || p_.rw > 32) throw std::invalid_argument("cp_engine: RW must be 1 to 32");
  mem_[0].assign(size_t(1) << p_.aw(), 0);
  mem_[1].assign(size_t(1) << p_.aw(), 0);
}

uint32_t CpEngine::wrap(int64_t a) const { return uint32_t(a) & mask(p_.aw()); }

// rev = 0: logical i is at lo + i; rev = 1: at lo + len - 1 - i.
uint32_t CpEngine::phys(const Reg& r, uint32_t logical) const {
  return r.rev ? wrap(int64_t(r.lo) + r.len - 1 - logical) : wrap(int64_t(r.lo) + logical);
}

// A prepend to the logical front writes just outside the window on the side
// the logical front is on.
uint32_t CpEngine::front_slot(const Reg& r) const {
  return r.rev ? wrap(int64_t(r.lo) + r.len) : wrap(int64_t(r.lo) - 1);
}

EngineError CpEngine::refusal(const In& i) const {
  const uint32_t u = i.in_u & mask_u_, v = i.in_v & mask_u_;
  if (u == 0) return EngineError::u_zero;
  if (v > u) return EngineError::v_gt_u;
  if (u > p_.u_max()) return EngineError::u_gt_umax;
  if ((i.in_k & mask_k_) > p_.kmax) return EngineError::k_gt_kmax;
  if ((i.in_rep & mask_rep_) == 0) return EngineError::rep_zero;
  return EngineError::none;
}

CpEngine::Regs CpEngine::next(const In& i, Cycle& io) const {
  const Regs& q = r_;
  Regs d = q;
  d.write_pending = false;
  d.err = false;
  d.snap_valid = false;

  // The build write reserved last cycle lands now: the source bit it read.
  if (q.write_pending) {
    const int t = q.write_to;
    io.we[t] = true;
    io.waddr[t] = q.write_addr;
    io.wbit[t] = rdata_[1 - t];
  }
  if (q.out_valid && i.move_ready) d.out_valid = false;

  const bool ready = q.state == State::idle && !q.out_valid;
  const auto begin_replay = [&](Regs& s) {
    s.state = State::replay;
    s.phase = 0;
    s.phase_left = s.reg[1].len;
    s.replay_addr = phys(s.reg[1], 0);
    s.inner = uint64_t(s.x) << s.k;
    s.outer = s.rep;
  };

  switch (q.state) {
    case State::idle: {
      if (!(i.in_valid && ready)) break;
      if (const EngineError e = refusal(i); e != EngineError::none) {
        d.err = true;
        d.err_code = uint32_t(e);
        break;
      }
      const uint32_t u = i.in_u & mask_u_, v = i.in_v & mask_u_;
      d.k = i.in_k & mask_k_;
      d.rep = i.in_rep & mask_rep_;
      if (v == 0 || v == u) {
        d.constant = true;
        d.constant_move = v != 0;
        d.x = u;
        begin_replay(d);
        break;
      }
      d.constant = false;
      d.x = u - v;
      d.y = v;
      io.we[0] = io.we[1] = true;  // M1 = "0", M2 = "1"
      io.waddr[0] = io.waddr[1] = 0;
      io.wbit[0] = false;
      io.wbit[1] = true;
      d.reg[0] = d.reg[1] = Reg{0, 1, false};
      if (d.x == d.y) {
        begin_replay(d);
      } else {
        const int target = d.x > d.y ? 1 : 0;
        d.reg[target].rev = true;
        d.reads_left = 1;
        d.read_addr = 0;
        d.state = State::build;
      }
      break;
    }

    case State::build: {
      if (q.reg[0].len + q.reg[1].len == p_.w) {  // one more bit would not fit
        d.err = true;
        d.err_code = uint32_t(EngineError::pattern_gt_w);
        d.state = State::idle;
        break;
      }
      const int target = q.x > q.y ? 1 : 0, source = 1 - target;
      io.re[source] = true;
      io.raddr[source] = q.read_addr;
      d.write_pending = true;
      d.write_to = target;
      d.write_addr = front_slot(q.reg[target]);
      Reg& t = d.reg[target];
      if (!t.rev) t.lo = wrap(int64_t(t.lo) - 1);
      t.len += 1;
      d.reads_left = q.reads_left - 1;
      d.read_addr = wrap(int64_t(q.read_addr) + (q.reg[source].rev ? 1 : -1));
      if (q.reads_left != 1) break;

      // The iteration's last bit: subtract, snapshot, choose the next target.
      if (target == 1) d.x = q.x - q.y;
      else d.y = q.y - q.x;
      d.snap_valid = true;
      d.snap_x = d.x;
      d.snap_y = d.y;
      d.snap[0] = d.reg[0];
      d.snap[1] = d.reg[1];
      if (d.x == d.y) {
        begin_replay(d);
        break;
      }
      const int next_target = d.x > d.y ? 1 : 0, next_source = 1 - next_target;
      d.reg[next_target].rev = !d.reg[next_target].rev;
      d.reads_left = d.reg[next_source].len;
      d.read_addr = phys(d.reg[next_source], d.reg[next_source].len - 1);
      break;
    }

    case State::replay: {
      if (q.write_pending || !(!q.out_valid || i.move_ready)) break;
      if (!q.constant) {
        const int m = q.phase == 0 ? 1 : 0;  // phase 0 reads M2, phase 1 reads M1
        io.re[m] = true;
        io.raddr[m] = q.replay_addr;
        d.out_from = m;
      }
      d.out_valid = true;
      const bool pattern_end = q.constant || (q.phase == 1 && q.phase_left == 1);
      d.out_last = pattern_end && q.inner == 1 && q.outer == 1;
      d.out_pend = pattern_end;
      if (pattern_end) {
        d.phase = 0;
        d.phase_left = q.reg[1].len;
        d.replay_addr = phys(q.reg[1], 0);
        if (q.inner != 1) {
          d.inner = q.inner - 1;
        } else if (q.outer != 1) {
          d.outer = q.outer - 1;
          d.inner = uint64_t(q.x) << q.k;
        } else {
          d.state = State::idle;
        }
      } else if (q.phase_left == 1) {
        d.phase = 1;  // M2 done: reverse(M1) follows, from M1's logical end
        d.phase_left = q.reg[0].len;
        d.replay_addr = phys(q.reg[0], q.reg[0].len - 1);
      } else {
        d.phase_left = q.phase_left - 1;
        // Forward through M2 is logical +1; backward through M1 is logical -1.
        const Reg& r = q.reg[q.phase == 0 ? 1 : 0];
        const int logical_step = q.phase == 0 ? 1 : -1;
        d.replay_addr = wrap(int64_t(q.replay_addr) + (r.rev ? -logical_step : logical_step));
      }
      break;
    }
  }
  return d;
}

CpEngineOut CpEngine::outputs() const {
  Cycle io;
  (void)next(in, io);
  const Regs& q = r_;
  CpEngineOut o;
  o.in_ready = q.state == State::idle && !q.out_valid;
  o.err = q.err;
  o.err_code = q.err ? q.err_code : 0;
  o.move_valid = q.out_valid;
  const bool bit = q.constant ? q.constant_move : rdata_[q.out_from];
  o.move = q.out_valid && bit;
  o.move_last = q.out_valid && q.out_last;
  o.move_pend = q.out_valid && q.out_pend;
  o.dbg_we1 = io.we[0];
  o.dbg_waddr1 = io.we[0] ? io.waddr[0] : 0;
  o.dbg_wbit1 = io.we[0] && io.wbit[0];
  o.dbg_we2 = io.we[1];
  o.dbg_waddr2 = io.we[1] ? io.waddr[1] : 0;
  o.dbg_wbit2 = io.we[1] && io.wbit[1];
  o.dbg_iter = q.snap_valid;
  if (q.snap_valid) {
    o.dbg_x = q.snap_x;
    o.dbg_y = q.snap_y;
    o.dbg_m1_lo = q.snap[0].lo;
    o.dbg_m1_len = q.snap[0].len;
    o.dbg_m1_rev = q.snap[0].rev;
    o.dbg_m2_lo = q.snap[1].lo;
    o.dbg_m2_len = q.snap[1].len;
    o.dbg_m2_rev = q.snap[1].rev;
  }
  return o;
}

bool CpEngine::still(const In& i) const {
  Cycle io;
  Regs d = next(i, io);
  if (i.rst) d.write_pending = d.out_valid = d.err = d.snap_valid = false, d.state = State::idle;
  return d == r_ && !io.we[0] && !io.we[1] && !io.re[0] && !io.re[1];
}

void CpEngine::tick() {
  Cycle io;
  Regs d = next(in, io);
  for (int m = 0; m < 2; ++m)  // synchronous reads see the memory before this edge's write
    if (io.re[m]) rdata_[m] = mem_[m][io.raddr[m]] != 0;
  for (int m = 0; m < 2; ++m)
    if (io.we[m]) mem_[m][io.waddr[m]] = io.wbit[m];
  if (in.rst) {  // synchronous reset of control state only, as in the RTL
    d.state = State::idle;
    d.write_pending = d.out_valid = d.err = d.snap_valid = false;
  }
  r_ = d;
}

}  // namespace cpstep::model

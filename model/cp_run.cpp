// SPDX-License-Identifier: MIT
#include "model/cp_run.h"

#include <algorithm>

#include "model/bits.h"
#include "model/cp_engine.h"

namespace cpstep::model {

CpRun::CpRun(Params p) : p_(p), aw_(CpEngineParams{p.w}.aw()) {
  banks_.assign(p_.n, std::vector<uint8_t>(std::size_t(2) << aw_, 0));
}

CpRun::Out CpRun::eval(const In& i, Regs& d, Replay& rp) const {
  const Regs& q = r_;
  const unsigned n = p_.n;
  const uint32_t lane_move = rbits_ & bits::mask(n);
  Out o;
  // A move fires when it is due, the replay registers hold it and every axis that
  // steps in it is ready; E-stop and abort stop it in the same cycle. A move is
  // counted late once: in the first cycle it is due and does not fire, or when it
  // fires after its time without having waited due (its chunk came late).
  const bool due = q.chunk_loaded && q.elapsed >= q.delay;
  const bool stopping = i.estop || i.abort;
  o.fire = q.running && q.cur_valid && !stopping && due && q.rp_valid &&
           (lane_move & ~i.pulse_ready & bits::mask(n)) == 0;
  o.stretch = q.running && due && !q.late && !stopping && (!o.fire || q.elapsed != q.delay);
  o.seg_done = o.fire && q.moves_left == 1 && q.timer_last;
  o.seg_active = q.running && q.cur_valid && !o.seg_done;
  o.step = o.fire ? lane_move : 0;
  o.dir = q.dir;
  o.running = q.running;
  o.cur_valid = q.cur_valid;
  if (o.stretch) d.late = true;
  if (o.fire) d.late = false;

  rp.lane = q.cur_lane;
  rp.next = q.rp_ptr;
  d.elapsed = q.elapsed == ~0u ? q.elapsed : q.elapsed + 1;
  auto load_chunk = [&] {
    const FifoWord& head = i.ch_head;
    o.ch_pop = true;
    d.delay = uint32_t(head[0]);
    d.timer_inc = uint32_t(bits::sext16(uint32_t(head[0] >> 32)));
    d.moves_left = uint32_t(head[0] >> 48) & 0xFFFF;
    d.timer_add2 = uint32_t(head[1]) & 0xFFFF;
    d.timer_last = (head[1] >> 16 & 1) != 0;
  };
  if (!q.chunk_loaded && i.ch_valid) {
    load_chunk();
    d.chunk_loaded = true;
  }
  if (o.fire) {
    d.elapsed = 1;
    if (q.moves_left != 1) {
      d.moves_left = (q.moves_left - 1) & 0xFFFF;
      d.delay = q.delay + q.timer_inc;
      d.timer_inc = q.timer_inc + uint32_t(bits::sext16(q.timer_add2));
    } else if (i.ch_valid) {
      load_chunk();
    } else {
      d.chunk_loaded = false;
    }
    // The replay registers fetch the next move of the running lane's patterns.
    if (!o.seg_done) {
      rp.re = true;
      for (unsigned a = 0; a < n; ++a)
        rp.next[a] = q.rp_ptr[a] == q.lm1[q.cur_lane][a] ? 0 : (q.rp_ptr[a] + 1) & bits::mask(aw_);
    }
  }
  if (o.seg_done) {
    d.cur_valid = false;
    d.rp_valid = false;
    if (q.cur_end) {
      d.running = false;
    } else if ((i.run_level & 3) == 0 && i.segq_empty && !i.build_busy && !i.fault) {
      d.running = false;
      o.fault = true;
    }
  }
  // Load the next built segment; its moving axes take their directions.
  if ((!q.cur_valid || o.seg_done) && i.run_valid && !i.fault) {
    const uint32_t dir = uint32_t(i.run_head) & bits::mask(n);
    const uint32_t moving = uint32_t(i.run_head >> n) & bits::mask(n);
    o.run_pop = true;
    d.cur_valid = true;
    d.cur_lane = unsigned(i.run_head >> (2 * n + 1) & 1);
    d.cur_end = (i.run_head >> (2 * n) & 1) != 0;
    d.dir = (q.dir & ~moving) | (dir & moving);
    // The replay registers fetch each pattern's first move.
    rp.re = true;
    rp.lane = d.cur_lane;
    d.rp_valid = true;
    rp.next.fill(0);
  }
  if (i.start && !i.fault && !q.running) {
    d.running = true;
    d.elapsed = 1;
  }
  if (i.flush) {
    d.running = false;
    d.cur_valid = false;
    d.chunk_loaded = false;
    d.cur_lane = 0;
    d.late = false;
    d.rp_valid = false;
  }
  return o;
}

CpRun::Out CpRun::eval_outputs(const In& i) const {
  Regs d = r_;
  Replay rp;
  return eval(i, d, rp);
}

uint64_t CpRun::quiet_for(const In& i) const {
  if (i.rst || i.bank_we || i.len_we) return 0;
  Regs d = r_;
  Replay rp;
  const Out o = eval(i, d, rp);
  if (o.fire || o.stretch || o.seg_done || o.ch_pop || o.run_pop || o.fault || rp.re) return 0;
  d.elapsed = r_.elapsed;
  if (!(d == r_)) return 0;
  // elapsed counts up (saturating); the next thing it can change is the pending
  // move falling due at elapsed == delay.
  if (r_.chunk_loaded && r_.elapsed < r_.delay) return r_.delay - r_.elapsed;
  return kForever;
}

void CpRun::skip(uint64_t cycles) {
  r_.elapsed = uint32_t(std::min<uint64_t>(uint64_t(r_.elapsed) + cycles, 0xFFFFFFFFu));
}

void CpRun::tick() {
  Regs d = r_;
  Replay rp;
  eval(in, d, rp);
  // The banks: the replay reads the storage as it was before this edge's write.
  const uint32_t half = 1u << aw_;
  if (rp.re) {
    uint32_t b = 0;
    for (unsigned a = 0; a < p_.n; ++a) b |= uint32_t(banks_[a][rp.lane * half + rp.next[a]]) << a;
    rbits_ = b;
    d.rp_ptr = rp.next;
  }
  if (in.bank_we && in.bank_axis < p_.n)
    banks_[in.bank_axis][unsigned(in.bank_lane) * half + (in.bank_waddr & (half - 1))] = in.bank_wbit;
  if (in.len_we && in.bank_axis < p_.n)
    d.lm1[in.bank_lane ? 1 : 0][in.bank_axis] = in.len_m1 & bits::mask(aw_);
  if (in.rst) {
    d.running = d.cur_valid = false;
    d.cur_lane = 0;
    d.chunk_loaded = d.late = d.rp_valid = false;
    d.dir = 0;
  }
  r_ = d;
}

}  // namespace cpstep::model

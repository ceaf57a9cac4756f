// SPDX-License-Identifier: MIT
#include "model/cp_run.h"

#include <algorithm>

#include "model/bits.h"
#include "model/cp_engine.h"

namespace cpstep::model {

CpRun::CpRun(Params p) : p_(p), aw_(CpEngineParams{p.w}.aw()), walker_(CpConicSerialParams{16, p.ciw, 24, p.ptimer}), ptimer_() {
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
  const CpPtimerOut pt = p_.ptimer ? ptimer_.outputs() : CpPtimerOut{};
  const bool due = p_.ptimer ? pt.due : q.chunk_loaded && q.elapsed >= q.delay;
  // In a conic, the plane axes step by the walker's presented move, in its directions;
  // its end mark must agree with the segment's last move.
  const CpConicSerialOut wo = p_.conic ? walker_.outputs() : CpConicSerialOut{};
  const bool conic_on = p_.conic && q.cur_conic;
  uint32_t plane_step = 0, plane_dir = 0;
  plane(plane_step, plane_dir);
  // A limit hit: the segment under way moves an axis toward its active limit (a plane
  // axis: the presented move steps it toward it); the run stops now as with STOP.
  const uint32_t toward = (q.moving & ((q.dir & i.lim_max) | (~q.dir & i.lim_min))) |
                          (plane_step & ((plane_dir & i.lim_max) | (~plane_dir & i.lim_min)));
  o.lim_hit = q.running && q.cur_valid && (toward & bits::mask(n)) != 0;
  const bool stopping = i.estop || i.abort || i.stop || o.lim_hit;
  const uint32_t move_steps = lane_move | plane_step;
  const bool seg_last = p_.ptimer ? q.mleft == 1 : q.moves_left == 1 && q.timer_last;
  const bool conic_ok = !conic_on || (wo.move_valid && wo.move_end == seg_last);
  o.walker_free = !wo.busy && !wo.move_valid;
  o.fire = q.running && q.cur_valid && !stopping && due && q.rp_valid && conic_ok &&
           (move_steps & ~i.pulse_ready & bits::mask(n)) == 0;
  o.fault_conic = q.running && q.cur_valid && !stopping && due && q.rp_valid && conic_on && wo.move_valid &&
                  wo.move_end != seg_last;
  o.fault = o.fault_conic;
  // On time: elapsed passed delay by less than the last clock's increment (at scale 1: equal).
  // (ptimer: a move fires in the clock it falls due or is counted late while it waits.)
  const bool on_time = p_.ptimer || q.elapsed - q.delay < q.inc;
  o.stretch = q.running && due && !q.late && !stopping && (!o.fire || !on_time);
  o.seg_done = o.fire && seg_last;
  o.seg_active = q.running && q.cur_valid && !o.seg_done;
  o.step = o.fire ? move_steps : 0;
  o.dir = (q.dir & ~plane_step) | (plane_dir & plane_step);
  o.running = q.running;
  o.torch = q.torch;
  o.cur_valid = q.cur_valid;
  if (o.stretch) d.late = true;
  if (o.fire) d.late = false;

  rp.lane = q.cur_lane;
  rp.next = q.rp_ptr;
  // Scaled time: this clock's increment is the carry of the fraction plus the scale.
  const uint32_t ph_sum = q.ph + (i.scale & 0x3FFFF);
  const uint32_t inc = ph_sum >> 16;
  d.ph = ph_sum & 0xFFFF;
  d.inc = inc;
  d.elapsed = uint32_t(std::min<uint64_t>(uint64_t(q.elapsed) + inc, 0xFFFFFFFFu));
  auto load_chunk = [&] {
    const FifoWord& head = i.ch_head;
    o.ch_pop = true;
    d.delay = uint32_t(head[0]);
    d.timer_inc = uint32_t(bits::sext16(uint32_t(head[0] >> 32)));
    d.moves_left = uint32_t(head[0] >> 48) & 0xFFFF;
    d.timer_add2 = uint32_t(head[1]) & 0xFFFF;
    d.timer_last = (head[1] >> 16 & 1) != 0;
  };
  // The phase timer's words come from the chunk queue while its buffer is free; its
  // time advances on the carry of half clocks of scaled time, from START.
  const uint32_t pa_sum = q.pa + (i.scale & 0x3FFFF);
  d.pa = p_.ptimer ? pa_sum & 0x1FFFF : 0;
  if (p_.ptimer) o.ch_pop = i.ch_valid && pt.ready;
  if (!p_.ptimer && !q.chunk_loaded && i.ch_valid) {
    load_chunk();
    d.chunk_loaded = true;
  }
  if (o.fire) {
    d.elapsed = inc;
    d.mleft = (q.mleft - 1) & bits::mask64(34);
    d.dir = (q.dir & ~plane_step) | (plane_dir & plane_step);  // a plane axis keeps its direction
    if (q.moves_left != 1) {
      d.moves_left = (q.moves_left - 1) & 0xFFFF;
      d.delay = q.delay + q.timer_inc;
      d.timer_inc = q.timer_inc + uint32_t(bits::sext16(q.timer_add2));
    } else if (i.ch_valid && !p_.ptimer) {
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
  // A conic move whose end mark disagrees: the run stops before it, the segment is
  // dropped (the latched fault then flushes the rest).
  if (o.fault_conic) {
    d.running = false;
    d.cur_valid = false;
    d.rp_valid = false;
  }
  // ptimer: the timer ran out of phases while the pending move is not due: an underrun.
  if (p_.ptimer && q.running && q.cur_valid && pt.starved && !pt.due) {
    d.running = false;
    o.fault = true;
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
    d.out = (i.run_head >> (2 * n + 2) & 1) != 0;
    d.cur_conic = p_.conic && (i.run_head >> (2 * n + 9) & 1) != 0;
    d.cur_au = uint32_t(i.run_head >> (2 * n + 6)) & 7;
    d.cur_av = uint32_t(i.run_head >> (2 * n + 3)) & 7;
    d.dir = (d.dir & ~moving) | (dir & moving);
    d.moving = moving;
    // ptimer: the segment's moves U*2^k and its length per move.
    d.mleft = (i.run_head_pt & 0xFFFFFF) << (i.run_head_pt >> 24 & 15);
    d.cur_len = uint32_t(i.run_head_pt >> 28);
    // The replay registers fetch each pattern's first move.
    rp.re = true;
    rp.lane = d.cur_lane;
    d.rp_valid = true;
    rp.next.fill(0);
  }
  if (i.start && !i.fault && !q.running) {
    d.running = true;
    d.elapsed = inc;
    d.pa = 0;
  }
  // STOP: the run is off; what is loaded and queued stays (a START goes on, the
  // pending move timed from it).
  if (i.stop || o.lim_hit) d.running = false;  // (a limit hit: then its fault's flush)
  if (i.flush) {
    d.running = false;
    d.cur_valid = false;
    d.chunk_loaded = false;
    d.cur_lane = 0;
    d.late = false;
    d.rp_valid = false;
    d.out = false;
  }
  // The torch: on while the run is on and the segment last loaded says so; off from
  // the cycle after an E-stop or an abort is seen (their flush comes in that cycle).
  d.torch = d.running && d.out;
  return o;
}

// The plane axes' steps and directions in the walker's presented move (none outside
// a conic or with no move presented).
void CpRun::plane(uint32_t& step, uint32_t& dir) const {
  step = dir = 0;
  if (!p_.conic || !r_.cur_conic) return;
  const CpConicSerialOut wo = walker_.outputs();
  if (!wo.move_valid) return;
  const uint32_t u_bit = (1u << r_.cur_au) & bits::mask(p_.n), v_bit = (1u << r_.cur_av) & bits::mask(p_.n);
  step = (wo.move_dx != 0 ? u_bit : 0) | (wo.move_dy != 0 ? v_bit : 0);
  dir = (wo.move_dx < 0 ? 0 : u_bit) | (wo.move_dy < 0 ? 0 : v_bit);
}

bool CpRun::walker_free() const {
  if (!p_.conic) return true;
  const CpConicSerialOut wo = walker_.outputs();
  return !wo.busy && !wo.move_valid;
}

uint32_t CpRun::dir() const {
  uint32_t step = 0, dir = 0;
  plane(step, dir);
  return (r_.dir & ~step) | (dir & step);
}

CpRun::Out CpRun::eval_outputs(const In& i) const {
  Regs d = r_;
  Replay rp;
  return eval(i, d, rp);
}

uint64_t CpRun::quiet_for(const In& i) const {
  if (i.rst || i.bank_we || i.len_we) return 0;
  // The conic walker turns its passes every clock: clocked while a pass runs or
  // starts; between its passes (a move presented and the next decided, waiting for
  // the run to take it) it holds still, and the span to the move's due time skips.
  if (p_.conic && (!walker_.quiet(r_.cur_valid && r_.cur_conic) || i.cw_wr || i.cw_start || i.flush)) return 0;
  Regs d = r_;
  Replay rp;
  const Out o = eval(i, d, rp);
  if (o.fire || o.stretch || o.seg_done || o.ch_pop || o.run_pop || o.fault || o.lim_hit || rp.re) return 0;
  d.elapsed = r_.elapsed;
  d.ph = r_.ph;
  d.inc = r_.inc;
  d.pa = r_.pa;
  if (!(d == r_)) return 0;
  if (p_.ptimer) return ptimer_quiet_for(i);
  // elapsed counts up by the scaled time (saturating); the next thing it can change
  // is the pending move falling due at elapsed >= delay: after c clocks with
  // ph + c·scale >= (delay - elapsed)·2^16. At scale 0 it never does.
  const uint64_t sc = i.scale & 0x3FFFF;
  if (r_.chunk_loaded && r_.elapsed < r_.delay) {
    if (sc == 0) return kForever;
    const uint64_t need = (uint64_t(r_.delay - r_.elapsed) << 16) - r_.ph;
    return (need + sc - 1) / sc;
  }
  return kForever;
}

// The phase timer's share (ptimer builds): no word for it now, no clear, and it
// advances on the carry of the fraction pa taking the scale each clock (the carry
// of half clocks, at most one a clock while the scale is at most 2): quiet up to
// the clock of its first advance that is not (CpPtimer::quiet_advs).
uint64_t CpRun::ptimer_quiet_for(const In& i) const {
  if (i.flush || (i.ch_valid && ptimer_.outputs().ready)) return 0;
  const uint64_t sc = i.scale & 0x3FFFF;
  // (No move fires in a quiet clock; a conic's next length comes from the walker.)
  const bool len_valid = r_.cur_valid && (!(p_.conic && r_.cur_conic) || walker_.outputs().move_valid);
  const std::optional<uint64_t> advs = ptimer_.quiet_advs(len_valid, uint64_t(1) << 40);
  if (!advs) return 0;
  if (!r_.running || sc == 0 || *advs == CpPtimer::kForever) return kForever;
  if (sc > (1u << 17)) return 0;   // (two carries' worth a clock: clocked one by one)
  // Clock c advances the timer for the j-th time when pa + (c+1)·sc first reaches
  // j·2^17: the advance after the quiet ones comes in clock ceil(((advs+1)·2^17 - pa) / sc) - 1.
  const bits::u128 need = ((bits::u128)(*advs + 1) << 17) - r_.pa;
  return uint64_t((need + sc - 1) / sc) - 1;
}

void CpRun::skip(uint64_t cycles, uint32_t scale) {
  if (cycles == 0) return;
  if (p_.ptimer) {
    const bits::u128 pa = r_.pa + (bits::u128)(scale & 0x3FFFF) * cycles;
    if (r_.running) ptimer_.skip_advs(uint64_t(pa >> 17));
    r_.pa = uint32_t(pa & 0x1FFFF);
  }
  const bits::u128 sc = scale & 0x3FFFF;
  const bits::u128 total = r_.ph + sc * cycles;
  const bits::u128 before_last = r_.ph + sc * (cycles - 1);
  r_.inc = uint32_t(((before_last & 0xFFFF) + sc) >> 16);
  r_.ph = uint32_t(total & 0xFFFF);
  const bits::u128 e = r_.elapsed + (total >> 16);
  r_.elapsed = e > 0xFFFFFFFFu ? 0xFFFFFFFFu : uint32_t(e);
}

void CpRun::tick() {
  Regs d = r_;
  Replay rp;
  const Out o = eval(in, d, rp);
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
  if (p_.conic) {
    walker_.in.rst = in.rst;
    walker_.in.clear = in.flush;
    walker_.in.wr = in.cw_wr;
    walker_.in.wr_sel = in.cw_sel & 7;
    walker_.in.wr_data = in.cw_data;
    walker_.in.start = in.cw_start;
    walker_.in.cont = in.cw_cont;
    walker_.in.move_ready = r_.cur_conic && o.fire;
    walker_.in.len_k = r_.cur_len;
    walker_.in.len_go = r_.cur_valid && r_.cur_conic;
  }
  // ptimer: a conic's move lengths come from the walker (before its edge).
  const CpConicSerialOut wk = p_.conic && p_.ptimer ? walker_.outputs() : CpConicSerialOut{};
  if (p_.conic) walker_.tick();
  if (p_.ptimer) {
    const CpPtimerOut pt = ptimer_.outputs();
    CpPtimerIn& pi = ptimer_.in;
    pi.rst = in.rst;
    pi.clear = in.flush;
    pi.adv = r_.running && ((r_.pa + (in.scale & 0x3FFFF)) >> 17 & 1) != 0;
    pi.wr = in.ch_valid && pt.ready;
    pi.sel = uint32_t(in.ch_head[0] >> 32) & 7;
    pi.data = uint32_t(in.ch_head[0]);
    pi.fire = o.fire;
    // The length of the move pending after a fire is owed, handed the clock after:
    // the loaded segment's L, or with a conic loaded the walker's once it presents
    // the move.
    const bool walk = p_.conic && r_.cur_valid && r_.cur_conic;
    pi.len = uint64_t(walk ? wk.len : r_.cur_len) << 30;
    pi.len_valid = !o.fire && (walk ? wk.move_valid : r_.cur_valid);
    ptimer_.tick();
  }
  if (in.rst) {
    d.running = d.cur_valid = false;
    d.cur_lane = 0;
    d.chunk_loaded = d.late = d.rp_valid = false;
    d.dir = 0;
    d.cur_conic = false;
    d.out = d.torch = false;
    d.ph = 0;
    d.inc = 1;
    d.pa = 0;
  }
  r_ = d;
}

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
#include "model/cp_core.h"

#include <algorithm>
#include <stdexcept>

#include "model/bits.h"

namespace cpstep::model {

CpCore::CpCore(Params p)
    : p_(p),
      cmd_({p.n, p.umax, p.kmax, p.caw, p.tw, p.conic, p.feed, p.inputs, p.ptimer}),
      build_({p.n, p.w, p.umax, p.saw, p.conic, p.ptimer}),
      run_({p.n, p.w, p.conic, p.ciw, p.ptimer}),
      status_({p.n, p.w, p.umax, p.kmax, p.caw, p.saw, p.tw, p.pw, p.step_high_reset, p.step_low_reset,
               p.dir_setup_reset, p.dir_hold_reset, p.step_pol_reset, p.dir_pol_reset, p.cbuf_aw,
               p.clock_hz, p.build_id, p.conic, p.ciw, p.inputs, p.feed, p.ptimer}),
      inputs_(p.n),
      // (ptimer: a segment's length word, 32 bits; N + 2 words a segment; the run
      // queue's L, k, U above its fields; the chunk queue the timer's {sel, data}.)
      seg_fifo_({std::max(p.conic ? 32 + p.n : 30 + p.n, p.ptimer ? 32u : 0u),
                 p.saw + bits::clog2(p.n + 1 + (p.ptimer ? 1 : 0))}),
      chunk_fifo_({p.ptimer ? 35u : 81u, p.caw}),
      run_fifo_({run_fields() + (p.ptimer ? 60 : 0), 1}) {
  if (p_.n < 1 || p_.n > kCoreMaxAxes) throw std::invalid_argument("cp_core: N must be 1 to 8");
  if (p_.umax < p_.w || p_.umax > 16777214)
    throw std::invalid_argument("cp_core: UMAX must be W to 2^24-2");
  if (p_.kmax > 10) throw std::invalid_argument("cp_core: KMAX must be at most 10");
  if (p_.tw < 1 || p_.tw > 16) throw std::invalid_argument("cp_core: TW must be 1 to 16");
  if (p_.pw < 32) throw std::invalid_argument("cp_core: PW must be at least 32");
  if (p_.caw < 1 || p_.caw > 15) throw std::invalid_argument("cp_core: CAW must be 1 to 15");
  pulses_.assign(p_.n, CpPulse({p_.tw, p_.pw, p_.step_pol_reset, p_.dir_pol_reset}));
}

// A pulse timer's inputs: its axis's configuration (cp_status) and direction (cp_run).
CpPulseIn CpCore::pulse_in(unsigned a, bool step) const {
  const PulseConfig& c = status_.config(a);
  CpPulseIn pi;
  pi.rst = in.rst;
  pi.cfg_step_high = c.step_high;
  pi.cfg_step_low = c.step_low;
  pi.cfg_dir_setup = c.dir_setup;
  pi.cfg_dir_hold = c.dir_hold;
  pi.cfg_step_pol = c.step_pol;
  pi.cfg_dir_pol = c.dir_pol;
  pi.cfg_new = status_.cfg_new();
  pi.dir = (run_.dir() >> a & 1) != 0;
  pi.step = step;
  return pi;
}

CpCore::Wires CpCore::settle() const {
  const unsigned n = p_.n;
  Wires w;
  w.seg = seg_fifo_.outputs();
  w.chunk = chunk_fifo_.outputs();
  w.run = run_fifo_.outputs();
  // The inputs (registered outputs); without INPUTS none is looked at.
  CpInputsIn& ii = w.i_in;
  ii.rst = in.rst;
  ii.lim_min = in.lim_min;
  ii.lim_max = in.lim_max;
  ii.probe = in.probe;
  ii.cfg_write = false;  // set with the parser's outputs below
  if (p_.inputs) w.inp = inputs_.outputs();
  // The feed (registered outputs); without FEED the timer runs at scale 1.
  CpFeedIn& fi = w.f_in;
  fi.rst = in.rst;
  fi.hold = in.ctl_hold;
  fi.resume = in.ctl_resume;
  fi.ovr = in.ctl_ovr;
  fi.ovr_val = in.ctl_ovr_val & 0xFFFF;
  if (p_.feed) {
    w.fo = feed_.outputs();
  } else {
    w.fo.scale = 0x10000;
    w.fo.feed = w.fo.override = 0;
  }
  bool pulse_busy = false;
  uint32_t pulse_ready = 0;
  for (unsigned a = 0; a < n; ++a) {
    CpPulse pulse = pulses_[a];
    pulse.in = pulse_in(a, false);
    w.pulse[a] = pulse.outputs();
    pulse_busy = pulse_busy || w.pulse[a].busy;
    pulse_ready |= uint32_t(w.pulse[a].ready) << a;
  }

  // What the status counts and reads; the READ command's port.
  CpStatusIn& s = w.st_in;
  s.rst = in.rst;
  s.estop = in.estop;
  s.running = run_.running();
  s.torch = run_.torch();
  s.cur_valid = run_.cur_valid();
  s.segq = build_.segq();
  s.build_busy = build_.busy();
  s.run_level = w.run.level;
  s.ch_level = w.chunk.level;
  for (unsigned a = 0; a < n; ++a) s.position[a] = w.pulse[a].position;
  s.feed = w.fo.feed;  // (registered: the READ port sees them now)
  s.override = w.fo.override;
  s.rd_addr0 = in.cmd_data & 0xFF;
  s.rd_addr1 = in.rd_addr & 0xFF;

  CpCmdIn& c = w.cmd_in;
  c.rst = in.rst;
  c.cmd_valid = in.cmd_valid;
  c.cmd_data = in.cmd_data;
  c.rsp_ready = in.rsp_ready;
  c.flush = in.ctl_flush;
  c.read_data = status_.read(s, s.rd_addr0);
  c.fault = status_.fault();
  c.running = run_.running();
  c.pulse_busy = pulse_busy;
  c.seg_full = w.seg.full;
  c.ch_full = w.chunk.full;
  w.cmd = cmd_.eval_outputs(c);

  CpBuildIn& b = w.b_in;
  b.rst = in.rst;
  b.fault = status_.fault();
  b.seg_valid = w.seg.out_valid;
  b.seg_head = w.seg.out_data[0];
  b.seg_commit = w.cmd.seg_commit;
  b.run_level = w.run.level;
  b.cur_valid = run_.cur_valid();
  b.walker_free = run_.walker_free();
  w.b = build_.eval_outputs(b);

  CpRunIn& r = w.r_in;
  r.rst = in.rst;
  r.estop = in.estop;
  r.start = w.cmd.start || in.ctl_start;
  // STOP, the watchdog ran out, or the seek trips on the probe.
  r.stop = in.ctl_stop || status_.wd_trip(in.kick) || w.inp.seek_stop;
  r.lim_min = w.inp.lim_min;
  r.lim_max = w.inp.lim_max;
  r.scale = w.fo.scale;
  r.abort = w.cmd.abort;
  r.fault = status_.fault();
  r.ch_valid = w.chunk.out_valid;
  r.ch_head = w.chunk.out_data;
  r.run_valid = w.run.out_valid;
  r.run_head = w.run.out_data[0] & bits::mask64(run_fields());
  if (p_.ptimer)   // {L, k, U} above the fields
    r.run_head_pt = (w.run.out_data[0] >> run_fields() | w.run.out_data[1] << (64 - run_fields())) & bits::mask64(60);
  r.run_level = w.run.level;
  r.segq_empty = build_.segq() == 0;
  r.build_busy = build_.busy();
  r.bank_we = w.b.bank_we;
  r.bank_axis = w.b.bank_axis;
  r.bank_waddr = w.b.bank_waddr;
  r.bank_wbit = w.b.bank_wbit;
  r.bank_lane = w.b.build_lane;
  r.len_we = w.b.len_we;
  r.len_m1 = w.b.len_m1;
  r.pulse_ready = pulse_ready;
  r.cw_wr = w.b.cw_wr;
  r.cw_sel = w.b.cw_sel;
  r.cw_data = w.b.cw_data;
  r.cw_start = w.b.cw_start;
  r.cw_cont = w.b.cw_cont;
  w.r = run_.eval_outputs(r);

  s.abort = w.cmd.abort;
  s.clear = w.cmd.clear;
  s.ack = in.ctl_ack;
  s.kick = in.kick;
  s.lim_hit = w.r.lim_hit && !w.inp.seek_lim;  // in the seek's mode 3 a trip, not LIMIT
  w.i_in.running = run_.running();
  w.i_in.lim_hit = w.r.lim_hit;
  s.seek = w.inp.seek;
  s.lim_min = w.inp.lim_min;
  s.lim_max = w.inp.lim_max;
  s.probe = w.inp.probe;
  s.drivers_on = w.cmd.drivers_on;
  s.drivers_off = w.cmd.drivers_off;
  s.cfg_write = w.cmd.cfg_write;
  w.i_in.cfg_write = w.cmd.cfg_write;
  w.i_in.cfg_word = in.cmd_data;
  w.f_in.cfg_write = w.cmd.cfg_write;
  w.f_in.cfg_word = in.cmd_data;
  s.cfg_word = in.cmd_data;
  s.cmd_fault = w.cmd.fault;
  s.cmd_code = w.cmd.fault_code;
  s.build_fault = w.b.fault;
  s.run_fault = w.r.fault;
  s.run_conic = w.r.fault_conic;
  s.stretch = w.r.stretch;
  s.fire = w.r.fire;
  s.seg_done = w.r.seg_done;
  s.seg_active = w.r.seg_active;
  w.st = status_.eval_outputs(s);
  // The status's flush, or an out-of-band FLUSH.
  w.b_in.flush = w.st.flush || in.ctl_flush;
  w.r_in.flush = w.st.flush || in.ctl_flush;
  return w;
}

const CpCore::Wires& CpCore::wires() const {
  if (!wires_valid_ || !(in == wires_in_)) {
    wires_ = settle();
    wires_in_ = in;
    wires_valid_ = true;
  }
  return wires_;
}

bool CpCore::lazy_holds() const {
  // Every input as the quiet found it, but the read port's address (it only chooses
  // what rd_data shows).
  if (lazy_left_ == 0) return false;
  In x = in;
  x.rd_addr = lazy_in_.rd_addr;
  return x == lazy_in_;
}

void CpCore::catch_up() {
  if (lazy_pending_) {
    cmd_.skip(lazy_pending_);
    run_.skip(lazy_pending_, scale());
    status_.skip(lazy_pending_);
    if (p_.inputs) inputs_.skip(lazy_pending_);
    if (p_.feed) feed_.skip(lazy_pending_);
    for (CpPulse& p : pulses_) p.skip(lazy_pending_);
    wires_valid_ = false;
  }
  lazy_pending_ = lazy_left_ = 0;
}

void CpCore::set_lazy(bool on) {
  catch_up();
  lazy_ = on;
  backoff_ = 0;
  backoff_left_ = 0;
}

CpCore::Out CpCore::outputs() const {
  if (lazy_holds()) {
    Out o = lazy_out_;
    o.rd_data = status_.read(lazy_st_, in.rd_addr & 0xFF);
    return o;
  }
  return outputs(wires());
}

uint32_t CpCore::read_port(uint32_t addr) const {
  if (lazy_holds()) return status_.read(lazy_st_, addr & 0xFF);
  return status_.read(wires().st_in, addr & 0xFF);
}

CpCore::Out CpCore::outputs(const Wires& w) const {
  Out o;
  o.cmd_ready = w.cmd.cmd_ready;
  o.rsp_valid = w.cmd.rsp_valid;
  o.rsp_data = w.cmd.rsp_data;
  o.rsp_addr = w.cmd.rsp_addr;
  o.rd_data = w.st.rd_data1;
  for (unsigned a = 0; a < p_.n; ++a) {
    o.step |= uint32_t(w.pulse[a].step) << a;
    o.dir |= uint32_t(w.pulse[a].dir) << a;
    // Sign-extend from PW bits.
    const unsigned shift = 64 - p_.pw;
    o.position[a] = int64_t(w.pulse[a].position << shift) >> shift;
  }
  o.running = w.r.running;
  o.torch = w.r.torch;
  o.fault = w.st.fault;
  o.stretched = w.st.stretched;
  o.err_code = w.st.err;
  o.enable = w.st.enable;
  o.status = w.st.status;
  o.stretch_count = w.st.stretch_count;
  o.moves_done = w.st.moves_done;
  o.segments_done = w.st.segments_done;
  return o;
}

namespace {

CpFifoIn fifo_in(bool rst, bool clear, bool wr, const FifoWord& data, bool commit, bool rollback, bool pop) {
  CpFifoIn f;
  f.rst = rst;
  f.clear = clear;
  f.wr = wr;
  f.wr_data = data;
  f.commit = commit;
  f.rollback = rollback;
  f.out_ready = pop;
  return f;
}

}  // namespace

CpFifoIn CpCore::seg_in(const Wires& w) const {
  return fifo_in(in.rst, w.st.flush || in.ctl_flush, w.cmd.seg_wr, {w.cmd.seg_data, 0, 0, 0}, w.cmd.seg_commit,
                 w.cmd.seg_rollback, w.b.seg_pop);
}
CpFifoIn CpCore::chunk_in(const Wires& w) const {
  return fifo_in(in.rst, w.st.flush || in.ctl_flush, w.cmd.ch_wr, w.cmd.ch_data, w.cmd.ch_commit, w.cmd.ch_rollback, w.r.ch_pop);
}
CpFifoIn CpCore::run_in(const Wires& w) const {
  const unsigned f = run_fields();
  return fifo_in(in.rst, w.st.flush || in.ctl_flush, w.b.run_wr,
                 {w.b.run_data | w.b.run_data_pt << f, w.b.run_data_pt >> (64 - f), 0, 0}, true, false, w.r.run_pop);
}

uint64_t CpCore::quiet_for(uint64_t limit) const {
  // Lazy: the quiet the last clock found, if the inputs still hold it.
  if (lazy_) return lazy_holds() ? std::min(limit, lazy_left_) : 0;
  return quiet_for(wires(), limit);
}

uint64_t CpCore::quiet_for(const Wires& w, uint64_t limit) const {
  if (in.rst || limit == 0) return 0;
  // Every part without a counter must be still: it takes no word, writes no
  // queue or bank, latches nothing. The parser may be counting its chunk
  // check's clocks (a counter, as the timers).
  uint64_t h = limit;
  if (!cmd_.still(w.cmd_in)) {
    h = std::min(h, cmd_.counting_for(w.cmd_in));
    if (h == 0) return 0;
  }
  if (!build_.still(w.b_in)) return 0;
  h = std::min(h, status_.quiet_for(w.st_in, h));  // the watchdog's count counts
  if (p_.inputs) h = std::min(h, inputs_.quiet_for(w.i_in, h));  // and the inputs' sample counter
  if (p_.feed) h = std::min(h, feed_.quiet_for(w.f_in, h));  // and the feed's tick counter (s settled or still)
  if (h == 0) return 0;
  if (!seg_fifo_.still(seg_in(w)) || !chunk_fifo_.still(chunk_in(w)) || !run_fifo_.still(run_in(w))) return 0;
  // The counters: the move timer and each pulse timer say how far they stay quiet.
  h = std::min<uint64_t>(h, run_.quiet_for(w.r_in));
  for (unsigned a = 0; a < p_.n && h > 0; ++a)
    h = std::min(h, pulses_[a].quiet_for(pulse_in(a, (w.r.step >> a & 1) != 0)));
  return h;
}

void CpCore::skip(uint64_t cycles) {
  if (lazy_holds()) {
    // Within the quiet already found: counted with the rest.
    lazy_pending_ += cycles;
    lazy_left_ -= cycles;
    return;
  }
  catch_up();
  cmd_.skip(cycles);
  run_.skip(cycles, scale());
  status_.skip(cycles);
  if (p_.inputs) inputs_.skip(cycles);
  if (p_.feed) feed_.skip(cycles);
  for (CpPulse& p : pulses_) p.skip(cycles);
  wires_valid_ = false;
}

void CpCore::tick() {
  if (lazy_holds()) {
    ++lazy_pending_;
    --lazy_left_;
    return;
  }
  catch_up();
  const Wires& w = wires();
  if (lazy_) {
    if (backoff_left_ > 0) {
      --backoff_left_;
    } else if (const uint64_t h = quiet_for(w, ~uint64_t(0))) {
      // This clock starts a quiet: count it and the next h - 1 while the inputs stay.
      lazy_in_ = in;
      lazy_out_ = outputs(w);
      lazy_st_ = w.st_in;
      lazy_pending_ = 1;
      lazy_left_ = h - 1;
      backoff_ = 0;
      return;
    } else {
      // Not quiet: look again next clock, then after 1, 2, 4 ... 16 clocks
      // while it stays so (a move's one busy clock costs one look; a segment's
      // build, hundreds of busy clocks, few).
      backoff_left_ = backoff_;
      backoff_ = std::clamp(2 * backoff_, 1u, 16u);
    }
  }
  auto edge = [&](CpFifo& f, const CpFifoIn& fi) {
    f.in = fi;
    f.tick();
  };
  edge(seg_fifo_, seg_in(w));
  edge(chunk_fifo_, chunk_in(w));
  edge(run_fifo_, run_in(w));
  // The pulse timers take this cycle's configuration and direction (registered).
  for (unsigned a = 0; a < p_.n; ++a) {
    pulses_[a].in = pulse_in(a, (w.r.step >> a & 1) != 0);
    pulses_[a].tick();
  }
  cmd_.in = w.cmd_in;
  cmd_.tick();
  build_.in = w.b_in;
  build_.tick();
  run_.in = w.r_in;
  run_.tick();
  status_.in = w.st_in;
  status_.tick();
  if (p_.inputs) {
    inputs_.in = w.i_in;
    inputs_.tick();
  }
  if (p_.feed) {
    feed_.in = w.f_in;
    feed_.tick();
  }
  wires_valid_ = false;
}

}  // namespace cpstep::model

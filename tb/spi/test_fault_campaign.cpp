// SPDX-License-Identifier: MIT
// The fault campaign (issue 17, docs/RELIABILITY.md "Fault campaign"): random jobs
// streamed to the Verilated card through its pins only, as the host streams them
// (docs/PROTOCOL.md: COMMANDS frames within the free words, each frame's result
// learnt from a POLL before the next, a refused frame sent again), and in each run
// one injection at a random cycle:
//
//   estop          the E-stop input high for a while, then low again
//   reset          rst for 1..3 cycles, anywhere (mid-frame too)
//   underrun       the host stops feeding after a segment without the end flag
//   bad_segment    a segment the core must refuse whole (codes 1..8, 15)
//   damaged_frame  a bit flipped on MOSI, or a wrong CRC
//   cs_glitch      CS high for a few cycles in the middle of a frame
//   sck_glitch     a runt SCK pulse in a low phase, or a dip in a high phase
//
// Each run is judged from the pins and the replies only:
// - every STEP/DIR pin obeys its configured pulse timing (tb/pulse/pin_checker.h:
//   no runt pulse, DIR setup and hold) and position_o counts its pulses;
// - the move events (leading STEP edges) are, in order, the moves of the segments
//   the card accepted: after move i of a segment (U, v, k) each axis stands at
//   sign·floor((2·v·i + U)/(2U)) (SPEC §1), DIR as commanded, no move before its
//   programmed time; how a run may end is set by the injection (docs/CORE.md
//   "Faults"): every segment whole (clean end, underrun), whole segments then
//   possibly the one under way whole (a refused segment), or cut anywhere but no
//   leading edge after the stop (E-stop, reset);
// - the counters, positions, READ count, status and the latched fault code in the
//   replies agree with that; the code of a bad segment is what the golden model
//   (model::CpCore) latches for it, and the test's own reading of docs/CORE.md;
// - a damaged frame's result is docs/PROTOCOL.md's, computed by the reference in
//   card_harness.h from the bits the card saw, and nothing of it executes (every
//   COMMANDS frame carries a READ, so the READ count shows each frame that ran);
// - the card recovers: (release,) CLEAR, and a following job runs exactly.
//
// CPSTEP_SEED sets the campaign's seed (default below); a failing run prints its
// seed, the injection, its cycle, what differed, and leaves waveforms in
// $CPSTEP_WAVE_DIR: an FST of the whole card (the recorded pins replayed into a
// traced instance, as tb/common/lockstep.h does) and a VCD of the card's pins.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "card_harness.h"
#include "common/lockstep.h"
#include "core/core_bench.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "pulse/pin_checker.h"
#include "sim/vcd_writer.h"

namespace cpstep::tb {
namespace {

enum class Kind { estop, reset, underrun, bad_segment, damaged_frame, cs_glitch, sck_glitch };
constexpr unsigned kKinds = 7;
const char* kind_name(Kind k) {
  static const char* const names[] = {"estop",         "reset",     "underrun",  "bad_segment",
                                      "damaged_frame", "cs_glitch", "sck_glitch"};
  return names[unsigned(k)];
}

constexpr uint32_t kEstop = 10, kUnderrun = 9;

// ---------------------------------------------------------------------------------
// The bench's own bit-level reading of a frame: bits MSB first, back to bytes.
std::vector<bool> to_bits(const std::vector<uint8_t>& b) {
  std::vector<bool> v;
  for (uint8_t x : b)
    for (int i = 7; i >= 0; --i) v.push_back(x >> i & 1);
  return v;
}
std::vector<uint8_t> to_bytes(const std::vector<bool>& bits) {
  std::vector<uint8_t> b((bits.size() + 7) / 8, 0);
  for (size_t i = 0; i < bits.size(); ++i)
    if (bits[i]) b[i / 8] |= uint8_t(0x80 >> (i % 8));
  return b;
}
// docs/PROTOCOL.md's result for the bits the card saw (card_harness.h's reference).
uint8_t result_of(const std::vector<bool>& bits, size_t free, unsigned axes) {
  const auto bytes = to_bytes(bits);
  return expected_result(bytes, bits.size(), free, axes);
}

// ---------------------------------------------------------------------------------
// Everything the card's pins did, cycle by cycle, and the pin checkers.
struct EdgeEvent {
  uint64_t cycle;
  uint32_t mask;      // axes with a leading STEP edge in this cycle
  uint32_t positive;  // their direction, read through the DIR polarity
};
struct AxisCfg {
  uint32_t high = 1, low = 1, setup = 1, hold = 1;
};

class Monitor {
 public:
  Monitor(const model::CpCoreParams& p) : p_(p) { reset_all(); }

  void observe(uint64_t c, const sim::CardIn& in, const sim::CardOut& out) {
    if (in.rst) {
      if (!in_rst_) rst_starts.push_back(c);
      in_rst_ = true;
      for (unsigned a = 0; a < p_.n; ++a) pins_[a].check(c, pulse_in(a, true), pins_of(out, a));
      cfg.assign(p_.n, AxisCfg{});
      count.assign(p_.n, 0);
      prev_fault_ = false;
      return;
    }
    in_rst_ = false;
    uint32_t mask = 0, pos = 0;
    for (unsigned a = 0; a < p_.n; ++a) {
      pins_[a].check(c, pulse_in(a, false), pins_of(out, a));
      if (pins_[a].leading()) {
        mask |= 1u << a;
        if (pins_[a].positive()) pos |= 1u << a;
        count[a] += pins_[a].positive() ? 1 : -1;
      }
    }
    if (mask) edges.push_back({c, mask, pos});
    if (out.fault && !prev_fault_) fault_rises.push_back({c, out.err_code});
    prev_fault_ = out.fault;
  }

  std::vector<std::string> errors() const {
    std::vector<std::string> e;
    for (unsigned a = 0; a < p_.n; ++a)
      for (const auto& m : pins_[a].errors()) e.push_back("axis " + std::to_string(a) + " pins: " + m);
    return e;
  }

  std::vector<AxisCfg> cfg;           // the pulse configuration the host set (in force)
  std::vector<int64_t> count;         // signed pulses since the last reset
  std::vector<EdgeEvent> edges;
  std::vector<std::pair<uint64_t, uint32_t>> fault_rises;  // cycle fault_o rose, code
  std::vector<uint64_t> rst_starts;

 private:
  void reset_all() {
    pins_.clear();
    for (unsigned a = 0; a < p_.n; ++a) pins_.emplace_back(32, p_.step_pol_reset, p_.dir_pol_reset);
    cfg.assign(p_.n, AxisCfg{});
    count.assign(p_.n, 0);
  }
  // The configuration as the pin checker sees it; the campaign keeps the reset polarities.
  model::CpPulseIn pulse_in(unsigned a, bool rst) const {
    return {rst, cfg[a].high, cfg[a].low, cfg[a].setup, cfg[a].hold, bool(p_.step_pol_reset),
            bool(p_.dir_pol_reset)};
  }
  static model::CpPulseOut pins_of(const sim::CardOut& o, unsigned a) {
    model::CpPulseOut p;
    p.step = (o.step >> a & 1) != 0;
    p.dir = (o.dir >> a & 1) != 0;
    p.position = uint64_t(uint32_t(o.position[a]));
    return p;
  }

  model::CpCoreParams p_;
  std::vector<PinChecker> pins_;
  bool in_rst_ = false, prev_fault_ = false;
};

// ---------------------------------------------------------------------------------
// The card, its recorded pins, scheduled E-stop and reset, and the SPI wire.
template <class P>
class Rig {
 public:
  static constexpr unsigned N = P::kAxes;

  explicit Rig(const model::CpCoreParams& p) : mon(p) {
    sim::CardIn in;
    in.rst = true;
    step(in);
    step(in);
  }

  sim::CardOut step(sim::CardIn in) {
    const uint64_t c = dut_.cycle();
    if (c == estop_on) estop_ = true;
    if (c == estop_off) estop_ = false;
    if (c == reset_at) rst_left_ = reset_len;
    in.estop = estop_;
    if (rst_left_ > 0) {
      in.rst = true;
      --rst_left_;
    }
    ins.push_back(in);
    last = dut_.step(in);
    outs.push_back(last);
    mon.observe(c, in, last);
    return last;
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) step({});
  }
  uint64_t cycle() const { return dut_.cycle(); }

  // Scheduled injections (cycle numbers; ~0 for none).
  uint64_t estop_on = ~uint64_t(0), estop_off = ~uint64_t(0);
  uint64_t reset_at = ~uint64_t(0);
  unsigned reset_len = 0;
  bool reset_done() const { return cycle() > reset_at + reset_len; }

  Monitor mon;
  std::vector<sim::CardIn> ins;
  std::vector<sim::CardOut> outs;
  sim::CardOut last{};

 private:
  sim::RtlDut<P> dut_;
  bool estop_ = false;
  unsigned rst_left_ = 0;
};

// A glitch on the wire during one transfer.
struct Glitch {
  enum Type { none, cs_aligned, cs_free, sck_runt, sck_dip } type = none;
  size_t bit = 0;       // after (cs_aligned, sck_runt) or during (sck_dip) this bit
  unsigned len = 0;     // cycles CS is high (cs_*), or the runt's width
  unsigned offset = 0;  // cycle within the phase where it starts
  uint64_t free_at = 0;  // cs_free: schedule index where CS rises
};

// What one transfer did on the wire.
struct Xfer {
  std::vector<uint64_t> rise;  // cycle of each master SCK rise (the bits the master clocked)
  std::vector<bool> miso;      // MISO sampled at those rises
  uint64_t cs_fall = 0, cs_rise = 0;  // the master's CS fall and final rise
  uint64_t glitch_cycle = 0;         // where the glitch started (0: none)
  uint64_t glitch_end = 0;           // first cycle after it
};

// Pin-level mode-0 master with the SpiMaster's default timing (4/4, setup 4, hold
// 4, idle 4), written out as a schedule of pin levels so a glitch can be laid on it.
template <class P>
Xfer transfer(Rig<P>& rig, const std::vector<uint8_t>& bytes, const Glitch& g = {}) {
  const std::vector<bool> bits = to_bits(bytes);
  std::vector<sim::CardIn> s;
  std::vector<size_t> sample;  // schedule indices of the master's rises
  sim::CardIn in;
  in.cs_n = false;
  in.mosi = bits[0];
  for (int i = 0; i < 4; ++i) s.push_back(in);
  size_t glitch_at = 0, glitch_len = 0;
  for (size_t i = 0; i < bits.size(); ++i) {
    in.sck = true;
    in.mosi = bits[i];
    sample.push_back(s.size());
    for (unsigned c = 0; c < 4; ++c) {
      sim::CardIn x = in;
      if (g.type == Glitch::sck_dip && g.bit == i && c == g.offset) {
        x.sck = false;
        glitch_at = s.size(), glitch_len = 1;
      }
      s.push_back(x);
    }
    if (i + 1 == bits.size()) break;
    in.sck = false;
    in.mosi = bits[i + 1];
    for (unsigned c = 0; c < 4; ++c) {
      sim::CardIn x = in;
      if (g.type == Glitch::sck_runt && g.bit == i && c >= g.offset && c < g.offset + g.len) {
        x.sck = true;
        if (!glitch_len) glitch_at = s.size();
        ++glitch_len;
      }
      if (g.type == Glitch::cs_aligned && g.bit == i && c == 2) {
        // CS high for len cycles, 2 cycles after SCK fell; then low again, and
        // a full CS setup (4 cycles) before the next bit's rise.
        glitch_at = s.size(), glitch_len = g.len;
        sim::CardIn hi = x;
        hi.cs_n = true;
        for (unsigned k = 0; k < g.len; ++k) s.push_back(hi);
        for (unsigned k = 0; k < 4; ++k) s.push_back(x);
        break;
      }
      s.push_back(x);
    }
  }
  in.sck = false;
  for (int i = 0; i < 4; ++i) s.push_back(in);  // CS hold
  const size_t rise_idx = s.size();
  for (int i = 0; i < 4; ++i) s.push_back(sim::CardIn{});  // CS idle
  if (g.type == Glitch::cs_free) {
    glitch_at = g.free_at, glitch_len = g.len;
    for (size_t k = 0; k < g.len; ++k) s[g.free_at + k].cs_n = true;
  }

  Xfer x;
  const uint64_t base = rig.cycle();
  x.cs_fall = base;
  x.cs_rise = base + rise_idx;
  if (glitch_len) x.glitch_cycle = base + glitch_at, x.glitch_end = base + glitch_at + glitch_len;
  size_t next = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const sim::CardOut o = rig.step(s[i]);
    if (next < sample.size() && sample[next] == i) {
      x.rise.push_back(base + i);
      x.miso.push_back(!o.miso_oe || o.miso);
      ++next;
    }
  }
  return x;
}

// ---------------------------------------------------------------------------------
// The golden model's verdict on one segment: the code a fresh model core latches
// when it is sent (0: accepted and built).
uint32_t model_code(const model::CpCoreParams& p, const std::vector<uint32_t>& words) {
  model::CpCore m(p);
  auto tick = [&](model::CpCoreIn in) {
    m.in = in;
    const model::CpCoreOut o = m.outputs();
    m.tick();
    return o;
  };
  model::CpCoreIn rst;
  rst.rst = true;
  tick(rst);
  tick(rst);
  for (uint32_t w : words) {
    model::CpCoreIn in;
    in.cmd_valid = true;
    in.cmd_data = w;
    in.rsp_ready = true;
    for (int n = 0;; ++n) {
      if (tick(in).cmd_ready) break;
      if (n > 100000) return 0xFFFF;
    }
  }
  const uint64_t build = uint64_t(p.n) * (2 * p.w + 1) + 1000;
  for (uint64_t n = 0; n < build; ++n) {
    model::CpCoreIn in;
    in.rsp_ready = true;
    const model::CpCoreOut o = tick(in);
    if (o.fault) return o.err_code;
  }
  return 0;
}

// ---------------------------------------------------------------------------------
// How a job's motion may end (docs/CORE.md "Faults").
enum class Ending {
  clean,     // every segment whole, the last with the end flag
  underrun,  // every segment whole, UNDERRUN raised at the last move's leading edge
  refused,   // whole segments; from the fault on, only the segment under way, whole
  cut,       // stopped anywhere, no leading edge after `stop`
};
struct Job {
  std::vector<card::WireSegment> segs;  // accepted, in order
  uint64_t start_lb = 0;                // CS rise of the frame with START (START is later)
  Ending ending = Ending::clean;
  uint64_t stop = ~uint64_t(0);   // cut: the last cycle a leading edge may have
  uint64_t fault = ~uint64_t(0);  // refused/underrun: the cycle fault_o rose
};
struct Tally {
  std::vector<int64_t> pos;
  uint64_t moves = 0, segments = 0, late = 0, cuts = 0;
};

// Checks the move events in [from, to) against the job; adds to `t`.
void verify_job(const Job& job, const std::vector<EdgeEvent>& edges, uint64_t from, uint64_t to, unsigned n,
                Tally& t, std::vector<std::string>& err) {
  auto fail = [&](uint64_t c, const std::string& what) {
    if (err.size() < 20) err.push_back("cycle " + std::to_string(c) + ": " + what);
  };
  size_t idx = 0;
  uint64_t i = 0, chunk = 0, in_chunk = 0;
  uint64_t anchor = job.start_lb;
  bool by_edge = false;
  std::vector<int64_t> rel(n, 0);
  uint64_t last_edge = 0;
  size_t front_at_fault = ~size_t(0);
  uint64_t front_moves_at_fault = 0;
  for (const EdgeEvent& e : edges) {
    if (e.cycle < from || e.cycle >= to) continue;
    if (job.ending == Ending::refused && e.cycle >= job.fault && front_at_fault == ~size_t(0)) {
      front_at_fault = idx;
      front_moves_at_fault = i;
    }
    if (job.ending == Ending::cut && e.cycle > job.stop)
      fail(e.cycle, "STEP leading edge (axes " + std::to_string(e.mask) + ") after the stop at cycle " +
                        std::to_string(job.stop));
    if (idx >= job.segs.size()) {
      fail(e.cycle, "STEP leading edge (axes " + std::to_string(e.mask) + ") with no accepted segment left to run");
      break;
    }
    if (job.ending == Ending::refused && e.cycle >= job.fault && idx != front_at_fault) {
      fail(e.cycle, "segment " + std::to_string(idx) + " moves after the fault at cycle " +
                        std::to_string(job.fault) + "; only segment " + std::to_string(front_at_fault) +
                        " (under way then) may");
      break;
    }
    const card::WireSegment& g = job.segs[idx];
    unsigned major = 0;
    while (major < n && g.v[major] != g.u) ++major;
    if (!(e.mask >> major & 1)) fail(e.cycle, "axes " + std::to_string(e.mask) + " stepped without the major axis");
    ++i;
    ++t.moves;
    last_edge = e.cycle;
    // Timing: the move's delay after the previous leading edge (or START).
    const card::WireChunk& c = g.chunks[chunk];
    const int64_t j = int64_t(in_chunk);
    const uint64_t delay = uint64_t(int64_t(c.interval) + j * c.add + int64_t(c.add2) * j * (j - 1) / 2);
    if (++in_chunk == c.count) ++chunk, in_chunk = 0;
    if (e.cycle < anchor + delay)
      fail(e.cycle, "move " + std::to_string(i) + " of segment " + std::to_string(idx) + " early: programmed " +
                        std::to_string(delay) + " cycles after cycle " + std::to_string(anchor));
    else if (by_edge && e.cycle > anchor + delay)
      ++t.late;
    anchor = e.cycle;
    by_edge = true;
    for (unsigned a = 0; a < n; ++a) {
      if (e.mask >> a & 1) {
        const bool pos = e.positive >> a & 1;
        rel[a] += pos ? 1 : -1;
        t.pos[a] += pos ? 1 : -1;
        if (pos != g.dir_positive[a])
          fail(e.cycle, "axis " + std::to_string(a) + " stepped " + (pos ? "+" : "-") + " in segment " +
                            std::to_string(idx) + ", commanded " + (g.dir_positive[a] ? "+" : "-"));
      }
      const uint64_t want_abs = (2 * uint64_t(g.v[a]) * i + g.u) / (2 * uint64_t(g.u));
      const int64_t want = g.dir_positive[a] ? int64_t(want_abs) : -int64_t(want_abs);
      if (rel[a] != want) {
        fail(e.cycle, "axis " + std::to_string(a) + " after move " + std::to_string(i) + " of segment " +
                          std::to_string(idx) + " (U " + std::to_string(g.u) + ", v " + std::to_string(g.v[a]) +
                          ", k " + std::to_string(g.k) + "): expected " + std::to_string(want) + " steps, actual " +
                          std::to_string(rel[a]));
        rel[a] = want;  // report each deviation once
      }
    }
    if (i == uint64_t(g.u) << g.k) {
      ++t.segments;
      ++idx;
      i = chunk = in_chunk = 0;
      rel.assign(n, 0);
      if (g.end) by_edge = false, anchor = ~uint64_t(0) / 2;  // nothing may follow in this job
    }
  }
  const bool partial = i > 0;
  switch (job.ending) {
    case Ending::clean:
    case Ending::underrun:
      if (idx != job.segs.size())
        fail(last_edge, "the run stopped after " + std::to_string(idx) + " whole segments and " + std::to_string(i) +
                            " moves; expected all " + std::to_string(job.segs.size()) + " segments");
      if (job.ending == Ending::underrun && job.fault != last_edge)
        fail(job.fault, "UNDERRUN raised at cycle " + std::to_string(job.fault) +
                            ", expected at the last move's leading edge, cycle " + std::to_string(last_edge));
      break;
    case Ending::refused:
      ++t.cuts;  // a move of the next segment may be counted late, then flushed
      if (partial)
        fail(last_edge, "segment " + std::to_string(idx) + " cut after " + std::to_string(i) +
                            " moves: a refused segment lets the one under way complete");
      (void)front_moves_at_fault;
      break;
    case Ending::cut:
      ++t.cuts;  // a move counted late, then cut (docs/CORE.md "Stretch")
      break;
  }
}

// ---------------------------------------------------------------------------------
// One run: a card, a job, one injection, the checks, the recovery.
template <class P>
class Run {
 public:
  static constexpr unsigned N = P::kAxes;

  Run(uint64_t seed, Kind kind, std::string where)
      : params_(model::core_params(P::kBuild)),
        seed_(seed),
        kind_(kind),
        where_(std::move(where)),
        gen_(params_, seed),
        rig_(params_) {}

  // True when every check passed.
  bool go() {
    try {
      body();
    } catch (const std::exception& e) {
      fail("exception", "no exception", e.what());
    }
    for (const auto& e : rig_.mon.errors()) fail("pins", "pulse timing per docs/PULSE.md", e);
    if (!errors_.empty()) report();
    return errors_.empty();
  }
  uint64_t cycles() const { return rig_.cycle(); }
  uint64_t moves_checked() const { return moves_checked_; }
  const std::string& variant() const { return variant_; }

 private:
  // ---- failures
  void fail(const std::string& signal, const std::string& expected, const std::string& actual) {
    if (errors_.size() < 24)
      errors_.push_back("cycle " + std::to_string(rig_.cycle()) + " " + signal + ": expected " + expected +
                        ", actual " + actual);
  }
  template <class T>
  static std::string str(const T& v) {
    std::ostringstream o;
    if constexpr (requires { v.begin(); }) {
      o << "{";
      for (const auto& x : v) o << " " << x;
      o << " }";
    } else {
      o << v;
    }
    return o.str();
  }
  template <class A, class B>
  void expect_eq(const std::string& signal, const A& expected, const B& actual) {
    if (!(expected == actual)) fail(signal, str(expected), str(actual));
  }
  void report() {
    std::ostringstream m;
    const char* card = N == 2 ? "small" : "default";
    m << "fault campaign run failed: run seed " << seed_ << " (" << where_ << "), card " << card << ", injection "
      << kind_name(kind_) << " at cycle " << inject_cycle_ << " (" << detail_ << ")\n";
    for (const auto& e : errors_) m << "  " << e << "\n";
    m << "  waveforms: " << write_waves();
    ADD_FAILURE() << m.str();
  }
  std::string write_waves() {
    const char* wave_dir = std::getenv("CPSTEP_WAVE_DIR");
    std::filesystem::path d = wave_dir ? wave_dir : ".";
    std::filesystem::create_directories(d);
    const std::string stem = "FaultCampaign." + std::string(N == 2 ? "small" : "default") + ".seed" +
                             std::to_string(seed_) + "." + kind_name(kind_);
    const std::string fst = (d / (stem + ".fst")).string(), vcd = (d / (stem + ".vcd")).string();
    {
      sim::RtlDut<P> traced(fst);
      for (const sim::CardIn& in : rig_.ins) traced.step(in);
    }
    std::ofstream os(vcd);
    sim::VcdWriter w(os, "1ns", "card");
    const int clk = w.add_signal("clk"), rst = w.add_signal("rst"), sck = w.add_signal("spi_sck"),
              cs = w.add_signal("spi_cs_n"), mosi = w.add_signal("spi_mosi"), miso = w.add_signal("spi_miso"),
              estop = w.add_signal("estop"), step = w.add_signal("step", N), dir = w.add_signal("dir", N),
              en = w.add_signal("enable"), run = w.add_signal("running"), flt = w.add_signal("fault"),
              code = w.add_signal("err_code", 8);
    std::vector<int> pos;
    for (unsigned a = 0; a < N; ++a) pos.push_back(w.add_signal("position" + std::to_string(a), 32));
    for (size_t c = 0; c < rig_.ins.size(); ++c) {
      const sim::CardIn& i = rig_.ins[c];
      const sim::CardOut& o = rig_.outs[c];
      w.set(clk, 0);
      w.set(rst, i.rst), w.set(sck, i.sck), w.set(cs, i.cs_n), w.set(mosi, i.mosi), w.set(estop, i.estop);
      w.set(miso, o.miso_oe ? o.miso : 1), w.set(step, o.step), w.set(dir, o.dir), w.set(en, o.enable);
      w.set(run, o.running), w.set(flt, o.fault), w.set(code, o.err_code);
      for (unsigned a = 0; a < N; ++a) w.set(pos[a], uint32_t(o.position[a]));
      w.sample(2 * c);
      w.set(clk, 1);
      w.sample(2 * c + 1);
    }
    return fst + " (every signal) and " + vcd + " (the pins; cycle n spans time 2n..2n+1)";
  }

  // ---- the host
  card::Reply decode(const Xfer& x) {
    std::vector<bool> bits(x.miso.begin(), x.miso.end());
    bits.resize(8 * card::reply_bytes(N), false);
    return card::decode_reply(to_bytes(bits), N);
  }
  card::Reply poll() {
    const Xfer x = transfer(rig_, card::encode_poll(++seq_, N));
    const card::Reply r = decode(x);
    if (!r.ok() && !reset_touches(x)) fail("reply", "a well-formed reply", r.error);
    if (rig_.reset_at != ~uint64_t(0) && x.cs_fall > rig_.reset_at + rig_.reset_len && !first_after_reset_)
      first_after_reset_ = r;
    return r;
  }
  // Word 1 (free words) of the reply that began at the master's bit `from`.
  static size_t reply_free(const Xfer& x, size_t from) {
    if (x.miso.size() < from + 48) return P::kCbufWords;
    const auto b = to_bytes(std::vector<bool>(x.miso.begin() + long(from), x.miso.begin() + long(from) + 48));
    return size_t(b[4]) << 8 | b[5];
  }
  // The scheduled reset falls within (or just before) this transfer.
  bool reset_touches(const Xfer& x) const {
    return rig_.reset_at != ~uint64_t(0) && rig_.reset_at <= x.cs_rise + 8 && rig_.reset_at + 8 >= x.cs_fall;
  }
  std::vector<uint8_t> frame_bytes(uint8_t seq, const std::vector<uint32_t>& words) const {
    return card::encode_frame(card::FrameType::commands, seq, words, card::reply_bytes(N));
  }
  // Sends a COMMANDS frame and learns its result from a POLL; true when it was
  // accepted (and then `cs_rise` is where its words became the card's).
  bool command(const std::vector<uint32_t>& words, uint64_t* cs_rise = nullptr) {
    const uint8_t seq = ++seq_;
    const Xfer x = transfer(rig_, frame_bytes(seq, words));
    if (cs_rise) *cs_rise = x.cs_rise;
    const uint64_t r = rig_.reset_at;
    const bool reset_here = r != ~uint64_t(0) && r >= x.cs_fall;
    if (reset_here && r <= x.cs_rise) return false;  // cut by the reset: it never executes
    last_ = poll();
    // A reset after CS rose: the card took the frame and may have run some of it
    // before the reset, but its result is lost; the moves are judged as a cut job.
    if (reset_here && r < rig_.cycle()) return true;
    if (last_.last_seq != seq || last_.last_result != 0) {
      fail("last_result", "OK for frame seq " + std::to_string(seq),
           std::to_string(last_.last_result) + " for seq " + std::to_string(last_.last_seq));
      return false;
    }
    ++reads_;
    return true;
  }
  // Sends an URGENT frame (docs/PROTOCOL.md "Out of band") and learns its result.
  void urgent(uint32_t bits) {
    const uint8_t seq = ++seq_;
    transfer(rig_, card::encode_frame(card::FrameType::urgent, seq, std::vector<uint32_t>{bits},
                                      card::reply_bytes(N)));
    last_ = poll();
    if (last_.last_seq != seq || last_.last_result != 0)
      fail("last_result", "OK for URGENT frame seq " + std::to_string(seq),
           std::to_string(last_.last_result) + " for seq " + std::to_string(last_.last_seq));
  }
  std::vector<uint32_t> control(bool start, bool abort, bool clear) {
    std::vector<uint32_t> w;
    card::encode_control(start, abort, clear, w);
    card::encode_read(card::Register::id, 0, w);
    return w;
  }
  // Polls until the card is stopped and has taken every word (or gives up).
  void wait_idle(uint64_t max_cycles = 3'000'000) {
    const uint64_t until = rig_.cycle() + max_cycles;
    for (;;) {
      last_ = poll();
      if (!(last_.status & 1) && !(last_.flags & card::reply_flag::busy)) return;
      if (rig_.cycle() > until) {
        fail("status", "stopped and the buffer empty", "still running or busy after " + std::to_string(max_cycles));
        return;
      }
      rig_.idle(1500);
    }
  }
  bool faulted() const { return (last_.status >> 1 & 1) != 0; }

  // ---- the job
  card::WireSegment segment(bool end, uint64_t min_cycles) {
    JobShape shape;
    shape.max_moves = 300;
    shape.max_chunks = 4;
    shape.max_delay = 40;
    card::WireSegment s = gen_.segment(shape, end);
    const uint64_t have = JobGen::programmed_cycles(s);
    if (have < min_cycles) {
      card::WireChunk& c = s.chunks.front();
      c.interval += uint32_t((min_cycles - have + c.count - 1) / c.count);
    }
    return s;
  }
  std::vector<card::WireSegment> make_job(unsigned n, uint64_t first_min, uint64_t min) {
    std::vector<card::WireSegment> j;
    for (unsigned i = 0; i < n; ++i) j.push_back(segment(i + 1 == n, i == 0 ? first_min : min));
    return j;
  }
  std::vector<uint32_t> words_of(const card::WireSegment& s, bool start) {
    std::vector<uint32_t> w;
    card::encode_segment(s, w);
    if (start) card::encode_control(true, false, false, w);
    card::encode_read(card::Register::id, 0, w);
    return w;
  }
  void configure() {
    std::vector<uint32_t> w;
    std::vector<AxisCfg> cfg(N);
    const uint32_t top = std::min<uint32_t>(12, (1u << params_.tw) - 1);
    for (unsigned a = 0; a < N; ++a) {
      cfg[a] = {gen_.uniform(1, top), gen_.uniform(1, top), gen_.uniform(0, top), gen_.uniform(0, top)};
      card::encode_config(a, card::ConfigField::step_high, cfg[a].high, w);
      card::encode_config(a, card::ConfigField::step_low, cfg[a].low, w);
      card::encode_config(a, card::ConfigField::dir_setup, cfg[a].setup, w);
      card::encode_config(a, card::ConfigField::dir_hold, cfg[a].hold, w);
    }
    card::encode_drivers(true, w);
    card::encode_read(card::Register::id, 0, w);
    rig_.mon.cfg = cfg;  // in force before any pulse: the pins are idle until START
    command(w);
  }

  // A bad segment for one of docs/CORE.md's codes, made from a valid one; returns
  // the code the test reads docs/CORE.md to give.
  uint32_t make_bad(card::WireSegment& s) {
    for (uint64_t tries = 0;;) {
      s = segment(false, 0);
      // Every code in turn over consecutive runs of this kind (seeds 7 apart).
      const uint32_t pick = uint32_t((seed_ + tries++) % 9);
      auto chunk_with = [&](uint32_t lo, uint32_t hi) -> card::WireChunk* {
        for (auto& c : s.chunks)
          if (c.count >= lo && c.count <= hi) return &c;
        return nullptr;
      };
      switch (pick) {
        case 0: {  // SEG_U
          s.u = gen_.chance(0.5) ? 0 : params_.umax + 1;
          for (auto& v : s.v) v = std::min(v, s.u);
          s.v[0] = s.u;
          return 1;
        }
        case 1:  // SEG_V_GT_U
          s.v[gen_.uniform(0, N - 1)] = s.u + 1;
          return 2;
        case 2:  // SEG_K
          s.k = params_.kmax + 1;
          return 3;
        case 3:  // SEG_CHUNKS: none
          s.chunks.clear();
          return 4;
        case 4:  // SEG_CHUNK_ZERO
          if (gen_.chance(0.5)) s.chunks[gen_.uniform(0, uint32_t(s.chunks.size() - 1))].interval = 0;
          else s.chunks[gen_.uniform(0, uint32_t(s.chunks.size() - 1))].count = 0;
          return 5;
        case 5: {  // SEG_DELAY: the last delay below 1 or past 2^32 - 1
          card::WireChunk* c = chunk_with(2, 65535);
          if (!c) continue;
          c->add2 = 0;
          if (gen_.chance(0.5)) {
            c->interval = gen_.uniform(1, 1000);
            c->add = int16_t(-int32_t(c->interval));
          } else {
            c->interval = 0xFFFFFFFFu - gen_.uniform(0, 3);
            c->add = int16_t(gen_.uniform(4, 100));
          }
          return 6;
        }
        case 6: {  // SEG_COUNT_SUM: one move fewer (the delays left stay in range: they are monotone)
          card::WireChunk* c = chunk_with(2, 65535);
          if (!c) continue;
          c->count -= 1;
          return 7;
        }
        case 7: {  // SEG_PATTERN: U / gcd(U, v) > W, everything else valid
          uint32_t u = params_.w + 1;
          auto prime = [](uint32_t x) {
            for (uint32_t d = 2; d * d <= x; ++d)
              if (x % d == 0) return false;
            return true;
          };
          while (!prime(u)) ++u;
          s.u = u;
          s.k = 0;
          for (unsigned a = 0; a < N; ++a) s.v[a] = a == 0 ? u : gen_.uniform(1, u - 1);
          s.chunks = {{gen_.uniform(5, 40), uint16_t(u), 0, 0}};
          return 8;
        }
        default: {  // SEG_ADD2: the increments change sign, the delays stay in range
          card::WireChunk* c = chunk_with(3, 200);
          if (!c) continue;
          const int64_t cnt = c->count;
          const bool up = gen_.chance(0.5);
          c->add = int16_t(up ? 5 : -5);
          c->add2 = int16_t(up ? -10 : 10);
          // Delays interval + j·add + add2·j(j−1)/2, j < count: keep them all in 1..2^32−1.
          c->interval = uint32_t(20 + 5 * cnt * cnt);
          return 15;
        }
      }
    }
  }

  // ---- the run
  void body() {
    configure();
    if (!errors_.empty()) return;

    const unsigned nseg = gen_.uniform(3, 6);
    // Long enough segments that the stream keeps ahead of the card over SPI, also
    // with a refused frame sent again (docs/PROTOCOL.md "Flow control").
    std::vector<card::WireSegment> job = make_job(nseg, 40000, 16000);
    uint64_t total = 0;
    for (const auto& s : job) total += JobGen::programmed_cycles(s);

    // The frames: segment 0 with START, then one segment each (and a READ each).
    std::vector<std::vector<uint32_t>> frames;
    std::vector<int> frame_seg;  // index into job, -1 for the bad segment
    for (unsigned i = 0; i < nseg; ++i) {
      frames.push_back(words_of(job[i], i == 0));
      frame_seg.push_back(int(i));
    }
    const uint64_t t0 = rig_.cycle();
    size_t inject_frame = ~size_t(0), stop_after = ~size_t(0), reset_frame = ~size_t(0);
    uint32_t bad_code = 0;
    switch (kind_) {
      case Kind::estop:
        rig_.estop_on = t0 + gen_.uniform(0, uint32_t(total + 20000));
        rig_.estop_off = rig_.estop_on + gen_.uniform(1, 20000);
        inject_cycle_ = rig_.estop_on;
        detail_ = "E-stop pin high cycles " + std::to_string(rig_.estop_on) + ".." + std::to_string(rig_.estop_off - 1);
        break;
      case Kind::reset:
        rig_.reset_len = gen_.uniform(1, 3);
        if (gen_.chance(0.5)) {
          rig_.reset_at = t0 + gen_.uniform(0, uint32_t(total + 20000));
          inject_cycle_ = rig_.reset_at;
        } else {
          reset_frame = gen_.uniform(0, nseg - 1);  // in the middle of this frame's transfer
        }
        detail_ = "rst high for " + std::to_string(rig_.reset_len) + " cycles";
        break;
      case Kind::underrun:
        stop_after = gen_.uniform(0, nseg - 2);
        detail_ = "the host stops after segment " + std::to_string(stop_after) + " of " + std::to_string(nseg);
        break;
      case Kind::bad_segment: {
        card::WireSegment bad;
        const uint32_t want = make_bad(bad);
        std::vector<uint32_t> w;
        card::encode_segment(bad, w);
        bad_code = model_code(params_, w);
        if (bad_code != want)
          fail("model", "code " + std::to_string(want) + " (docs/CORE.md's table for this segment)",
               "the model latches " + std::to_string(bad_code));
        const size_t at = gen_.uniform(1, nseg - 1);  // after START's frame
        card::encode_read(card::Register::id, 0, w);
        frames.insert(frames.begin() + long(at), w);
        frame_seg.insert(frame_seg.begin() + long(at), -1);
        inject_frame = at;
        variant_ = "code " + std::to_string(bad_code);
        detail_ = "segment " + std::to_string(at) + " refused with code " + std::to_string(bad_code) + " (" +
                  card::error_name(bad_code).name + ")";
        break;
      }
      case Kind::damaged_frame:
      case Kind::cs_glitch:
      case Kind::sck_glitch:
        inject_frame = gen_.uniform(0, nseg - 1);
        break;
    }

    // Stream the job.
    Job main;
    main.start_lb = ~uint64_t(0);
    last_ = poll();
    for (size_t k = 0; k < frames.size();) {
      if (rig_.reset_at != ~uint64_t(0) && rig_.cycle() >= rig_.reset_at) break;
      if (faulted()) break;  // the host stops streaming at a fault
      if (stop_after != ~size_t(0) && k > stop_after) {
        inject_cycle_ = rig_.cycle();
        break;
      }
      if (frames[k].size() > last_.free_words) {
        rig_.idle(400);
        last_ = poll();
        continue;
      }
      uint64_t cs_rise = 0;
      bool accepted;
      if (k == reset_frame && rig_.reset_at == ~uint64_t(0)) {
        rig_.reset_at = rig_.cycle() + 4 + gen_.uniform(0, uint32_t(64 * card::frame_bytes(frames[k].size())));
        inject_cycle_ = rig_.reset_at;
      }
      if (k == inject_frame && kind_ != Kind::bad_segment && !injected_) {
        injected_ = true;
        accepted = inject_on_wire(frames[k], cs_rise);
      } else {
        accepted = command(frames[k], &cs_rise);
        if (k == inject_frame) inject_cycle_ = cs_rise;
      }
      if (!accepted) {
        if (rig_.reset_at != ~uint64_t(0) && rig_.cycle() >= rig_.reset_at) break;
        if (!errors_.empty()) return;
        continue;  // refused on the wire: sent again
      }
      if (frame_seg[k] >= 0 && !(bad_code && k > inject_frame)) main.segs.push_back(job[size_t(frame_seg[k])]);
      if (k == 0) main.start_lb = cs_rise;
      ++k;
    }
    if (!errors_.empty()) return;

    // Let every scheduled injection happen, and the card settle.
    while (rig_.cycle() <= rig_.estop_on && rig_.estop_on != ~uint64_t(0)) rig_.idle(1000);
    if (kind_ == Kind::reset && rig_.reset_at == ~uint64_t(0)) {  // the host stopped before that frame
      rig_.reset_at = rig_.cycle() + 10;
      inject_cycle_ = rig_.reset_at;
    }
    while (rig_.reset_at != ~uint64_t(0) && !rig_.reset_done()) rig_.idle(1000);
    if (kind_ != Kind::reset) wait_idle();

    // How the job may have ended, and the code.
    uint32_t want_code = 0;
    const auto& fr = rig_.mon.fault_rises;
    auto first_fault_after = [&](uint64_t c) -> const std::pair<uint64_t, uint32_t>* {
      for (const auto& f : fr)
        if (f.first >= c) return &f;
      return nullptr;
    };
    switch (kind_) {
      case Kind::estop: {
        variant_ = rig_.outs[rig_.estop_on].running ? "while running" : "while stopped";
        main.ending = Ending::cut;
        main.stop = rig_.estop_on + 2;  // two synchronizer flops: seen in +2; no edge after it
        want_code = kEstop;
        const auto* f = first_fault_after(t0);
        if (!f) fail("fault_o", "rises at cycle " + std::to_string(rig_.estop_on + 3), "never rose");
        else {
          expect_eq("fault_o rise cycle (E-stop)", rig_.estop_on + 3, f->first);
          expect_eq("err_code_o at the E-stop", kEstop, f->second);
        }
        // Drivers off from the cycle after it is seen, while it is held.
        for (uint64_t c = rig_.estop_on + 3; c < std::min<uint64_t>(rig_.estop_off, rig_.outs.size()); ++c)
          if (rig_.outs[c].enable) {
            fail("enable_o", "0 while the E-stop is held", "1 at cycle " + std::to_string(c));
            break;
          }
        break;
      }
      case Kind::reset:
        variant_ = std::string(rig_.outs[rig_.reset_at - 1].running ? "running, " : "stopped, ") +
                   (rig_.ins[rig_.reset_at].cs_n ? "CS high" : "mid-frame");
        main.ending = Ending::cut;
        main.stop = rig_.reset_at - 1;
        break;
      case Kind::underrun: {
        main.ending = Ending::underrun;
        want_code = kUnderrun;
        const auto* f = first_fault_after(t0);
        if (!f) fail("fault_o", "UNDERRUN after the last segment", "never rose");
        else main.fault = f->first;
        break;
      }
      case Kind::bad_segment: {
        main.ending = Ending::refused;
        want_code = bad_code;
        const auto* f = first_fault_after(t0);
        if (!f) fail("fault_o", "code " + std::to_string(bad_code), "never rose");
        else main.fault = f->first;
        break;
      }
      default:
        main.ending = Ending::clean;
        if (const auto* f = first_fault_after(t0))
          fail("fault_o", "no fault", "code " + std::to_string(f->second) + " at cycle " + std::to_string(f->first));
        break;
    }
    if (!main.segs.empty() && main.start_lb == ~uint64_t(0)) fail("bench", "START sent", "not sent");

    if (kind_ == Kind::reset) {
      after_reset(main);
    } else {
      // The fault code, latched, in the reply and on the pins; the queues flushed.
      const card::Status st = card::decode_status(last_.status);
      expect_eq("status error code", want_code, st.err_code);
      expect_eq("err_code_o", want_code, rig_.last.err_code);
      expect_eq("status fault", want_code != 0, st.fault);
      expect_eq("status segments queued", 0u, st.segments_queued);
      expect_eq("status chunks queued", 0u, st.chunks_queued);
      jobs_.push_back(main);
    }

    // E-stop still held: CLEAR is refused. Then released.
    if (kind_ == Kind::estop) {
      if (rig_.cycle() + 12000 < rig_.estop_off) {  // held through the CLEAR frame and the POLL
        command(control(false, false, true));
        const card::Status st = card::decode_status(last_.status);
        expect_eq("status error code after CLEAR under E-stop", kEstop, st.err_code);
        expect_eq("reply E-stop flag", true, (last_.flags & card::reply_flag::estop) != 0);
        expect_eq("status E-stop bit", true, st.estop);
      }
      while (rig_.cycle() < rig_.estop_off + 4) rig_.idle(std::min<uint64_t>(1000, rig_.estop_off + 4 - rig_.cycle()));
    }
    if (!errors_.empty()) return;
    recover();
  }

  // The injection on the wire for the frames' kinds; returns whether the frame (as
  // the card saw it) was accepted, and checks its result against the protocol.
  bool inject_on_wire(const std::vector<uint32_t>& words, uint64_t& cs_rise) {
    const uint8_t seq = ++seq_;
    const uint8_t prev_seq = uint8_t(seq - 1);  // the POLL just before
    const std::vector<uint8_t> bytes = frame_bytes(seq, words);
    const std::vector<bool> bits = to_bits(bytes);
    const size_t frame_bits = 8 * card::frame_bytes(words.size());
    std::ostringstream d;

    if (kind_ == Kind::damaged_frame) {
      std::vector<uint8_t> bad = bytes;
      const size_t len = card::frame_bytes(words.size());
      for (;;) {
        bad = bytes;
        if (gen_.chance(0.5)) {
          const size_t bit = gen_.uniform(0, uint32_t(frame_bits - 1));
          bad[bit / 8] ^= uint8_t(0x80 >> (bit % 8));
          d.str("");
          d << "bit " << bit << " of the frame flipped on MOSI";
          variant_ = "bit flipped";
        } else {
          const uint16_t x = uint16_t(gen_.uniform(1, 0xFFFF));
          bad[len - 2] ^= uint8_t(x >> 8);
          bad[len - 1] ^= uint8_t(x);
          d.str("");
          d << "CRC xor 0x" << std::hex << x;
          variant_ = "wrong CRC";
        }
        if (result_of(to_bits(bad), P::kCbufWords, N) != 0) break;
      }
      const Xfer x = transfer(rig_, bad);
      inject_cycle_ = x.cs_fall;
      const size_t free = reply_free(x, 0);
      const uint8_t want = result_of(to_bits(bad), free, N);
      detail_ = d.str() + ", result " + card::frame_result_name(want).name;
      last_ = poll();
      expect_eq("last_result of the damaged frame", unsigned(want), unsigned(last_.last_result));
      expect_eq("last_seq after the damaged frame", unsigned(bad[1]), unsigned(last_.last_seq));
      cs_rise = x.cs_rise;
      return false;  // refused: the host sends it again
    }

    if (kind_ == Kind::cs_glitch) {
      const bool aligned = gen_.chance(0.5);
      Glitch g;
      if (aligned) {
        // After bit i (not the frame's last), CS high for 2..6 cycles, then a new
        // frame from bit i + 1: docs/PROTOCOL.md decides both halves exactly.
        for (;;) {
          g.type = Glitch::cs_aligned;
          g.bit = gen_.uniform(0, uint32_t(frame_bits - 2));
          g.len = gen_.uniform(2, 6);
          const std::vector<bool> b(bits.begin() + long(g.bit) + 1, bits.end());
          if (result_of(b, P::kCbufWords, N) != 0) break;
        }
        const Xfer x = transfer(rig_, bytes, g);
        inject_cycle_ = x.glitch_cycle;
        const std::vector<bool> a(bits.begin(), bits.begin() + long(g.bit) + 1);
        const std::vector<bool> b(bits.begin() + long(g.bit) + 1, bits.end());
        // Frame B's own reply (its word 1: free words) is what the card sent after CS fell again.
        const size_t free = reply_free(x, g.bit + 1);
        const uint8_t want_a = result_of(a, P::kCbufWords, N), want_b = result_of(b, free, N);
        d << "CS high for " << g.len << " cycles after bit " << g.bit << " of " << frame_bits
          << " (aligned): results " << card::frame_result_name(want_a).name << ", "
          << card::frame_result_name(want_b).name;
        detail_ = d.str();
        variant_ = "between bits, 2-6 cycles";
        expect_eq("result of the first half (TRUNCATED)", 1u, unsigned(want_a));
        const uint8_t seq_after_a = a.size() >= 16 ? seq : prev_seq;
        const uint8_t seq_after_b = b.size() >= 16 ? to_bytes(b)[1] : seq_after_a;
        last_ = poll();
        expect_eq("last_result after the CS glitch (the second half)", unsigned(want_b), unsigned(last_.last_result));
        expect_eq("last_seq after the CS glitch", unsigned(seq_after_b), unsigned(last_.last_seq));
        cs_rise = x.cs_rise;
        return false;
      }
      // Free-running: CS high for 1..6 cycles while SCK goes on, at a cycle of the
      // frame's bits. The first half is cut (TRUNCATED); the rest is refused.
      // Rises while CS is high, and one just at the CS edges, may or may not count.
      g.type = Glitch::cs_free;
      g.len = gen_.uniform(1, 6);
      const size_t bit = gen_.uniform(1, uint32_t(frame_bits - 4));
      g.free_at = 4 + 8 * bit + gen_.uniform(0, 7);  // schedule index within bit `bit`'s period
      const Xfer x = transfer(rig_, bytes, g);
      inject_cycle_ = x.glitch_cycle;
      // The bits whose rises came at least 2 cycles after CS fell again, give or take one.
      size_t first = 0;
      while (first < x.rise.size() && x.rise[first] < x.glitch_end) ++first;
      std::vector<uint8_t> cands;
      for (size_t f = first >= 1 ? first - 1 : 0; f <= first + 1 && f < bits.size(); ++f)
        cands.push_back(result_of(std::vector<bool>(bits.begin() + long(f), bits.end()), P::kCbufWords, N));
      d << "CS high for " << g.len << " cycles at cycle " << x.glitch_cycle << " (in bit " << bit << " of "
        << frame_bits << ", SCK running on)";
      detail_ = d.str();
      variant_ = g.len < 2 ? "SCK running, 1 cycle" : "SCK running, 2-6 cycles";
      last_ = poll();
      const bool unseen_ok = g.len < 2;  // below the protocol's 2-cycle minimum the card may miss it
      if (unseen_ok && last_.last_result == 0 && last_.last_seq == seq) {
        detail_ += "; the card did not see CS high";
        variant_ += ", not seen";
        ++reads_;
        cs_rise = x.cs_rise;
        return true;
      }
      if (std::find(cands.begin(), cands.end(), last_.last_result) == cands.end() || last_.last_result == 0) {
        std::ostringstream c;
        for (uint8_t r : cands) c << unsigned(r) << " ";
        fail("last_result after the CS glitch", "one of { " + c.str() + "} (never 0)",
             std::to_string(last_.last_result));
      }
      cs_rise = x.cs_rise;
      return false;
    }

    // SCK glitch: a runt pulse in a low phase (1 or 2 cycles, between two bits), or
    // a one-cycle dip in a high phase; both are an extra rising edge. SCK high or
    // low for fewer than 3 cycles is below docs/PROTOCOL.md's minimum, so the card
    // may take the extra bit (the MOSI level then) or miss it: the result must be
    // the protocol's for one of the two, and the frame runs exactly when it is OK.
    Glitch g;
    std::vector<bool> dup;
    for (;;) {
      if (gen_.chance(0.5)) {
        g.type = Glitch::sck_runt;
        g.bit = gen_.uniform(0, uint32_t(frame_bits - 2));
        g.len = gen_.uniform(1, 2);
        g.offset = gen_.uniform(1, 3 - g.len);
        dup = bits;  // MOSI carries bit + 1 in that low phase
        dup.insert(dup.begin() + long(g.bit) + 1, bits[g.bit + 1]);
      } else {
        g.type = Glitch::sck_dip;
        g.bit = gen_.uniform(0, uint32_t(frame_bits - 1));
        g.len = 1;
        g.offset = gen_.uniform(1, 2);
        dup = bits;
        dup.insert(dup.begin() + long(g.bit), bits[g.bit]);
      }
      if (result_of(dup, P::kCbufWords, N) != 0) break;
    }
    const Xfer x = transfer(rig_, bytes, g);
    inject_cycle_ = x.glitch_cycle;
    const uint8_t want_dup = result_of(dup, P::kCbufWords, N);
    d << (g.type == Glitch::sck_runt ? "runt SCK pulse of " + std::to_string(g.len) + " cycle(s) after bit "
                                     : "SCK dip of 1 cycle in bit ")
      << g.bit << " of " << frame_bits << ": result " << card::frame_result_name(want_dup).name
      << " if the card takes the extra bit, OK if not";
    detail_ = d.str();
    variant_ = g.type == Glitch::sck_runt ? "runt pulse" : "dip";
    last_ = poll();
    cs_rise = x.cs_rise;
    if (last_.last_result == 0) {
      detail_ += "; the card missed the glitch";
      variant_ += ", missed";
      expect_eq("last_seq after the SCK glitch (missed)", unsigned(seq), unsigned(last_.last_seq));
      ++reads_;
      return true;
    }
    expect_eq("last_seq after the SCK glitch", unsigned(to_bytes(dup)[1]), unsigned(last_.last_seq));
    expect_eq("last_result after the SCK glitch", unsigned(want_dup), unsigned(last_.last_result));
    variant_ += ", extra bit taken";
    ++sck_seen_;
    return false;
  }

  // After a reset: counters, positions, status at zero, nothing moves after it,
  // the fresh flag when it fell between frames; then a new phase.
  void after_reset(Job& main) {
    const uint64_t r = rig_.reset_at;
    bool between = true;
    for (uint64_t c = r >= 8 ? r - 8 : 0; c < r + rig_.reset_len + 8 && c < rig_.ins.size(); ++c)
      if (!rig_.ins[c].cs_n) between = false;
    // The phase before: checked by its edges only (the counters are gone).
    Tally t;
    t.pos.assign(N, 0);
    std::vector<std::string> err;
    verify_job(main, rig_.mon.edges, main.start_lb == ~uint64_t(0) ? 0 : main.start_lb, r, N, t, err);
    for (const auto& e : err) fail("moves before the reset", "as the segments command", e);
    moves_checked_ += t.moves;
    for (const auto& e : rig_.mon.edges)
      if (e.cycle < (main.start_lb == ~uint64_t(0) ? r : main.start_lb) || (e.cycle >= r && e.cycle < rig_.cycle())) {
        fail("step_o", "no leading edge outside the job and after the reset", "one at cycle " + std::to_string(e.cycle));
        break;
      }
    phase_start_ = r + rig_.reset_len;
    reads_ = 0;
    jobs_.clear();
    // A reply after the reset (and after the frame it may have cut).
    last_ = poll();
    if (between && first_after_reset_) {
      const card::Reply& q = *first_after_reset_;
      expect_eq("reply fresh flag (the first frame after the reset)", true, (q.flags & card::reply_flag::fresh) != 0);
      expect_eq("last_seq in the first reply after the reset", 0u, unsigned(q.last_seq));
      expect_eq("last_result in the first reply after the reset", 0u, unsigned(q.last_result));
    }
    rig_.idle(200);
    last_ = poll();
    const card::Status st = card::decode_status(last_.status);
    expect_eq("status after reset", 0u, last_.status & ~0x8u);
    (void)st;
    expect_eq("moves after reset", 0u, last_.moves);
    expect_eq("segments after reset", 0u, last_.segments);
    expect_eq("stretch after reset", 0u, last_.stretch);
    expect_eq("reads after reset", 0u, unsigned(last_.reads));
    expect_eq("free words after reset", unsigned(P::kCbufWords), unsigned(last_.free_words));
    expect_eq("positions after reset", std::vector<int32_t>(N, 0), last_.positions);
    expect_eq("enable_o after reset", false, rig_.last.enable);
    configure();
  }

  // CLEAR, drivers on, and a short job that must run exactly; then the totals.
  void recover() {
    last_ = poll();
    if (faulted()) {
      command(control(false, false, true));
      if ((last_.status >> 8 & 0xFF) == kEstop) {
        // An E-stop is cleared only by the out-of-band ACK (docs/CORE.md "Faults").
        expect_eq("status fault after CLEAR of an E-stop", 1u, last_.status >> 1 & 1);
        urgent(card::urgent::ack);
      }
      expect_eq("status fault after CLEAR", 0u, last_.status >> 1 & 1);
    }
    if (!(last_.flags & card::reply_flag::drivers)) {
      std::vector<uint32_t> w;
      card::encode_drivers(true, w);
      card::encode_read(card::Register::id, 0, w);
      command(w);
    }
    if (!errors_.empty()) return;
    Job rec;
    const unsigned n = gen_.uniform(1, 3);
    const std::vector<card::WireSegment> job = make_job(n, 20000, 16000);
    for (unsigned i = 0; i < n; ++i) {
      const std::vector<uint32_t> w = words_of(job[i], i == 0);
      while (w.size() > last_.free_words) {
        rig_.idle(400);
        last_ = poll();
      }
      uint64_t cs = 0;
      if (!command(w, &cs)) return;
      if (i == 0) rec.start_lb = cs;
      rec.segs.push_back(job[i]);
    }
    wait_idle();
    rec.ending = Ending::clean;
    jobs_.push_back(rec);
    for (const auto& f : rig_.mon.fault_rises)
      if (f.first >= rec.start_lb)
        fail("fault_o", "no fault in the job after recovery", "code " + std::to_string(f.second));

    // Every job of this phase against the pins, then the totals in the reply.
    Tally t;
    t.pos.assign(N, 0);
    std::vector<std::string> err;
    for (size_t j = 0; j < jobs_.size(); ++j) {
      const uint64_t from = j == 0 ? phase_start_ : jobs_[j].start_lb;
      const uint64_t to = j + 1 < jobs_.size() ? jobs_[j + 1].start_lb : ~uint64_t(0);
      verify_job(jobs_[j], rig_.mon.edges, from, to, N, t, err);
    }
    for (const auto& e : err) fail("step_o/dir_o", "the accepted segments' moves", e);
    moves_checked_ += t.moves;
    const card::Reply r = last_;
    const card::Status st = card::decode_status(r.status);
    std::vector<int32_t> want_pos, pins_pos, count;
    for (unsigned a = 0; a < N; ++a) {
      want_pos.push_back(int32_t(t.pos[a]));
      pins_pos.push_back(rig_.last.position[a]);
      count.push_back(int32_t(rig_.mon.count[a]));
    }
    expect_eq("reply positions vs the accepted segments' moves", want_pos, r.positions);
    expect_eq("position_o vs the pulses counted on STEP/DIR", count, pins_pos);
    expect_eq("reply positions vs position_o", pins_pos, r.positions);
    expect_eq("reply moves done", uint32_t(t.moves), r.moves);
    expect_eq("reply segments done", uint32_t(t.segments), r.segments);
    expect_eq("reply READ count (one per accepted COMMANDS frame)", unsigned(reads_), unsigned(r.reads));
    if (r.stretch < t.late || r.stretch > t.late + jobs_.size() + t.cuts)
      fail("stretch counter", "in " + std::to_string(t.late) + ".." + std::to_string(t.late + jobs_.size() + t.cuts) +
                                  " (moves seen late, + one first move per START, + one per cut)",
           std::to_string(r.stretch));
    expect_eq("status fault", false, st.fault);
    expect_eq("status running", false, st.running);
    expect_eq("status segments queued", 0u, st.segments_queued);
    expect_eq("status chunks queued", 0u, st.chunks_queued);
    expect_eq("drivers enabled", true, st.drivers_enabled && rig_.last.enable);
    expect_eq("free words", unsigned(P::kCbufWords), unsigned(r.free_words));
    expect_eq("last READ", card::kCardId, r.last_read);
  }

  model::CpCoreParams params_;
  uint64_t seed_;
  Kind kind_;
  std::string where_;
  JobGen gen_;
  Rig<P> rig_;
  uint8_t seq_ = 0;
  card::Reply last_;
  unsigned reads_ = 0;
  std::vector<Job> jobs_;
  uint64_t phase_start_ = 0;
  uint64_t inject_cycle_ = 0;
  bool injected_ = false;
  std::optional<card::Reply> first_after_reset_;
  unsigned sck_seen_ = 0;
  std::string detail_, variant_;
  uint64_t moves_checked_ = 0;
  std::vector<std::string> errors_;
};

// ---------------------------------------------------------------------------------
struct KindStats {
  unsigned runs = 0, passed = 0;
  uint64_t cycles = 0, moves = 0;
  std::map<std::string, unsigned> variants;
};

// `per_kind` injections of every kind, the two cards taking turns; each run's
// seed is the campaign seed + its number.
void campaign(unsigned per_kind) {
  const uint64_t seed = core_seed(17017);
  // CPSTEP_FAULT_RUN=i runs only run i of the campaign (a failure's reproducer).
  const char* only_env = std::getenv("CPSTEP_FAULT_RUN");
  const long only = only_env ? std::strtol(only_env, nullptr, 0) : -1;
  std::printf("fault campaign: CPSTEP_SEED=%llu, %u injections per kind\n", (unsigned long long)seed, per_kind);
  std::array<KindStats, kKinds> st{};
  const auto t0 = std::chrono::steady_clock::now();
  for (unsigned i = 0; i < per_kind * kKinds; ++i) {
    if (only >= 0 && long(i) != only) continue;
    const Kind kind = Kind(i % kKinds);
    const uint64_t s = seed + i;
    const std::string where = "CPSTEP_SEED=" + std::to_string(seed) + " CPSTEP_FAULT_RUN=" + std::to_string(i);
    KindStats& k = st[unsigned(kind)];
    auto tally = [&](auto& r) {
      const bool ok = r.go();
      ++k.runs;
      k.passed += ok;
      k.cycles += r.cycles();
      k.moves += r.moves_checked();
      if (!r.variant().empty()) ++k.variants[r.variant()];
    };
    if ((i / kKinds) % 2 == 0) {
      Run<CardSmall> r(s, kind, where);
      tally(r);
    } else {
      Run<sim::CardDefault> r(s, kind, where);
      tally(r);
    }
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  uint64_t runs = 0, passed = 0, cycles = 0, moves = 0;
  std::printf("%-14s %10s %8s %14s %12s\n", "kind", "injections", "passed", "cycles", "moves");
  for (unsigned k = 0; k < kKinds; ++k) {
    std::printf("%-14s %10u %8u %14llu %12llu\n", kind_name(Kind(k)), st[k].runs, st[k].passed,
                (unsigned long long)st[k].cycles, (unsigned long long)st[k].moves);
    runs += st[k].runs, passed += st[k].passed, cycles += st[k].cycles, moves += st[k].moves;
  }
  std::printf("%-14s %10llu %8llu %14llu %12llu\n", "total", (unsigned long long)runs, (unsigned long long)passed,
              (unsigned long long)cycles, (unsigned long long)moves);
  for (unsigned k = 0; k < kKinds; ++k) {
    std::printf("%-14s", kind_name(Kind(k)));
    for (const auto& [v, n] : st[k].variants) std::printf(" [%s: %u]", v.c_str(), n);
    std::printf("\n");
  }
  std::printf("%.1f s, %.2f M cycles/s\n", secs, double(cycles) / secs / 1e6);
  EXPECT_EQ(passed, runs);
}

// The CI subset: 15 injections of each kind (105).
TEST(FaultCampaign, Ci) { campaign(15); }
// Nightly (label long): 150 of each kind (1,050).
TEST(FaultCampaign, Long) { campaign(150); }

}  // namespace
}  // namespace cpstep::tb

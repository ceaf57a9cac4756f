// SPDX-License-Identifier: MIT
// An independent checker of the motion core's pins (docs/CORE.md, SPEC §1–§2). It is
// fed the core's inputs and outputs every cycle and the segments the host sent that
// the core must run, and nothing of the model or the RTL's internals:
//
// - a move event is a leading STEP edge of the running segment's major axis; every
//   other axis steps only in move events, and after move i of a segment (U, v, k)
//   each axis stands at sign·floor((2·v·i + U) / (2U)) (SPEC §1's closed form, ties
//   up; the same for every doubling 2^k), so within half a step of the ideal line,
//   and on its delta at the segment's end;
// - each move happens no earlier than its programmed time (its chunk's
//   interval + j·add + add2·j(j−1)/2 after the previous move's leading edge, the first after START
//   from the START cycle), and is either exactly on time or counted late;
// - every axis's pins obey its pulse timing and position_o counts its pulses
//   (tb/pulse/pin_checker.h, one per axis);
// - the configuration in force is decoded from the CONFIG words the core takes
//   (refused while running or while a STEP pin is at its active level).
#pragma once

#include <cstdint>
#include <deque>
#include <sstream>
#include <string>
#include <vector>

#include "card/protocol.h"
#include "model/cp_core_ports.h"
#include "pulse/pin_checker.h"

namespace cpstep::tb {

class CoreChecker {
 public:
  explicit CoreChecker(const model::CpCoreParams& p) : p_(p) {
    for (unsigned a = 0; a < p_.n; ++a) pins_.emplace_back(32, p_.step_pol_reset, p_.dir_pol_reset);
    reset_state();
  }

  // A segment the core has to run, in the order sent.
  void expect(const card::WireSegment& s) {
    Seg g;
    g.u = s.u;
    g.k = s.k;
    g.end = s.end;
    g.chunks = s.chunks;
    for (unsigned a = 0; a < p_.n; ++a) {
      g.v.push_back(s.v[a]);
      g.positive.push_back(s.dir_positive[a]);
      if (g.major < 0 && s.v[a] == s.u) g.major = int(a);
    }
    if (g.major < 0) fail("bench error: a segment with no axis at v = U");
    queue_.push_back(g);
  }
  // A fault or abort dropped whatever was queued, the running segment included.
  void abandon() {
    queue_.clear();
    cursor_ = {};
    origin_ = pos_;
    anchored_ = false;
  }

  void observe(uint64_t cycle, const model::CpCoreIn& in, const model::CpCoreOut& out) {
    cycle_ = cycle;
    if (in.rst) {
      reset_state();
      for (unsigned a = 0; a < p_.n; ++a) pins_[a].check(cycle, pulse_in(a, true), pins_of(out, a));
      return;
    }
    // Leading edges as the pin checker classifies the raw pins (the polarity in force
    // at the edge, a polarity edge is no pulse).
    uint32_t rise = 0;
    for (unsigned a = 0; a < p_.n; ++a) {
      pins_[a].check(cycle, pulse_in(a, false), pins_of(out, a));
      if (pins_[a].leading()) {
        rise |= 1u << a;
        const bool positive = pins_[a].positive();
        pos_[a] += positive ? 1 : -1;
        dir_at_edge_[a] = positive;
      }
    }
    if (rise) on_edges(rise, out);
    take_command(in, out);
    check_read_port(in, out);
  }

  // Some axis's STEP pin is at its active level in the cycle last observed (the core
  // refuses CONFIG then: a host waits for this to fall before configuring).
  bool pulse_high() const {
    for (const PinChecker& c : pins_)
      if (c.active()) return true;
    return false;
  }

  // Figures.
  uint64_t moves() const { return moves_; }
  uint64_t late_moves() const { return late_; }
  uint64_t segments_done() const { return segments_done_; }
  uint64_t last_edge_cycle() const { return last_edge_; }
  int64_t position(unsigned a) const { return pos_[a]; }
  bool queue_empty() const { return queue_.empty(); }
  size_t queued() const { return queue_.size(); }
  // Moves of the running and queued segments not made yet.
  uint64_t moves_ahead() const {
    uint64_t m = 0;
    for (const Seg& g : queue_) m += uint64_t(g.u) << g.k;
    return m - cursor_.move;
  }
  std::vector<std::string> errors() const {
    std::vector<std::string> e = errors_;
    for (unsigned a = 0; a < p_.n; ++a)
      for (const auto& m : pins_[a].errors()) e.push_back("axis " + std::to_string(a) + ": " + m);
    return e;
  }
  std::string report() const {
    std::ostringstream s;
    for (const auto& e : errors()) s << "  " << e << "\n";
    return s.str();
  }

 private:
  struct Seg {
    uint32_t u = 0;
    unsigned k = 0;
    bool end = false;
    int major = -1;
    std::vector<uint32_t> v;
    std::vector<bool> positive;
    std::vector<card::WireChunk> chunks;
  };
  struct Cursor {
    uint64_t move = 0;          // moves made in the running segment
    size_t chunk = 0;           // chunk of the next move
    uint32_t in_chunk = 0;      // its index within the chunk
  };
  struct AxisCfg {
    uint32_t high, low, setup, hold;
    bool step_pol, dir_pol;
  };

  void reset_state() {
    cfg_.assign(p_.n, AxisCfg{p_.step_high_reset, p_.step_low_reset, p_.dir_setup_reset,
                              p_.dir_hold_reset, p_.step_pol_reset, p_.dir_pol_reset});
    dir_at_edge_.assign(p_.n, false);
    pos_.assign(p_.n, 0);
    queue_.clear();
    cursor_ = {};
    origin_ = pos_;
    anchored_ = false;
    words_left_ = 0;
  }

  model::CpPulseIn pulse_in(unsigned a, bool rst) const {
    model::CpPulseIn i;
    i.rst = rst;
    i.cfg_step_high = cfg_[a].high;
    i.cfg_step_low = cfg_[a].low;
    i.cfg_dir_setup = cfg_[a].setup;
    i.cfg_dir_hold = cfg_[a].hold;
    i.cfg_step_pol = cfg_[a].step_pol;
    i.cfg_dir_pol = cfg_[a].dir_pol;
    return i;
  }
  static model::CpPulseOut pins_of(const model::CpCoreOut& o, unsigned a) {
    model::CpPulseOut p;
    p.step = (o.step >> a & 1) != 0;
    p.dir = (o.dir >> a & 1) != 0;
    p.position = uint64_t(o.position[a]) & 0xFFFFFFFFu;
    return p;
  }

  // The read port (docs/CORE.md "Read port") shows the registers the outputs
  // show, in the same cycle; unmapped addresses read 0.
  void check_read_port(const model::CpCoreIn& in, const model::CpCoreOut& out) {
    const uint32_t r = in.rd_addr & 0xFF;
    uint32_t want = 0;
    if (r == 0x00) want = out.status;
    else if (r == 0x01) want = out.stretch_count;
    else if (r == 0x02) want = out.moves_done;
    else if (r == 0x03) want = out.segments_done;
    else if (r == 0x1F) want = card::kCardId;
    else if (r == 0x20) return;  // the capabilities word: CoreFaults.DriversEnableAndCapabilities
    else if (r >= 0x23 && r <= 0x25) return;  // more capability constants (docs/CORE.md): not checked here
    else if (r == 0x21) want = p_.w;
    else if (r == 0x22) want = p_.umax;
    else if (r >= 0x10 && r < 0x10 + p_.n) want = uint32_t(out.position[r - 0x10]);
    if (out.rd_data != want) {
      std::ostringstream m;
      m << "read port: register 0x" << std::hex << r << " reads 0x" << out.rd_data << ", the outputs show 0x"
        << want;
      fail(m.str());
    }
  }

  void fail(const std::string& what) {
    if (errors_.size() < 12) errors_.push_back("cycle " + std::to_string(cycle_) + ": " + what);
  }

  void on_edges(uint32_t rise, const model::CpCoreOut& out) {
    last_edge_ = cycle_;
    if (queue_.empty()) {
      fail("STEP leading edge (axes mask " + std::to_string(rise) + ") with no segment to run");
      return;
    }
    const Seg& g = queue_.front();
    if (!(rise >> g.major & 1)) {
      fail("axes mask " + std::to_string(rise) + " stepped without the major axis " +
           std::to_string(g.major) + ": a step outside a move event");
      return;
    }
    const uint64_t i = ++cursor_.move;
    ++moves_;
    check_timing(g, out);
    for (unsigned a = 0; a < p_.n; ++a) {
      if ((rise >> a & 1) && dir_at_edge_[a] != g.positive[a])
        fail("axis " + std::to_string(a) + " stepped with DIR " + (dir_at_edge_[a] ? "+" : "-") +
             " in a segment that moves it " + (g.positive[a] ? "+" : "-"));
      // SPEC §1: floor((2·v·i + U) / (2U)), ties rounded up.
      const uint64_t want_abs = (2 * uint64_t(g.v[a]) * i + g.u) / (2 * uint64_t(g.u));
      const int64_t want = g.positive[a] ? int64_t(want_abs) : -int64_t(want_abs);
      const int64_t got = pos_[a] - origin_[a];
      if (got != want)
        fail("axis " + std::to_string(a) + " after move " + std::to_string(i) + " of segment " +
             std::to_string(segments_done_) + " (U " + std::to_string(g.u) + ", v " +
             std::to_string(g.v[a]) + ", k " + std::to_string(g.k) + ") is at " +
             std::to_string(got) + " steps from the segment's start; the closed form says " +
             std::to_string(want));
    }
    if (i == uint64_t(g.u) << g.k) {
      for (unsigned a = 0; a < p_.n; ++a) {
        const int64_t delta = int64_t(uint64_t(g.v[a]) << g.k) * (g.positive[a] ? 1 : -1);
        if (pos_[a] - origin_[a] != delta)
          fail("segment " + std::to_string(segments_done_) + " ended with axis " + std::to_string(a) +
               " " + std::to_string(pos_[a] - origin_[a]) + " steps from its start, delta " +
               std::to_string(delta));
      }
      ++segments_done_;
      if (g.end) anchored_ = false;  // the next move is timed from the next START
      queue_.pop_front();
      cursor_ = {};
      origin_ = pos_;
    }
  }

  // The move just seen is the segment's cursor_.move-th; its programmed delay comes
  // from its chunk, counted from the previous leading edge (or START).
  void check_timing(const Seg& g, const model::CpCoreOut& out) {
    if (cursor_.chunk >= g.chunks.size()) {
      fail("bench error: more moves than the chunks program");
      return;
    }
    const card::WireChunk& c = g.chunks[cursor_.chunk];
    const int64_t j = cursor_.in_chunk;
    const int64_t delay = int64_t(c.interval) + j * c.add + int64_t(c.add2) * j * (j - 1) / 2;
    if (++cursor_.in_chunk == c.count) {
      ++cursor_.chunk;
      cursor_.in_chunk = 0;
    }
    if (!anchored_) {
      fail("a move with no START (or previous move) to time it from");
    } else {
      const uint64_t due = anchor_ + uint64_t(delay);
      if (cycle_ < due)
        fail("move " + std::to_string(cursor_.move) + " of segment " + std::to_string(segments_done_) +
             " early: its leading edge at cycle " + std::to_string(cycle_) + ", programmed for " +
             std::to_string(due) + " (delay " + std::to_string(delay) + ")");
      if (cycle_ > due) {
        ++late_;
        if (!out.stretched) fail("a move fired late but the stretched flag is low");
      }
    }
    anchor_ = cycle_;
    anchored_ = true;
  }

  // Command framing: CONFIG applies from the next cycle unless refused (while running,
  // or while some axis's STEP pin is active: docs/CORE.md), a START taken while
  // stopped and without a fault anchors the timing.
  void take_command(const model::CpCoreIn& in, const model::CpCoreOut& out) {
    if (!(in.cmd_valid && out.cmd_ready)) return;
    const uint32_t w = in.cmd_data;
    if (words_left_ > 0) {
      --words_left_;
      return;
    }
    switch (w >> 28) {
      case 0x1: words_left_ = 1 + p_.n + ((w >> 22 & 1) ? 3 : 2) * (w & 0xFFFF); break;
      case 0x2: {
        const uint32_t axis = w >> 24 & 0xF, field = w >> 20 & 0xF, value = w & 0xFFFF;
        if (out.running || pulse_high() || axis >= p_.n || field > 4 || (field <= 1 && value == 0)) break;
        AxisCfg& c = cfg_[axis];
        switch (field) {
          case 0: c.high = value; break;
          case 1: c.low = value; break;
          case 2: c.setup = value; break;
          case 3: c.hold = value; break;
          default:
            c.step_pol = (w & 1) != 0;
            c.dir_pol = (w >> 1 & 1) != 0;
        }
        break;
      }
      case 0x3:
        if ((w & 1) && !(w & 2) && !out.running && !out.fault) {
          anchor_ = cycle_ + 1;  // the first move's edge is its delay after START's edge
          anchored_ = true;
        }
        break;
      default: break;
    }
  }

  model::CpCoreParams p_;
  std::vector<PinChecker> pins_;
  std::vector<AxisCfg> cfg_;
  std::vector<bool> dir_at_edge_;
  std::vector<int64_t> pos_, origin_;
  std::deque<Seg> queue_;
  Cursor cursor_;
  bool anchored_ = false;
  uint64_t anchor_ = 0;
  uint32_t words_left_ = 0;
  uint64_t cycle_ = 0, moves_ = 0, late_ = 0, segments_done_ = 0, last_edge_ = 0;
  std::vector<std::string> errors_;
};

}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// cp_core — cycle-accurate, bit-exact model of rtl/cp_core.v, the motion core.
//
// Written from docs/CORE.md ("Cycle behaviour" states every rule it follows). Like
// the RTL it is the twins of its parts joined by three queues: CpCmd (command
// parser and chunk check), CpBuild (the pattern builder with the one CpEngine),
// CpRun (banks, replay, timer, fire, stretch), CpStatus (faults, counters,
// configuration, READ), three CpFifos (segment words, chunks, built segments) and
// N CpPulses.
// The bench sets `in`, reads outputs() (the pins before the rising edge), then
// calls tick() (the edge).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "model/cp_build.h"
#include "model/cp_cmd.h"
#include "model/cp_core_ports.h"
#include "model/cp_fifo.h"
#include "model/cp_pulse.h"
#include "model/cp_feed.h"
#include "model/cp_inputs.h"
#include "model/cp_run.h"
#include "model/cp_status.h"

namespace cpstep::model {

class CpCore {
 public:
  using Params = CpCoreParams;
  using In = CpCoreIn;
  using Out = CpCoreOut;

  explicit CpCore(Params params = {});

  In in;

  Out outputs() const;
  void tick();

  // Event skipping. quiet_for(limit): how many clocks from now, with the inputs in
  // `in` held, change nothing but counters — the move timer counting towards the
  // pending move, the pulse timers' high, low and setup counts — so that every
  // output (pins, position, status, READ data, cmd_ready) stays as it is now; at
  // most `limit`, 0 when this clock must be clocked normally. skip(n) then
  // advances n <= quiet_for() clocks at once, leaving the core in exactly the
  // state n tick()s would have. docs/SIM.md ("The fast engine").
  uint64_t quiet_for(uint64_t limit) const;
  void skip(uint64_t cycles);

  // Lazy clocking, for the fast engine (docs/SIM.md "Engines"): when a clock finds
  // the core quiet for h clocks, tick() only counts the next ones for as long as
  // the inputs stay (all but rd_addr, which only chooses what rd_data shows), and
  // skips them at once when the inputs change or the quiet ends; outputs() gives
  // the outputs of the quiet (rd_data read for the rd_addr of the clock). Every
  // output in every clock is the same as without it. After a clock that was not
  // quiet, the next few do not ask (2, 4 up to 16 clocks), so busy stretches
  // cost about one settle a clock. Lazy, quiet_for() answers with the quiet the
  // last clock found (0 if it found none) rather than looking. Off by default.
  void set_lazy(bool on);
  // The read port's data for register `addr` with the inputs in `in` otherwise:
  // what outputs().rd_data would be for that rd_addr.
  uint32_t read_port(uint32_t addr) const;

  const Params& params() const { return p_; }

 private:
  // Every part's inputs and outputs in one cycle, settled in the order the RTL's
  // combinational paths run: queues and pulse timers (registered), the READ
  // port, parser, builder, runner, then the status's flush.
  struct Wires {
    CpFifoOut seg, chunk, run;
    std::array<CpPulseOut, kCoreMaxAxes> pulse{};
    CpStatusIn st_in;
    CpStatusOut st;
    CpCmdIn cmd_in;
    CpCmdOut cmd;
    CpBuildIn b_in;
    CpBuildOut b;
    CpRunIn r_in;
    CpRunOut r;
    CpInputsIn i_in;
    CpInputsOut inp;  // active limits and probe (all 0 without INPUTS)
    CpFeedIn f_in;
    CpFeedOut fo;     // the timer's scale (1 without FEED), READ 0x29/0x2A (0 without)
  };
  Wires settle() const;
  // settle() for the current inputs, computed once per clock.
  const Wires& wires() const;
  uint64_t quiet_for(const Wires& w, uint64_t limit) const;
  Out outputs(const Wires& w) const;
  // Lazy clocking: the quiet clocks still ahead and the ones counted, not yet skipped.
  bool lazy_holds() const;
  void catch_up();
  CpPulseIn pulse_in(unsigned axis, bool step) const;
  // The move timer's scale now (cp_feed's register; 1 without FEED), Q2.16.
  uint32_t scale() const { return p_.feed ? feed_.outputs().scale : 0x10000; }
  // The run queue word's fields below the phase timer's L, k, U: {[conic, u, v,]
  // out, lane, end, moving[N], dir[N]}.
  unsigned run_fields() const { return 3 + 2 * p_.n + (p_.conic ? 7 : 0); }
  // The three queues' inputs this clock.
  CpFifoIn seg_in(const Wires& w) const;
  CpFifoIn chunk_in(const Wires& w) const;
  CpFifoIn run_in(const Wires& w) const;

  Params p_;
  CpCmd cmd_;
  CpBuild build_;
  CpRun run_;
  CpStatus status_;
  CpInputs inputs_;
  CpFeed feed_;
  CpFifo seg_fifo_, chunk_fifo_, run_fifo_;
  std::vector<CpPulse> pulses_;

  mutable Wires wires_{};
  mutable In wires_in_{};
  mutable bool wires_valid_ = false;

  bool lazy_ = false;
  In lazy_in_{};
  Out lazy_out_{};
  CpStatusIn lazy_st_{};
  uint64_t lazy_left_ = 0, lazy_pending_ = 0;
  unsigned backoff_ = 0, backoff_left_ = 0;  // clocks between looks for a quiet, after a look found none
};

}  // namespace cpstep::model

// cp_core — cycle-accurate, bit-exact model of rtl/cp_core.v, the motion core.
//
// Written from docs/CORE.md ("Cycle behaviour" states every rule it follows). Like
// the RTL it is built from the sub-blocks' own models — 2·N CpEngines (lane l, axis
// a is engine l·N + a), N CpPulses and three CpFifos (segments, built segments,
// chunks) — with the core's own logic on top: the command parser and validator,
// the builder, the runner with its move-event timer, status and faults.
// The bench sets `in`, reads outputs() (the pins before the rising edge), then
// calls tick() (the edge).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "model/cp_core_ports.h"
#include "model/cp_engine.h"
#include "model/cp_fifo.h"
#include "model/cp_pulse.h"

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

  const Params& params() const { return p_; }

 private:
  // The command parser's position in a command (docs/CORE.md, "Cycle behaviour").
  enum class Parse {
    command, seg_h1, seg_v, chunk_interval, chunk_count, chunk_add2, chunk_inc, chunk_check, reply
  };

  struct AxisConfig {
    uint32_t step_high = 1, step_low = 1, dir_setup = 1, dir_hold = 1;
    bool step_pol = true, dir_pol = true;
  };

  // A segment as the segment queue holds it.
  struct Segment {
    bool end = false;
    uint32_t k = 0;
    uint32_t dir = 0;  // bit i: axis i positive
    uint32_t u = 0;
    std::array<uint32_t, kCoreMaxAxes> v{};
  };

  struct Regs {
    // Control state (reset).
    Parse parse = Parse::command;
    bool discard = false;     // the segment being read is dropped
    bool rsp_valid = false;
    bool running = false;
    bool cur_valid = false;   // a built segment is loaded for running
    unsigned cur_lane = 0, build_lane = 0;
    bool chunk_loaded = false;  // the timer holds a chunk
    bool late = false;          // the pending move has been counted as stretched
    unsigned bad_lanes = 0;     // bit l: lane l holds a segment its engines refused
    bool fault = false;
    uint32_t err = 0;
    bool stretched = false;
    bool enable = false;        // drivers enabled
    uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
    uint32_t dir = 0;           // bit i: the direction axis i steps in
    std::array<AxisConfig, kCoreMaxAxes> cfg{};
    // Datapath (not reset).
    Segment seg;                // the segment being read
    bool seg_add2 = false;      // its chunks carry add2 (three words)
    uint32_t chunks_left = 0, v_index = 0;
    uint32_t interval = 0, count = 0, add = 0, add2 = 0;
    uint64_t count_sum = 0;
    // The chunk check's bit-serial products (docs/CORE.md): pass 1 (count-2)·add2,
    // pass 2 (count-1)·(add + last increment); both fit 49 bits, never wrap.
    int64_t product = 0, mul_b = 0;
    uint32_t mul_a = 0;
    uint32_t rsp_data = 0;
    bool cur_end = false;
    uint32_t delay = 0, moves_left = 0, elapsed = 0;
    uint32_t timer_inc = 0;   // the running increment, 32 bits (signed, mod 2^32)
    uint32_t timer_add2 = 0;  // 16 bits
  };

  // Everything one clock decides besides the next register values: the sub-blocks'
  // inputs and the fault raised.
  struct Cycle {
    bool take = false;
    bool seg_wr = false, seg_pop = false, run_wr = false, run_pop = false;
    FifoWord run_data{};
    bool chunk_wr = false, chunk_commit = false, chunk_rollback = false, chunk_pop = false;
    bool build = false;         // the build lane's engines take the queue's head
    bool fire = false;          // a move event
    bool stretch = false;       // a move is counted late
    uint32_t step = 0;          // axes that step in it
    bool start = false, abort = false, clear = false, cfg_write = false;
    bool drivers_on = false, drivers_off = false;
    bool fault_set = false;
    uint32_t fault_code = 0;
    bool flush = false;
    void raise(CoreError e) {
      fault_set = true;
      fault_code = uint32_t(e);  // a later raise in the same cycle overrides
    }
  };

  // What the sub-blocks show in this cycle.
  struct View {
    CpFifoOut seg, run, chunk;
    std::array<CpEngineOut, 2 * kCoreMaxAxes> engine;
    std::array<CpPulseOut, kCoreMaxAxes> pulse;
  };

  // Bit layouts of the queue entries (as in the RTL).
  FifoWord pack_segment(const Segment& s) const;
  Segment unpack_segment(const FifoWord& w) const;
  unsigned seg_bits() const { return 1 + 4 + p_.n + 24 * (p_.n + 1); }

  void reset_control(Regs& d) const;
  bool cmd_ready() const;
  CpPulseIn pulse_in(unsigned axis, uint32_t step) const;
  uint32_t read_register(uint32_t reg) const;

  void parse(const View& v, Regs& d, Cycle& c) const;
  void parse_check_chunk(const View& v, Regs& d, Cycle& c) const;
  void parse_check_increment(Regs& d, Cycle& c) const;
  bool multiply_step(Regs& d) const;
  void build(const View& v, Regs& d, Cycle& c) const;
  void run(const View& v, Regs& d, Cycle& c) const;
  void latch_faults(Regs& d, Cycle& c) const;

  Params p_;
  uint32_t mask_tw_;
  std::vector<CpEngine> engines_;
  std::vector<CpPulse> pulses_;
  CpFifo seg_fifo_, run_fifo_, chunk_fifo_;
  Regs r_;
};

}  // namespace cpstep::model

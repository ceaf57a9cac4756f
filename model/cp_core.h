// cp_core — cycle-accurate, bit-exact model of rtl/cp_core.v, the motion core.
//
// Written from docs/CORE.md ("Cycle behaviour" states every rule it follows). Like
// the RTL it is built from the sub-blocks' own models — one CpEngine (the pattern
// builder), N CpPulses and three CpFifos (segment words, built segments, chunks) —
// with the core's own logic on top: the command parser and validator, the builder
// and the pattern banks, the replay, the runner with its move-event timer, status
// and faults.
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

  // The builder's state (docs/CORE.md "Builder").
  enum class Build { idle, next_axis, capture };

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
    Build build = Build::idle;
    bool rp_valid = false;      // the replay registers hold the next move
    uint32_t segs_queued = 0;   // committed segments in the segment queue
    bool fault = false;
    uint32_t err = 0;
    bool stretched = false;
    bool enable = false;        // drivers enabled
    uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
    uint32_t dir = 0;           // bit i: the direction axis i steps in
    std::array<AxisConfig, kCoreMaxAxes> cfg{};
    // Datapath (not reset).
    bool hdr_end = false;       // the segment being read: end flag, k, U
    uint32_t hdr_k = 0, seg_u = 0;
    bool seg_add2 = false;      // its chunks carry add2 (three words)
    uint32_t chunks_left = 0, v_index = 0;
    uint32_t interval = 0, count = 0, add = 0, add2 = 0;
    uint64_t count_sum = 0;
    // The chunk check's bit-serial products (docs/CORE.md): pass 1 (count-2)·add2,
    // pass 2 (count-1)·(add + last increment); both fit 49 bits, never wrap.
    int64_t product = 0, mul_b = 0;
    uint32_t mul_a = 0;
    uint32_t rsp_data = 0, rsp_addr = 0;
    bool cur_end = false;
    uint32_t delay = 0, moves_left = 0, elapsed = 0;
    uint32_t timer_inc = 0;   // the running increment, 32 bits (signed, mod 2^32)
    uint32_t timer_add2 = 0;  // 16 bits
    bool timer_last = false;  // the timer's chunk is its segment's last
    // The builder's datapath.
    unsigned b_axis = 0;
    uint32_t b_u = 0, b_dir = 0, b_moving = 0, cap_addr = 0;
    bool b_end = false;
    // Replay: the address of the move in each axis's replay register, and each
    // lane's pattern lengths minus one.
    std::array<uint32_t, kCoreMaxAxes> rp_ptr{};
    std::array<std::array<uint32_t, kCoreMaxAxes>, 2> lm1{};
  };

  // Everything one clock decides besides the next register values: the sub-blocks'
  // inputs and the fault raised.
  struct Cycle {
    bool take = false;
    bool seg_wr = false, seg_pop = false, seg_commit = false, seg_rollback = false;
    FifoWord seg_data{};
    bool run_wr = false, run_pop = false;
    FifoWord run_data{};
    bool chunk_wr = false, chunk_commit = false, chunk_rollback = false, chunk_pop = false;
    bool eng_in_valid = false, eng_move_ready = false, cap_done = false, eng_rst = false;
    uint32_t bank_we = 0, bank_waddr = 0;  // axes written, their address in the build lane
    bool bank_wbit = false;
    bool bank_re = false;       // the replay registers load rp_next of lane rp_lane
    unsigned rp_lane = 0;
    std::array<uint32_t, kCoreMaxAxes> rp_next{};
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
    CpEngineOut engine;
    std::array<CpPulseOut, kCoreMaxAxes> pulse;
  };


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
  unsigned aw_;  // pattern bank address width, as the RTL's AW
  CpEngine engine_;
  // Axis a's pattern bank: lane l's pattern at l·2^AW + address; the replay
  // registers (bit a: axis a's next move).
  std::vector<std::vector<uint8_t>> banks_;
  uint32_t rbits_ = 0;
  std::vector<CpPulse> pulses_;
  CpFifo seg_fifo_, run_fifo_, chunk_fifo_;
  Regs r_;
};

}  // namespace cpstep::model

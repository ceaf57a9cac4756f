// SPDX-License-Identifier: MIT
// cp_run — cycle-accurate, bit-exact model of rtl/cp_run.v, the motion core's
// runner: the pattern banks and the replay, the move-event timer, the fire
// decision and the stretch count (docs/CORE.md "Structure", "Timing and stretch").
// Same ports as the RTL; outputs() before the edge, tick() the edge.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "model/cp_conic_serial.h"
#include "model/cp_core_ports.h"
#include "model/cp_fifo.h"
#include "model/cp_ptimer.h"

namespace cpstep::model {

struct CpRunParams {
  unsigned n = 4, w = 1024;
  bool conic = false;  // the conic walker, for CONIC segments (docs/CORE.md)
  unsigned ciw = 40;   // its internal width
  // Moves timed by the phase timer (rtl/cp_ptimer.v) instead of chunks: the chunk
  // queue carries its words, the run queue each segment's moves and length per move.
  bool ptimer = false;
};

struct CpRunIn {
  bool rst = false, flush = false, estop = false, start = false, abort = false, fault = false;
  bool stop = false;  // STOP (out of band): the run off, what is loaded stays
  bool ch_valid = false;
  FifoWord ch_head{};      // 81 bits: {last, add2, count, add, interval}
  bool run_valid = false;
  uint64_t run_head = 0;   // {[conic, u, v,] out, lane, end, moving[N], dir[N]}
  uint64_t run_head_pt = 0;  // ptimer: the fields above those, {L[31:0], k[3:0], U[23:0]}
  uint32_t run_level = 0;  // 2 bits
  bool segq_empty = false, build_busy = false;
  // The banks' write port (cp_build).
  bool bank_we = false;
  uint32_t bank_axis = 0, bank_waddr = 0;
  bool bank_wbit = false, bank_lane = false;
  bool len_we = false;
  uint32_t len_m1 = 0;
  uint32_t pulse_ready = 0;  // bit a: axis a's pulse timer is ready
  // Active limit switches (cp_inputs), bit a: axis a.
  uint32_t lim_min = 0, lim_max = 0;
  // The timer's scale, Q2.16 (cp_feed; 0x10000 = 1): the scaled time each clock adds.
  // (ptimer: the timer advances on the carry of a 17-bit fraction taking it each clock.)
  uint32_t scale = 0x10000;
  // The conic walker's word port (cp_build).
  bool cw_wr = false;
  uint32_t cw_sel = 0, cw_data = 0;
  bool cw_start = false;
  bool cw_cont = false;  // with cw_start: the walk continues the last one
};

struct CpRunOut {
  bool ch_pop = false, run_pop = false;
  uint32_t step = 0, dir = 0;  // bit a: axis a
  bool running = false, cur_valid = false;
  bool torch = false;          // the torch output (a register)
  bool fire = false, seg_done = false, stretch = false, seg_active = false;
  bool fault = false;        // underrun, or a conic's walk not ending on its last move
  bool fault_conic = false;  // the fault is the conic's (CONIC_END)
  bool lim_hit = false;      // the run stops now: a limit toward which it moves is active
  bool walker_free = false;  // the conic walker is not walking and its last move is taken
};

class CpRun {
 public:
  using Params = CpRunParams;
  using In = CpRunIn;
  using Out = CpRunOut;

  explicit CpRun(Params p = {});
  In in;
  Out outputs() const { return eval_outputs(in); }
  // The outputs for inputs `i` (the core settles its parts with it).
  Out eval_outputs(const In& i) const;
  void tick();

  // Event skipping (CpCore::quiet_for): how many clocks with inputs `i` change
  // nothing but the move timer's elapsed count — no move fires or is counted
  // late, no queue is popped, no bank is written — before the pending move falls
  // due (ptimer: before the phase timer's pending move falls due or its phase ends,
  // CpPtimer::quiet_advs). 0: clock it normally; kForever: nothing here ends the quiet.
  static constexpr uint64_t kForever = ~uint64_t(0);
  uint64_t quiet_for(const In& i) const;
  // Advances that many quiet clocks at once, at the timer's scale `scale` (Q2.16).
  void skip(uint64_t cycles, uint32_t scale);

  // Registered outputs, for the core's other parts.
  bool running() const { return r_.running; }
  bool torch() const { return r_.torch; }
  bool cur_valid() const { return r_.cur_valid; }
  // DIR as the pulse timers see it: the registers, but a plane axis of a conic shows
  // the presented move's direction before the move fires (rtl/cp_run.v dir_o).
  uint32_t dir() const;
  // The conic walker is free for the next conic (not walking, its last move taken).
  bool walker_free() const;

 private:
  struct Regs {
    // Reset.
    bool running = false;
    bool cur_valid = false;  // a segment is loaded for running
    unsigned cur_lane = 0;
    bool chunk_loaded = false;  // the timer holds a chunk
    bool late = false;          // the pending move has been counted as stretched
    bool rp_valid = false;      // the replay registers hold the next move
    uint32_t dir = 0;
    uint32_t moving = 0;  // the loaded segment's moving axes
    // Datapath.
    bool cur_end = false;
    bool out = false;    // reset: the out bit of the segment last loaded
    bool torch = false;  // reset: the torch pin
    uint32_t delay = 0, moves_left = 0, elapsed = 0;  // elapsed: scaled time since the last move
    uint32_t ph = 0;   // reset: the fraction of scaled time (Q0.16)
    uint32_t inc = 1;  // reset: what the last clock added to elapsed
    uint32_t timer_inc = 0;   // the running increment, 32 bits (signed, mod 2^32)
    uint32_t timer_add2 = 0;  // 16 bits
    bool timer_last = false;  // the timer's chunk is its segment's last
    // Replay: the address of the move in each axis's replay register, and each
    // lane's pattern lengths minus one (lane, axis).
    std::array<uint32_t, kCoreMaxAxes> rp_ptr{};
    std::array<std::array<uint32_t, kCoreMaxAxes>, 2> lm1{};
    bool cur_conic = false;  // reset: the loaded segment is a conic, and its plane axes
    uint32_t cur_au = 0, cur_av = 0;
    // ptimer: the loaded segment's moves still to fire (34 bits), its length per
    // move (Q2.30), and the fraction of half clocks of scaled time (17 bits, reset).
    uint64_t mleft = 0;
    uint32_t cur_len = 0;
    uint32_t pa = 0;
    bool operator==(const Regs&) const = default;
  };
  // The replay's read of the banks this cycle.
  struct Replay {
    bool re = false;
    unsigned lane = 0;
    std::array<uint32_t, kCoreMaxAxes> next{};
  };
  Out eval(const In& i, Regs& d, Replay& rp) const;
  uint64_t ptimer_quiet_for(const In& i) const;
  void plane(uint32_t& step, uint32_t& dir) const;

  Params p_;
  unsigned aw_;
  // Axis a's bank: lane l's pattern at l·2^AW + address; the replay registers
  // (bit a: axis a's next move).
  std::vector<std::vector<uint8_t>> banks_;
  uint32_t rbits_ = 0;
  CpConicSerial walker_;
  CpPtimer ptimer_;
  Regs r_;
};

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
// cp_build — cycle-accurate, bit-exact model of rtl/cp_build.v, the motion core's
// pattern builder (docs/CORE.md "Structure" and "Builder"). It holds the one
// CpEngine. Same ports as the RTL; outputs() before the edge, tick() the edge.
#pragma once

#include <cstdint>

#include "model/cp_engine.h"

namespace cpstep::model {

struct CpBuildParams {
  unsigned n = 4, w = 1024, umax = 1048575, saw = 2;
  bool conic = false;  // CONIC segments (docs/CORE.md): the walker's words, wider queue words
  bool ptimer = false;  // a segment's last word its length per move, into the run queue with k and U
};

struct CpBuildIn {
  bool rst = false, flush = false, fault = false;
  bool seg_valid = false;
  uint64_t seg_head = 0;  // 30 + N bits; with conic 32 + N
  bool seg_commit = false;
  uint32_t run_level = 0;  // 2 bits
  bool cur_valid = false;
  bool walker_free = false;  // the conic walker (cp_run) is free for the next conic
};

struct CpBuildOut {
  bool seg_pop = false;
  bool run_wr = false;
  uint64_t run_data = 0;  // {[conic, u, v,] lane, end, moving[N], dir[N]}
  uint64_t run_data_pt = 0;  // ptimer: the fields above those, {L[31:0], k[3:0], U[23:0]}
  bool bank_we = false;
  uint32_t bank_axis = 0, bank_waddr = 0;
  bool bank_wbit = false;
  bool build_lane = false;
  bool len_we = false;
  uint32_t len_m1 = 0;
  // The conic walker's word port: a conic's words, the last with the start.
  bool cw_wr = false;
  uint32_t cw_sel = 0, cw_data = 0;
  bool cw_start = false;
  bool cw_cont = false;  // with cw_start: the walk continues the last one (K5, K6 written)
  bool fault = false;  // the engine refused a pattern
  bool busy = false;
  uint32_t segq = 0;   // committed segments in the segment queue
};

class CpBuild {
 public:
  using Params = CpBuildParams;
  using In = CpBuildIn;
  using Out = CpBuildOut;

  explicit CpBuild(Params p = {});
  In in;
  Out outputs() const { return eval_outputs(in); }
  // The outputs for inputs `i` (the core settles its parts with it).
  Out eval_outputs(const In& i) const;
  void tick();
  // True when a clock with inputs `i` changes no register, bank or queue, and
  // the engine is still (the event-skipping core's test; see CpCore::quiet_for).
  bool still(const In& i) const;

  // Registered outputs, for the core's other parts.
  bool busy() const { return r_.state != State::idle; }
  uint32_t segq() const { return r_.segq; }

 private:
  enum class State { idle, next_axis, capture, conic_words, length };
  struct Regs {
    State state = State::idle;  // reset
    bool build_lane = false;    // reset
    uint32_t segq = 0;          // reset
    unsigned axis = 0;
    uint32_t u = 0, dir = 0, moving = 0, cap_addr = 0;
    bool end = false;
    bool out = false;  // the torch output while the segment runs
    bool conic = false;                 // the segment being built is a conic
    bool cont = false;                  // ... that continues the last walk
    uint32_t au = 0, av = 0, k_index = 0;
    uint32_t k = 0;                     // ptimer: the segment's k
    bool operator==(const Regs&) const = default;
  };
  struct Engine {
    bool in_valid = false, move_ready = false, rst = false;
  };
  Out eval(const In& i, Regs& d, Engine& e) const;

  Params p_;
  unsigned aw_, uw_, sqw_;
  CpEngine engine_;
  Regs r_;
};

}  // namespace cpstep::model

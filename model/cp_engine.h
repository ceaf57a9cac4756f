// SPDX-License-Identifier: MIT
// cp_engine — cycle-accurate, bit-exact model of rtl/cp_engine.v.
//
// Written from docs/ENGINE.md (the engine's cycle contract), not from the RTL.
// Same ports as the RTL; the bench sets `in`, reads outputs() (combinational in
// the current state and inputs), then calls tick() for the rising edge.
#pragma once

#include <cstdint>
#include <vector>

namespace cpstep::model {

struct CpEngineParams {
  unsigned w = 1024;   // pattern capacity W
  unsigned kmax = 8;   // largest doubling exponent
  unsigned rw = 16;    // width of the replay multiplier
  unsigned umax = 0;   // largest u accepted; 0 means W

  unsigned aw() const;  // memory address width, clog2(W)
  unsigned u_max() const { return umax ? umax : w; }
  unsigned uw() const;  // width of u and v, clog2(UMAX + 2)
  unsigned kw() const;  // width of k, clog2(KMAX + 2)
};

struct CpEngineIn {
  bool rst = false;
  bool in_valid = false;
  uint32_t in_u = 0, in_v = 0, in_k = 0, in_rep = 0;
  bool move_ready = false;
};

struct CpEngineOut {
  bool in_ready = false;
  bool err = false;
  uint32_t err_code = 0;
  bool move_valid = false, move = false, move_last = false;
  bool move_pend = false;  // the move ends a period of the pattern
  bool dbg_we1 = false;
  uint32_t dbg_waddr1 = 0;
  bool dbg_wbit1 = false;
  bool dbg_we2 = false;
  uint32_t dbg_waddr2 = 0;
  bool dbg_wbit2 = false;
  bool dbg_iter = false;
  uint32_t dbg_x = 0, dbg_y = 0;
  uint32_t dbg_m1_lo = 0, dbg_m1_len = 0;
  bool dbg_m1_rev = false;
  uint32_t dbg_m2_lo = 0, dbg_m2_len = 0;
  bool dbg_m2_rev = false;
};

enum class EngineError : uint32_t {
  none = 0,
  u_zero = 1,
  v_gt_u = 2,
  u_gt_umax = 3,
  k_gt_kmax = 4,
  rep_zero = 5,
  pattern_gt_w = 6,  // found during the build: u/gcd(u, v) > W
};

class CpEngine {
 public:
  using Params = CpEngineParams;
  using In = CpEngineIn;
  using Out = CpEngineOut;

  explicit CpEngine(CpEngineParams params = {});

  CpEngineIn in;

  CpEngineOut outputs() const;
  void tick();
  // True when a clock with inputs `i` changes no register and touches no
  // memory (the event-skipping core's test; see CpCore::quiet_for).
  bool still(const In& i) const;

  const CpEngineParams& params() const { return p_; }

 private:
  // A register M1 or M2: a window of a circular memory and a direction.
  struct Reg {
    uint32_t lo = 0, len = 0;
    bool rev = false;
    bool operator==(const Reg&) const = default;
  };
  enum class State { idle, build, replay };

  // Everything one clock does, decided from the state and the inputs.
  struct Cycle {
    bool we[2] = {false, false};
    uint32_t waddr[2] = {0, 0};
    bool wbit[2] = {false, false};
    bool re[2] = {false, false};
    uint32_t raddr[2] = {0, 0};
  };

  uint32_t wrap(int64_t a) const;
  uint32_t phys(const Reg& r, uint32_t logical) const;  // address of logical bit
  uint32_t front_slot(const Reg& r) const;              // where a prepend writes
  EngineError refusal(const In& i) const;

  // All registers of the engine; next() computes the state after the coming edge
  // and the memory operations of this cycle.
  struct Regs {
    // Control (reset).
    State state = State::idle;
    bool write_pending = false;
    bool out_valid = false;
    bool err = false;
    bool snap_valid = false;
    // Datapath.
    uint32_t x = 0, y = 0, k = 0, rep = 0;
    bool constant = false, constant_move = false;
    Reg reg[2];                           // [0] = M1, [1] = M2
    uint32_t reads_left = 0, read_addr = 0;   // build
    int write_to = 0;
    uint32_t write_addr = 0;
    int phase = 0;                        // replay: 0 = M2 forward, 1 = M1 backward
    uint32_t phase_left = 0, replay_addr = 0;
    uint64_t inner = 0;                   // replays left of x << k
    uint32_t outer = 0;                   // rounds of x << k left
    int out_from = 0;
    bool out_last = false;
    bool out_pend = false;
    uint32_t err_code = 0;
    uint32_t snap_x = 0, snap_y = 0;
    Reg snap[2];
    bool operator==(const Regs&) const = default;
  };
  Regs next(const In& i, Cycle& io) const;

  CpEngineParams p_;
  uint32_t mask_u_, mask_k_, mask_rep_;
  std::vector<uint8_t> mem_[2];  // [0] = M1, [1] = M2
  bool rdata_[2] = {false, false};
  Regs r_;
};

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
// cp_status — cycle-accurate, bit-exact model of rtl/cp_status.v, the motion
// core's faults (one priority encoder), counters, pulse configuration and READ
// registers (docs/CORE.md "Structure", "Faults"). Same ports as the RTL;
// outputs() before the edge, tick() the edge.
#pragma once

#include <array>
#include <cstdint>

#include "model/cp_core_ports.h"

namespace cpstep::model {

struct CpStatusParams {
  unsigned n = 4, w = 1024, umax = 1048575, kmax = 8, caw = 6, saw = 2, tw = 16, pw = 32;
  unsigned step_high_reset = 1, step_low_reset = 1, dir_setup_reset = 1, dir_hold_reset = 1;
  bool step_pol_reset = true, dir_pol_reset = true;
  unsigned cbuf_aw = 0;
  uint32_t clock_hz = 48000000;
  uint32_t build_id = 0;
  // Reported only (READ 0x26): conic segments taken, and the walker's width.
  bool conic = false;
  unsigned ciw = 40;
  bool inputs = false;  // reported only (READ 0x23 [24]): limit and probe inputs
  bool feed = false;    // reported only (READ 0x23 [25]): feed hold and override
  bool ptimer = false;  // READ 0x23 [26]; its segments' length word widens the segment queue
};

struct CpStatusIn {
  bool rst = false, estop = false;
  bool abort = false, clear = false, drivers_on = false, drivers_off = false;
  bool ack = false;  // ACK (out of band): clears any fault, E-stop's too
  bool kick = false;  // a whole frame with a good CRC ended: the watchdog's kick
  bool cfg_write = false;
  uint32_t cfg_word = 0;
  bool cmd_fault = false;
  uint32_t cmd_code = 0;  // 8 bits
  bool build_fault = false, run_fault = false;
  bool run_conic = false;  // the runner's fault is CONIC_END, not UNDERRUN
  bool lim_hit = false;    // the runner stopped at an active limit (LIMIT)
  // The inputs, active (cp_inputs): READ 0x27 live, 0x28 the limits at LIMIT.
  uint32_t lim_min = 0, lim_max = 0;
  bool probe = false;
  uint32_t seek = 0;  // the seek's {tripped, mode} (cp_inputs), READ 0x27 [19:17]
  // Feed hold and override (cp_feed; 0 without): READ 0x29, 0x2A.
  uint32_t feed = 0, override = 0;
  bool stretch = false, fire = false, seg_done = false, seg_active = false;
  bool running = false, cur_valid = false;
  bool torch = false;  // the torch output (status bit 5)
  uint32_t segq = 0;
  bool build_busy = false;
  uint32_t run_level = 0, ch_level = 0;
  std::array<uint64_t, kCoreMaxAxes> position{};  // PW bits each
  uint32_t rd_addr0 = 0, rd_addr1 = 0;           // 8 bits each
};

struct PulseConfig {
  uint32_t step_high = 1, step_low = 1, dir_setup = 1, dir_hold = 1;
  bool step_pol = true, dir_pol = true;
  bool operator==(const PulseConfig&) const = default;
};

struct CpStatusOut {
  uint32_t rd_data0 = 0, rd_data1 = 0;
  bool fault = false;
  uint32_t err = 0;
  bool flush = false, stretched = false, enable = false;
  uint32_t status = 0, stretch_count = 0, moves_done = 0, segments_done = 0;
  std::array<PulseConfig, kCoreMaxAxes> cfg{};
  bool cfg_new = false;  // CONFIG was written at the last edge
  bool wd_trip = false;  // the watchdog ran out: the runner stops, drivers off, WATCHDOG
};

// The fault priority encoder: which fault (if any) a cycle raises. Highest
// first: E-stop, abort, the watchdog, a limit hit, the runner's (underrun, or
// CONIC_END when run_conic), pattern, the command parser's refusal.
struct FaultPick {
  bool set = false;
  uint32_t code = 0;
};
FaultPick pick_fault(bool estop, bool abort, bool watchdog, bool limit, bool underrun, bool pattern,
                     bool cmd_fault, uint32_t cmd_code, bool run_conic = false);

class CpStatus {
 public:
  using Params = CpStatusParams;
  using In = CpStatusIn;
  using Out = CpStatusOut;

  explicit CpStatus(Params p = {});
  In in;
  Out outputs() const { return eval_outputs(in); }
  // The outputs for inputs `i` (the core settles its parts with it).
  Out eval_outputs(const In& i) const;
  void tick();
  // True when a clock with inputs `i` changes no register (the event-skipping
  // core's test; see CpCore::quiet_for).
  bool still(const In& i) const { return !i.rst && next(i) == r_; }
  // The clocks from now, with inputs `i` held, in which no register changes but the
  // watchdog's count, which counts on (at most `limit`; 0: clock this one). skip(n)
  // advances them.
  uint64_t quiet_for(const In& i, uint64_t limit) const;
  void skip(uint64_t cycles);
  // The watchdog trips in this clock if `kick` is not raised in it.
  bool wd_trip(bool kick) const { return r_.wd_limit != 0 && wd_at() && !kick; }

  // Registered outputs, for the core's other parts.
  bool fault() const { return r_.fault; }
  const PulseConfig& config(unsigned axis) const { return r_.cfg[axis]; }
  bool cfg_new() const { return r_.cfg_new; }
  // Register `reg` as READ shows it for the inputs `i`.
  uint32_t read(const In& i, uint32_t reg) const;

 private:
  struct Regs {
    bool fault = false;
    uint32_t err = 0;
    bool stretched = false, enable = false;
    uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
    std::array<PulseConfig, kCoreMaxAxes> cfg{};
    bool cfg_new = false;
    // The watchdog: its timeout in units of 4096 clocks (0: off), and the clocks since
    // the last kick (1 in the clock after it).
    uint32_t wd_limit = 0, wd_count = 1;
    uint32_t lim_min_at = 0, lim_max_at = 0;  // the active limits when LIMIT latched
    bool operator==(const Regs&) const = default;
  };
  bool wd_at() const { return r_.wd_count == uint64_t(r_.wd_limit) << 12; }
  // The queues flush in this clock: E-stop, abort, or a latched fault once the
  // segment under way has ended (it completes first).
  bool flush(const In& i) const { return i.estop || i.abort || (r_.fault && !i.seg_active); }
  Regs reset_state() const;
  Regs next(const In& i) const;  // the registers after a clock (not in reset)
  uint32_t status_word(const In& i) const;

  Params p_;
  uint32_t mask_tw_;
  Regs r_;
};

}  // namespace cpstep::model

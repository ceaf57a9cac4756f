// SPDX-License-Identifier: MIT
// Ports of rtl/cp_core.v, shared by its golden model and the simulation adaptors.
#pragma once

#include <array>
#include <cstdint>

namespace cpstep::model {

constexpr unsigned kCoreMaxAxes = 8;

struct CpCoreParams {
  unsigned n = 4;           // axes
  unsigned w = 1024;        // pattern capacity
  unsigned umax = 1048575;  // largest U
  unsigned kmax = 8;        // largest k
  unsigned caw = 6;         // chunk queue address width
  unsigned saw = 2;         // segment queue address width
  unsigned tw = 16;         // pulse timing field width
  unsigned pw = 32;         // position width
  unsigned step_high_reset = 1, step_low_reset = 1, dir_setup_reset = 1, dir_hold_reset = 1;
  // CONIC segments (opcode 0x5) walked by a bit-serial walker of ciw bits (docs/CONIC.md
  // section 8); refused as BAD_OPCODE without.
  bool conic = false;
  unsigned ciw = 40;
  // Limit switches and the probe (cp_inputs; docs/CORE.md "Inputs").
  bool inputs = false;
  // Feed hold, resume and override on scaled time (cp_feed; docs/CORE.md "Feed hold and override").
  bool feed = false;
  bool step_pol_reset = true, dir_pol_reset = true;
  // Only reported (READ 0x23..0x25): the command buffer's address width in front
  // of the core (0: none), the clock in Hz, the build id.
  unsigned cbuf_aw = 0;
  uint32_t clock_hz = 48000000;
  uint32_t build_id = 0;
  // Moves timed by the phase timer from PHASE commands instead of chunks, each
  // segment carrying its length per move (docs/PROTOCOL.md "Toward a compact wire").
  bool ptimer = false;
};

struct CpCoreIn {
  bool rst = false;
  bool cmd_valid = false;
  uint32_t cmd_data = 0;
  bool rsp_ready = false;
  bool estop = false;
  uint32_t rd_addr = 0;  // the read port's register (8 bits)
  // Out of band (rtl/cp_spi.v URGENT frames): START, STOP.
  bool ctl_start = false, ctl_stop = false, ctl_flush = false, ctl_ack = false;
  // HOLD, RESUME, OVERRIDE (out of band, FEED builds), and the override's value (Q2.14).
  bool ctl_hold = false, ctl_resume = false, ctl_ovr = false;
  uint32_t ctl_ovr_val = 0;
  // A whole frame with a good CRC ended (rtl/cp_spi.v frame_ok_o): the watchdog's kick.
  bool kick = false;
  // Limit switches (bit a: axis a) and the probe, synchronized.
  uint32_t lim_min = 0, lim_max = 0;
  bool probe = false;
  bool operator==(const CpCoreIn&) const = default;
};

struct CpCoreOut {
  bool cmd_ready = false;
  bool rsp_valid = false;
  uint32_t rsp_data = 0;
  uint32_t rsp_addr = 0;  // the register the reply names
  uint32_t rd_data = 0;   // the read port: register rd_addr, now
  uint32_t step = 0, dir = 0;  // bit i: axis i's pin
  bool torch = false;          // the torch output (docs/CORE.md "Torch")
  bool running = false, fault = false, stretched = false;
  uint32_t err_code = 0;
  std::array<int64_t, kCoreMaxAxes> position{};  // sign-extended from PW bits
  bool enable = false;                           // drivers enabled
  uint32_t status = 0;                           // READ 0x00, live
  uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
};

// Fault and refusal codes (docs/CORE.md).
enum class CoreError : uint32_t {
  none = 0,
  seg_u = 1,
  seg_v_gt_u = 2,
  seg_k = 3,
  seg_chunks = 4,
  seg_chunk_zero = 5,
  seg_delay = 6,
  seg_count_sum = 7,
  seg_pattern = 8,
  underrun = 9,
  estop = 10,
  abort = 11,
  bad_opcode = 12,
  config_busy = 13,
  config_value = 14,
  seg_add2 = 15,
  conic_axes = 16,  // a CONIC segment's plane axes: equal, not an axis, or a v_i of theirs not 0
  conic_end = 17,   // a conic's walk arrives at its end before its last move, or not at it
  conic_cont = 18,  // a CONIC continuing a walk (H0[18]) that does not follow a CONIC on its axes, its way
  watchdog = 19,    // no frame for the watchdog's timeout (CONFIG field 5)
  limit = 20,       // the segment under way moved toward an active limit switch
  seg_length = 21,  // (PTIMER builds) a segment's length per move L = 0
  seg_form = 22,    // (PTIMER builds) a segment's axis form H0[15:0] bad
};

}  // namespace cpstep::model

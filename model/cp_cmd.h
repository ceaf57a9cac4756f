// SPDX-License-Identifier: MIT
// cp_cmd — cycle-accurate, bit-exact model of rtl/cp_cmd.v, the motion core's
// command parser and chunk check (docs/CORE.md "Structure" and "Cycle behaviour").
// Same ports as the RTL; outputs() is what the RTL shows before the rising edge
// for the inputs in `in`, tick() the edge.
#pragma once

#include <cstdint>

#include "model/cp_core_ports.h"
#include "model/cp_fifo.h"

namespace cpstep::model {

struct CpCmdParams {
  unsigned n = 4, umax = 1048575, kmax = 8, caw = 6, tw = 16;
  bool conic = false;  // CONIC segments (opcode 0x5) taken; refused as BAD_OPCODE otherwise
  bool feed = false;    // CONFIG field 9 (the feed ramp's tick) taken; refused otherwise
  bool inputs = false;  // CONFIG field 10 (the seek) taken; refused otherwise (and above 10)
  // Segments timed by the phase timer: no chunks, a length per move after their
  // words; PHASE commands (opcode 0x6) into the chunk queue as the timer's words.
  bool ptimer = false;
};

struct CpCmdIn {
  bool rst = false;
  bool cmd_valid = false;
  uint32_t cmd_data = 0;
  bool rsp_ready = false;
  uint32_t read_data = 0;  // the register cmd_data[7:0] names, now
  bool fault = false, running = false, pulse_busy = false;
  bool seg_full = false, ch_full = false;
  bool flush = false;  // FLUSH (out of band): the command in hand dropped, nothing of it written
};

struct CpCmdOut {
  bool cmd_ready = false;
  bool rsp_valid = false;
  uint32_t rsp_data = 0, rsp_addr = 0;
  bool seg_wr = false, seg_commit = false, seg_rollback = false;
  uint64_t seg_data = 0;  // 30 + N bits; with conic 32 + N
  bool ch_wr = false, ch_commit = false, ch_rollback = false;
  FifoWord ch_data{};     // 81 bits: {last, add2, count, add, interval}; ptimer: {sel, data}
  bool start = false, abort = false, clear = false, drivers_on = false, drivers_off = false;
  bool cfg_write = false;
  bool fault = false;
  uint32_t fault_code = 0;
};

class CpCmd {
 public:
  // Clocks a chunk's check takes in the chunk_check state, whatever its values: the
  // RTL checks it bit-serially, bit i of every value in clock i (docs/CORE.md).
  static constexpr uint32_t kCheckClocks = 51;

  using Params = CpCmdParams;
  using In = CpCmdIn;
  using Out = CpCmdOut;

  explicit CpCmd(Params p = {});
  In in;
  Out outputs() const { return eval_outputs(in); }
  // The outputs for inputs `i` (the core settles its parts with it).
  Out eval_outputs(const In& i) const;
  void tick();
  // True when a clock with inputs `i` takes no word and changes no register or
  // queue (the event-skipping core's test; see CpCore::quiet_for).
  bool still(const In& i) const;
  // Clocks from now in which, with inputs `i`, the parser only counts its chunk
  // check's clocks (kCheckClocks - 1 of them change nothing but the count; the
  // last gives the verdict); 0 otherwise. skip(n) counts n of them at once
  // (nothing where the parser is not checking a chunk: it is still).
  uint64_t counting_for(const In& i) const;
  void skip(uint64_t cycles);

 private:
  enum class Parse {
    command, seg_h1, seg_v, chunk_interval, chunk_count, chunk_add2, chunk_check, reply, conic_words,
    seg_length,   // ptimer: the segment's length per move, then its commit
    phase_words,  // ptimer: a PHASE's words after H0 (v_index: the next one's sel)
    phase_w0      // ptimer: its W0 (interval) into the chunk queue, and the commit
  };
  struct Regs {
    // Reset.
    Parse parse = Parse::command;
    bool discard = false;  // the segment being read is dropped
    bool rsp_valid = false;
    // Datapath.
    bool hdr_end = false;  // the segment being read: end flag, k, U
    bool hdr_out = false;  // ... the torch output while it runs (H0[16])
    uint32_t hdr_k = 0, seg_u = 0;
    bool seg_add2 = false;  // its chunks carry add2 (three words)
    bool hdr_conic = false;  // a CONIC segment: its plane axes and direction
    uint32_t hdr_au = 0, hdr_av = 0;
    bool hdr_cw = false;
    bool hdr_cont = false;  // a CONIC that continues the last walk (H0[18])
    // The last segment committed was a CONIC on these axes, this way (none since a
    // fault or an ABORT): what a continuation may follow. lc_valid is reset.
    bool lc_valid = false;
    uint32_t lc_au = 0, lc_av = 0;
    bool lc_cw = false;
    uint32_t chunks_left = 0, v_index = 0;  // chunks_left: ptimer, H0[15:0] (the axis form)
    uint32_t interval = 0, count = 0, add = 0, add2 = 0;
    uint64_t count_sum = 0;
    uint32_t check_clock = 0;  // the chunk check's clock, 0 .. kCheckClocks-1
    uint32_t rsp_data = 0, rsp_addr = 0;
    bool operator==(const Regs&) const = default;
  };
  Out eval(const In& i, Regs& d) const;
  static CoreError chunk_verdict(const Regs& q);
  bool ready(const In& i) const;
  bool form_ok(uint32_t form) const;
  bool v_sent() const;

  Params p_;
  uint32_t mask_tw_;
  Regs r_;
};

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
// Port adaptors (sim/dut.h) between the Verilated parts of cp_core (rtl/CMakeLists.txt:
// cpstep_rtl_part_*) and their model twins, for the part benches (test_core_parts.cpp).
// Every output port is a compared field. Outputs are defined from the first reset
// edge on (docs/CORE.md), so each RTL part is constructed past one (AfterOneResetEdge).
#pragma once

#include <string>
#include <vector>

#include "Vcp_part_build.h"
#include "Vcp_part_cmd.h"
#include "Vcp_part_cmd_conic.h"
#include "Vcp_part_cmd_ptimer.h"
#include "Vcp_part_build_ptimer.h"
#include "Vcp_part_build_conic.h"
#include "Vcp_part_run_conic.h"
#include "Vcp_part_run.h"
#include "Vcp_part_run_ptimer.h"
#include "Vcp_part_feed.h"
#include "Vcp_part_inputs.h"
#include "Vcp_part_status.h"
#include "core/core_bench.h"
#include "model/bits.h"
#include "model/cp_build.h"
#include "model/cp_cmd.h"
#include "model/cp_feed.h"
#include "model/cp_inputs.h"
#include "model/cp_run.h"
#include "model/cp_status.h"
#include "sim/dut.h"
#include "sim/fifo_port.h"

namespace cpstep::tb {

#define CPSTEP_FIELD(name, expr) {name, [](const Out& o) { return uint64_t(expr); }}

// Pt: the phase timer's build (PTIMER = 1, with CONIC and FEED).
template <class V, bool Conic = false, bool Pt = false>
struct CmdPortT {
  using Rtl = AfterOneResetEdge<V>;
  using Model = model::CpCmd;
  using In = model::CpCmdIn;
  using Out = model::CpCmdOut;
  static Model::Params model_params() { return {3, 4095, 3, 3, 8, Conic, Conic, false, Pt}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.cmd_valid_i = i.cmd_valid;
    r.flush_i = i.flush;
    r.cmd_data_i = i.cmd_data;
    r.rsp_ready_i = i.rsp_ready;
    r.read_data_i = i.read_data;
    r.fault_i = i.fault;
    r.running_i = i.running;
    r.pulse_busy_i = i.pulse_busy;
    r.seg_full_i = i.seg_full;
    r.ch_full_i = i.ch_full;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.cmd_ready = r.cmd_ready_o;
    o.rsp_valid = r.rsp_valid_o;
    o.rsp_data = r.rsp_data_o;
    o.rsp_addr = r.rsp_addr_o;
    o.seg_wr = r.seg_wr_o;
    o.seg_data = r.seg_wdata_o;
    o.seg_commit = r.seg_commit_o;
    o.seg_rollback = r.seg_rollback_o;
    o.ch_wr = r.ch_wr_o;
    o.ch_data = sim::get_word(r.ch_wdata_o);
    o.ch_commit = r.ch_commit_o;
    o.ch_rollback = r.ch_rollback_o;
    o.start = r.start_o;
    o.abort = r.abort_o;
    o.clear = r.clear_o;
    o.drivers_on = r.drivers_on_o;
    o.drivers_off = r.drivers_off_o;
    o.cfg_write = r.cfg_write_o;
    o.fault = r.fault_o;
    o.fault_code = r.fault_code_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("cmd_ready_o", o.cmd_ready),     CPSTEP_FIELD("rsp_valid_o", o.rsp_valid),
        CPSTEP_FIELD("rsp_data_o", o.rsp_data),       CPSTEP_FIELD("rsp_addr_o", o.rsp_addr),
        CPSTEP_FIELD("seg_wr_o", o.seg_wr),           CPSTEP_FIELD("seg_wdata_o", o.seg_data),
        CPSTEP_FIELD("seg_commit_o", o.seg_commit),   CPSTEP_FIELD("seg_rollback_o", o.seg_rollback),
        CPSTEP_FIELD("ch_wr_o", o.ch_wr),             CPSTEP_FIELD("ch_wdata_o[63:0]", o.ch_data[0]),
        CPSTEP_FIELD("ch_wdata_o[80:64]", o.ch_data[1]), CPSTEP_FIELD("ch_commit_o", o.ch_commit),
        CPSTEP_FIELD("ch_rollback_o", o.ch_rollback), CPSTEP_FIELD("start_o", o.start),
        CPSTEP_FIELD("abort_o", o.abort),             CPSTEP_FIELD("clear_o", o.clear),
        CPSTEP_FIELD("drivers_on_o", o.drivers_on),   CPSTEP_FIELD("drivers_off_o", o.drivers_off),
        CPSTEP_FIELD("cfg_write_o", o.cfg_write),     CPSTEP_FIELD("fault_o", o.fault),
        CPSTEP_FIELD("fault_code_o", o.fault_code),
    };
    return f;
  }
};
using CmdPort = CmdPortT<Vcp_part_cmd>;
using CmdConicPort = CmdPortT<Vcp_part_cmd_conic, true>;
using CmdPtimerPort = CmdPortT<Vcp_part_cmd_ptimer, true, true>;

// Pt: the phase timer's build (PTIMER = 1): the run queue word's L, k, U above its fields.
template <class V, bool Conic = false, bool Pt = false>
struct BuildPortT {
  using Rtl = AfterOneResetEdge<V>;
  using Model = model::CpBuild;
  using In = model::CpBuildIn;
  using Out = model::CpBuildOut;
  static Model::Params model_params() { return {3, 32, 200, 1, Conic, Pt}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.walker_free_i = i.walker_free;
    r.flush_i = i.flush;
    r.fault_i = i.fault;
    r.seg_valid_i = i.seg_valid;
    r.seg_head_i = i.seg_head;
    r.seg_commit_i = i.seg_commit;
    r.run_level_i = i.run_level;
    r.cur_valid_i = i.cur_valid;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.seg_pop = r.seg_pop_o;
    o.run_wr = r.run_wr_o;
    if constexpr (Pt) {
      constexpr unsigned rcw = 9 + (Conic ? 7 : 0);
      const model::FifoWord w = sim::get_word(r.run_wdata_o);
      o.run_data = w[0] & model::bits::mask64(rcw);
      o.run_data_pt = (w[0] >> rcw | w[1] << (64 - rcw)) & model::bits::mask64(60);
    } else {
      o.run_data = r.run_wdata_o;
    }
    o.bank_we = r.bank_we_o;
    o.bank_axis = r.bank_axis_o;
    o.bank_waddr = r.bank_waddr_o;
    o.bank_wbit = r.bank_wbit_o;
    o.build_lane = r.build_lane_o;
    o.len_we = r.len_we_o;
    o.len_m1 = r.len_m1_o;
    o.fault = r.fault_o;
    o.busy = r.busy_o;
    o.segq = r.segq_o;
    o.cw_wr = r.cw_wr_o;
    o.cw_sel = r.cw_sel_o;
    o.cw_data = r.cw_data_o;
    o.cw_start = r.cw_start_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("seg_pop_o", o.seg_pop),       CPSTEP_FIELD("run_wr_o", o.run_wr),
        CPSTEP_FIELD("run_wdata_o", o.run_data),    CPSTEP_FIELD("run_wdata_o[L,k,U]", o.run_data_pt),
        CPSTEP_FIELD("bank_we_o", o.bank_we),
        CPSTEP_FIELD("bank_axis_o", o.bank_axis),   CPSTEP_FIELD("bank_waddr_o", o.bank_waddr),
        CPSTEP_FIELD("bank_wbit_o", o.bank_wbit),   CPSTEP_FIELD("build_lane_o", o.build_lane),
        CPSTEP_FIELD("len_we_o", o.len_we),         CPSTEP_FIELD("len_m1_o", o.len_m1),
        CPSTEP_FIELD("fault_o", o.fault),           CPSTEP_FIELD("busy_o", o.busy),
        CPSTEP_FIELD("segq_o", o.segq),             CPSTEP_FIELD("cw_wr_o", o.cw_wr),
        CPSTEP_FIELD("cw_sel_o", o.cw_sel),         CPSTEP_FIELD("cw_data_o", o.cw_data),
        CPSTEP_FIELD("cw_start_o", o.cw_start),
    };
    return f;
  }
};
using BuildPort = BuildPortT<Vcp_part_build>;
using BuildConicPort = BuildPortT<Vcp_part_build_conic, true>;
using BuildPtimerPort = BuildPortT<Vcp_part_build_ptimer, true, true>;

// The conic runner's walker: IW = 36. Pt: timed by the phase timer (PTIMER = 1).
template <class V, bool Conic = false, bool Pt = false>
struct RunPortT {
  using Rtl = AfterOneResetEdge<V>;
  using Model = model::CpRun;
  using In = model::CpRunIn;
  using Out = model::CpRunOut;
  static Model::Params model_params() { return {3, 32, Conic, 36, Pt}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.cw_wr_i = i.cw_wr;
    r.cw_sel_i = i.cw_sel & 7;
    r.cw_data_i = i.cw_data;
    r.cw_start_i = i.cw_start;
    r.flush_i = i.flush;
    r.estop_i = i.estop;
    r.start_i = i.start;
    r.stop_i = i.stop;
    r.abort_i = i.abort;
    r.fault_i = i.fault;
    r.ch_valid_i = i.ch_valid;
    sim::put_word(r.ch_head_i, i.ch_head);
    r.run_valid_i = i.run_valid;
    if constexpr (Pt) {
      // {L, k, U} above the other fields (9 bits with N = 3, 16 with the conic's).
      constexpr unsigned rcw = 9 + (Conic ? 7 : 0);
      sim::put_word(r.run_head_i, model::FifoWord{i.run_head | i.run_head_pt << rcw, i.run_head_pt >> (64 - rcw), 0, 0});
    } else {
      r.run_head_i = i.run_head;
    }
    r.run_level_i = i.run_level;
    r.segq_empty_i = i.segq_empty;
    r.build_busy_i = i.build_busy;
    r.bank_we_i = i.bank_we;
    r.bank_axis_i = i.bank_axis;
    r.bank_waddr_i = i.bank_waddr;
    r.bank_wbit_i = i.bank_wbit;
    r.bank_lane_i = i.bank_lane;
    r.len_we_i = i.len_we;
    r.len_m1_i = i.len_m1;
    r.pulse_ready_i = i.pulse_ready;
    r.lim_min_i = i.lim_min;
    r.lim_max_i = i.lim_max;
    r.scale_i = i.scale;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.ch_pop = r.ch_pop_o;
    o.run_pop = r.run_pop_o;
    o.step = r.step_o;
    o.dir = r.dir_o;
    o.running = r.running_o;
    o.torch = r.torch_o;
    o.cur_valid = r.cur_valid_o;
    o.fire = r.fire_o;
    o.seg_done = r.seg_done_o;
    o.stretch = r.stretch_o;
    o.seg_active = r.seg_active_o;
    o.fault = r.fault_o;
    o.fault_conic = r.fault_conic_o;
    o.walker_free = r.walker_free_o;
    o.lim_hit = r.lim_hit_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("fault_conic_o", o.fault_conic), CPSTEP_FIELD("walker_free_o", o.walker_free),
        CPSTEP_FIELD("ch_pop_o", o.ch_pop),         CPSTEP_FIELD("run_pop_o", o.run_pop),
        CPSTEP_FIELD("step_o", o.step),             CPSTEP_FIELD("dir_o", o.dir),
        CPSTEP_FIELD("running_o", o.running),       CPSTEP_FIELD("cur_valid_o", o.cur_valid),
        CPSTEP_FIELD("fire_o", o.fire),             CPSTEP_FIELD("seg_done_o", o.seg_done),
        CPSTEP_FIELD("stretch_o", o.stretch),       CPSTEP_FIELD("seg_active_o", o.seg_active),
        CPSTEP_FIELD("fault_o", o.fault),           CPSTEP_FIELD("torch_o", o.torch),
        CPSTEP_FIELD("lim_hit_o", o.lim_hit),
    };
    return f;
  }
};
using RunPort = RunPortT<Vcp_part_run>;
using RunConicPort = RunPortT<Vcp_part_run_conic, true>;
using RunPtimerPort = RunPortT<Vcp_part_run_ptimer, false, true>;

struct StatusPort {
  using Rtl = AfterOneResetEdge<Vcp_part_status>;
  using Model = model::CpStatus;
  using In = model::CpStatusIn;
  using Out = model::CpStatusOut;
  static constexpr unsigned kN = 3, kTW = 8, kPW = 40;
  static Model::Params model_params() {
    model::CpStatusParams p;
    p.n = kN;
    p.w = 32;
    p.umax = 4095;
    p.kmax = 3;
    p.caw = 3;
    p.saw = 1;
    p.tw = kTW;
    p.pw = kPW;
    p.step_high_reset = 3;
    p.step_low_reset = 2;
    p.dir_setup_reset = 5;
    p.dir_hold_reset = 4;
    p.step_pol_reset = false;
    p.dir_pol_reset = true;
    p.cbuf_aw = 5;
    p.clock_hz = 12345678;
    p.build_id = 3735928559u;
    p.conic = true;
    p.ciw = 36;
    p.inputs = true;
    p.feed = true;
    return p;
  }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.estop_i = i.estop;
    r.abort_i = i.abort;
    r.clear_i = i.clear;
    r.ack_i = i.ack;
    r.kick_i = i.kick;
    r.lim_hit_i = i.lim_hit;
    r.lim_min_i = i.lim_min;
    r.lim_max_i = i.lim_max;
    r.probe_i = i.probe;
    r.feed_i = i.feed;
    r.override_i = i.override;
    r.drivers_on_i = i.drivers_on;
    r.drivers_off_i = i.drivers_off;
    r.cfg_write_i = i.cfg_write;
    r.cfg_word_i = i.cfg_word;
    r.cmd_fault_i = i.cmd_fault;
    r.cmd_code_i = i.cmd_code;
    r.build_fault_i = i.build_fault;
    r.run_fault_i = i.run_fault;
    r.run_conic_i = i.run_conic;
    r.stretch_i = i.stretch;
    r.fire_i = i.fire;
    r.seg_done_i = i.seg_done;
    r.seg_active_i = i.seg_active;
    r.running_i = i.running;
    r.torch_i = i.torch;
    r.cur_valid_i = i.cur_valid;
    r.segq_i = i.segq;
    r.build_busy_i = i.build_busy;
    r.run_level_i = i.run_level;
    r.ch_level_i = i.ch_level;
    model::FifoWord pos{};
    for (unsigned a = 0; a < kN; ++a) model::bits::put(pos, kPW * a, kPW, i.position[a]);
    sim::put_word(r.position_i, pos);
    r.rd_addr0_i = i.rd_addr0;
    r.rd_addr1_i = i.rd_addr1;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.rd_data0 = r.rd_data0_o;
    o.rd_data1 = r.rd_data1_o;
    o.fault = r.fault_o;
    o.err = r.err_o;
    o.flush = r.flush_o;
    o.stretched = r.stretched_o;
    o.enable = r.enable_o;
    o.status = r.status_o;
    o.stretch_count = r.stretch_cnt_o;
    o.moves_done = r.moves_done_o;
    o.segments_done = r.segs_done_o;
    for (unsigned a = 0; a < kN; ++a) {
      model::PulseConfig& c = o.cfg[a];
      c.step_high = uint32_t(r.cfg_high_o >> (kTW * a)) & 0xFF;
      c.step_low = uint32_t(r.cfg_low_o >> (kTW * a)) & 0xFF;
      c.dir_setup = uint32_t(r.cfg_setup_o >> (kTW * a)) & 0xFF;
      c.dir_hold = uint32_t(r.cfg_hold_o >> (kTW * a)) & 0xFF;
      c.step_pol = (r.cfg_step_pol_o >> a & 1) != 0;
      c.dir_pol = (r.cfg_dir_pol_o >> a & 1) != 0;
    }
    o.cfg_new = r.cfg_new_o;
    o.wd_trip = r.wd_trip_o;
    return o;
  }
  // Axis a's configuration packed: high, low, setup, hold (8 bits each), polarities.
  static uint64_t cfg_bits(const Out& o, unsigned a) {
    const model::PulseConfig& c = o.cfg[a];
    return uint64_t(c.step_high) | uint64_t(c.step_low) << 8 | uint64_t(c.dir_setup) << 16 |
           uint64_t(c.dir_hold) << 24 | uint64_t(c.step_pol) << 32 | uint64_t(c.dir_pol) << 33;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("rd_data0_o", o.rd_data0),       CPSTEP_FIELD("rd_data1_o", o.rd_data1),
        CPSTEP_FIELD("fault_o", o.fault),             CPSTEP_FIELD("err_o", o.err),
        CPSTEP_FIELD("flush_o", o.flush),             CPSTEP_FIELD("stretched_o", o.stretched),
        CPSTEP_FIELD("enable_o", o.enable),           CPSTEP_FIELD("status_o", o.status),
        CPSTEP_FIELD("stretch_cnt_o", o.stretch_count), CPSTEP_FIELD("moves_done_o", o.moves_done),
        CPSTEP_FIELD("segs_done_o", o.segments_done), CPSTEP_FIELD("cfg_new_o", o.cfg_new),
        CPSTEP_FIELD("wd_trip_o", o.wd_trip),
        CPSTEP_FIELD("cfg axis 0 {pols, hold, setup, low, high}", cfg_bits(o, 0)),
        CPSTEP_FIELD("cfg axis 1 {pols, hold, setup, low, high}", cfg_bits(o, 1)),
        CPSTEP_FIELD("cfg axis 2 {pols, hold, setup, low, high}", cfg_bits(o, 2)),
    };
    return f;
  }

};

struct InputsPort {
  using Rtl = AfterOneResetEdge<Vcp_part_inputs>;
  using Model = model::CpInputs;
  using In = model::CpInputsIn;
  using Out = model::CpInputsOut;
  static Model::Params model_params() { return 3; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.lim_min_i = i.lim_min;
    r.lim_max_i = i.lim_max;
    r.probe_i = i.probe;
    r.cfg_write_i = i.cfg_write;
    r.cfg_word_i = i.cfg_word;
    r.running_i = i.running;
    r.lim_hit_i = i.lim_hit;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.lim_min = r.lim_min_o;
    o.lim_max = r.lim_max_o;
    o.probe = r.probe_o;
    o.seek_stop = r.seek_stop_o;
    o.seek_lim = r.seek_lim_o;
    o.seek = r.seek_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("lim_min_o", o.lim_min), CPSTEP_FIELD("lim_max_o", o.lim_max),
        CPSTEP_FIELD("probe_o", o.probe),     CPSTEP_FIELD("seek_stop_o", o.seek_stop),
        CPSTEP_FIELD("seek_lim_o", o.seek_lim), CPSTEP_FIELD("seek_o", o.seek),
    };
    return f;
  }
};

struct FeedPort {
  using Rtl = AfterOneResetEdge<Vcp_part_feed>;
  using Model = model::CpFeed;
  using In = model::CpFeedIn;
  using Out = model::CpFeedOut;
  static Model::Params model_params() { return {}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.cfg_write_i = i.cfg_write;
    r.cfg_word_i = i.cfg_word;
    r.hold_i = i.hold;
    r.resume_i = i.resume;
    r.ovr_i = i.ovr;
    r.ovr_val_i = i.ovr_val;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.scale = r.scale_o;
    o.feed = r.feed_o;
    o.override = r.override_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("scale_o", o.scale), CPSTEP_FIELD("feed_o", o.feed),
        CPSTEP_FIELD("override_o", o.override),
    };
    return f;
  }
};

#undef CPSTEP_FIELD

}  // namespace cpstep::tb

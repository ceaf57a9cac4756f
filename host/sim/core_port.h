// SPDX-License-Identifier: MIT
// Port adaptor for Verilated cp_core configurations (see dut.h).
#pragma once

#include <vector>

#include "model/cp_core_ports.h"
#include "sim/dut.h"

namespace cpstep::model {
class CpCore;
}

namespace cpstep::sim {

template <class V, unsigned N>
struct CorePortBase {
  using Rtl = V;
  using In = model::CpCoreIn;
  using Out = model::CpCoreOut;

  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.cmd_valid_i = i.cmd_valid;
    r.cmd_data_i = i.cmd_data;
    r.rsp_ready_i = i.rsp_ready;
    r.estop_i = i.estop;
    r.ctl_start_i = i.ctl_start;
    r.ctl_stop_i = i.ctl_stop;
    r.ctl_flush_i = i.ctl_flush;
    r.ctl_ack_i = i.ctl_ack;
    r.kick_i = i.kick;
    r.ctl_hold_i = i.ctl_hold;
    r.ctl_resume_i = i.ctl_resume;
    r.ctl_ovr_i = i.ctl_ovr;
    r.ctl_ovr_val_i = i.ctl_ovr_val;
    r.lim_min_i = i.lim_min;
    r.lim_max_i = i.lim_max;
    r.probe_i = i.probe;
    r.rd_addr_i = i.rd_addr;
  }
  static Out sample(const V& r) {
    Out o;
    o.cmd_ready = r.cmd_ready_o;
    o.rsp_valid = r.rsp_valid_o;
    o.rsp_data = r.rsp_data_o;
    o.rsp_addr = r.rsp_addr_o;
    o.rd_data = r.rd_data_o;
    o.step = r.step_o;
    o.dir = r.dir_o;
    o.torch = r.torch_o;
    o.running = r.running_o;
    o.fault = r.fault_o;
    o.stretched = r.stretched_o;
    o.err_code = r.err_code_o;
    o.enable = r.enable_o;
    o.status = r.status_o;
    o.stretch_count = r.stretch_cnt_o;
    o.moves_done = r.moves_done_o;
    o.segments_done = r.segs_done_o;
    for (unsigned a = 0; a < N; ++a) o.position[a] = int32_t(position_word(r, a));
    return o;
  }
  static const std::vector<Field<Out>>& fields() {
    static const std::vector<Field<Out>> f = [] {
      std::vector<Field<Out>> v = {
          {"cmd_ready_o", [](const Out& o) { return uint64_t(o.cmd_ready); }},
          {"rsp_valid_o", [](const Out& o) { return uint64_t(o.rsp_valid); }},
          {"rsp_data_o", [](const Out& o) { return uint64_t(o.rsp_data); }},
          {"rsp_addr_o", [](const Out& o) { return uint64_t(o.rsp_addr); }},
          {"rd_data_o", [](const Out& o) { return uint64_t(o.rd_data); }},
          {"step_o", [](const Out& o) { return uint64_t(o.step); }},
          {"dir_o", [](const Out& o) { return uint64_t(o.dir); }},
          {"torch_o", [](const Out& o) { return uint64_t(o.torch); }},
          {"running_o", [](const Out& o) { return uint64_t(o.running); }},
          {"fault_o", [](const Out& o) { return uint64_t(o.fault); }},
          {"stretched_o", [](const Out& o) { return uint64_t(o.stretched); }},
          {"err_code_o", [](const Out& o) { return uint64_t(o.err_code); }},
          {"enable_o", [](const Out& o) { return uint64_t(o.enable); }},
          {"status_o", [](const Out& o) { return uint64_t(o.status); }},
          {"stretch_cnt_o", [](const Out& o) { return uint64_t(o.stretch_count); }},
          {"moves_done_o", [](const Out& o) { return uint64_t(o.moves_done); }},
          {"segs_done_o", [](const Out& o) { return uint64_t(o.segments_done); }},
      };
      static const char* names[] = {"position_o[x]", "position_o[y]", "position_o[z]",
                                    "position_o[a]", "position_o[4]", "position_o[5]",
                                    "position_o[6]", "position_o[7]"};
      static uint64_t (*getters[])(const Out&) = {
          [](const Out& o) { return uint64_t(o.position[0]); },
          [](const Out& o) { return uint64_t(o.position[1]); },
          [](const Out& o) { return uint64_t(o.position[2]); },
          [](const Out& o) { return uint64_t(o.position[3]); },
          [](const Out& o) { return uint64_t(o.position[4]); },
          [](const Out& o) { return uint64_t(o.position[5]); },
          [](const Out& o) { return uint64_t(o.position[6]); },
          [](const Out& o) { return uint64_t(o.position[7]); },
      };
      for (unsigned a = 0; a < N; ++a) v.push_back({names[a], getters[a]});
      return v;
    }();
    return f;
  }

 private:
  // position_o is N*32 bits: an integer up to 64 bits, a word array above.
  static uint32_t position_word(const V& r, unsigned a) {
    if constexpr (N * 32 <= 64) return uint32_t(uint64_t(r.position_o) >> (32 * a));
    else return r.position_o[a];
  }
};

// A core port against the model with event skipping (SkippingModelDut,
// CpCore::quiet_for): the lockstep benches that prove the fast engine's core.
// Inputs that differ only in the read port's address are held: the registers
// it reads do not change while the core is quiet.
template <class Core>
struct Skipping : Core {
  using ModelStepper = SkippingModelDut<Skipping>;
  static bool held_equal(const model::CpCoreIn& a, const model::CpCoreIn& b) {
    model::CpCoreIn x = a;
    x.rd_addr = b.rd_addr;
    return x == b;
  }
};

}  // namespace cpstep::sim

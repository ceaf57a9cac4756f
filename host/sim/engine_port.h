// SPDX-License-Identifier: MIT
// Port adaptor between a Verilated cp_engine configuration and model::CpEngine
// (see dut.h for what an adaptor provides).
#pragma once

#include <vector>

#include "model/cp_engine.h"
#include "sim/dut.h"

namespace cpstep::sim {

template <class V, unsigned W, unsigned KMAX, unsigned RW, unsigned UMAX = W>
struct EnginePort {
  using Rtl = V;
  using Model = model::CpEngine;
  using In = model::CpEngineIn;
  using Out = model::CpEngineOut;

  static Model::Params model_params() { return {W, KMAX, RW, UMAX}; }

  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.in_valid_i = i.in_valid;
    r.in_u_i = i.in_u;
    r.in_v_i = i.in_v;
    r.in_k_i = i.in_k;
    r.in_rep_i = i.in_rep;
    r.move_ready_i = i.move_ready;
  }

  static Out sample(const V& r) {
    Out o;
    o.in_ready = r.in_ready_o;
    o.err = r.err_o;
    o.err_code = r.err_code_o;
    o.move_valid = r.move_valid_o;
    o.move = r.move_o;
    o.move_last = r.move_last_o;
    o.move_pend = r.move_pend_o;
    o.dbg_we1 = r.dbg_we1_o;
    o.dbg_waddr1 = r.dbg_waddr1_o;
    o.dbg_wbit1 = r.dbg_wbit1_o;
    o.dbg_we2 = r.dbg_we2_o;
    o.dbg_waddr2 = r.dbg_waddr2_o;
    o.dbg_wbit2 = r.dbg_wbit2_o;
    o.dbg_iter = r.dbg_iter_o;
    o.dbg_x = r.dbg_x_o;
    o.dbg_y = r.dbg_y_o;
    o.dbg_m1_lo = r.dbg_m1_lo_o;
    o.dbg_m1_len = r.dbg_m1_len_o;
    o.dbg_m1_rev = r.dbg_m1_rev_o;
    o.dbg_m2_lo = r.dbg_m2_lo_o;
    o.dbg_m2_len = r.dbg_m2_len_o;
    o.dbg_m2_rev = r.dbg_m2_rev_o;
    return o;
  }

  static const std::vector<Field<Out>>& fields() {
#define CPSTEP_FIELD(port, member) \
  Field<Out> { port, [](const Out& o) { return uint64_t(o.member); } }
    static const std::vector<Field<Out>> f = {
        CPSTEP_FIELD("in_ready_o", in_ready),     CPSTEP_FIELD("err_o", err),
        CPSTEP_FIELD("err_code_o", err_code),     CPSTEP_FIELD("move_valid_o", move_valid),
        CPSTEP_FIELD("move_o", move),             CPSTEP_FIELD("move_last_o", move_last),
        CPSTEP_FIELD("move_pend_o", move_pend),
        CPSTEP_FIELD("dbg_we1_o", dbg_we1),       CPSTEP_FIELD("dbg_waddr1_o", dbg_waddr1),
        CPSTEP_FIELD("dbg_wbit1_o", dbg_wbit1),   CPSTEP_FIELD("dbg_we2_o", dbg_we2),
        CPSTEP_FIELD("dbg_waddr2_o", dbg_waddr2), CPSTEP_FIELD("dbg_wbit2_o", dbg_wbit2),
        CPSTEP_FIELD("dbg_iter_o", dbg_iter),     CPSTEP_FIELD("dbg_x_o", dbg_x),
        CPSTEP_FIELD("dbg_y_o", dbg_y),           CPSTEP_FIELD("dbg_m1_lo_o", dbg_m1_lo),
        CPSTEP_FIELD("dbg_m1_len_o", dbg_m1_len), CPSTEP_FIELD("dbg_m1_rev_o", dbg_m1_rev),
        CPSTEP_FIELD("dbg_m2_lo_o", dbg_m2_lo),   CPSTEP_FIELD("dbg_m2_len_o", dbg_m2_len),
        CPSTEP_FIELD("dbg_m2_rev_o", dbg_m2_rev),
    };
#undef CPSTEP_FIELD
    return f;
  }
};

}  // namespace cpstep::sim

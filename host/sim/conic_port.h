// SPDX-License-Identifier: MIT
// Port adaptor between a Verilated cp_conic configuration and model::CpConic
// (see dut.h for what an adaptor provides).
#pragma once

#include <vector>

#include "model/cp_conic.h"
#include "sim/dut.h"

namespace cpstep::sim {

template <class V, unsigned QW, unsigned LW, unsigned FW, unsigned PW, uint32_t NMAX>
struct ConicPort {
  using Rtl = V;
  using Model = model::CpConic;
  using In = model::CpConicIn;
  using Out = model::CpConicOut;

  static Model::Params model_params() { return {QW, LW, FW, PW, NMAX}; }

  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.in_valid_i = i.in_valid;
    r.in_a_i = uint64_t(i.in_a);
    r.in_b_i = uint64_t(i.in_b);
    r.in_c_i = uint64_t(i.in_c);
    r.in_d_i = uint64_t(i.in_d);
    r.in_e_i = uint64_t(i.in_e);
    r.in_f_i = uint64_t(i.in_f);
    r.in_x0_i = uint32_t(i.in_x0);
    r.in_y0_i = uint32_t(i.in_y0);
    r.in_x1_i = uint32_t(i.in_x1);
    r.in_y1_i = uint32_t(i.in_y1);
    r.in_cw_i = i.in_cw;
    r.move_ready_i = i.move_ready;
  }

  // The two's-complement fields back to signed values.
  static int step_of(unsigned v) { return (v & 2) ? -1 : int(v & 1); }
  static int64_t coord_of(uint64_t v) {
    const unsigned xw = model_params().xw();
    const uint64_t sign = uint64_t(1) << (xw - 1);
    v &= (sign << 1) - 1;
    return int64_t(v ^ sign) - int64_t(sign);
  }

  static Out sample(const V& r) {
    Out o;
    o.in_ready = r.in_ready_o;
    o.err = r.err_o;
    o.err_code = r.err_code_o;
    o.move_valid = r.move_valid_o;
    o.move_dx = step_of(r.move_dx_o);
    o.move_dy = step_of(r.move_dy_o);
    o.move_last = r.move_last_o;
    o.move_x = coord_of(r.move_x_o);
    o.move_y = coord_of(r.move_y_o);
    return o;
  }

  static const std::vector<Field<Out>>& fields() {
#define CPSTEP_FIELD(port, member) \
  Field<Out> { port, [](const Out& o) { return uint64_t(o.member); } }
    static const std::vector<Field<Out>> f = {
        CPSTEP_FIELD("in_ready_o", in_ready),     CPSTEP_FIELD("err_o", err),
        CPSTEP_FIELD("err_code_o", err_code),     CPSTEP_FIELD("move_valid_o", move_valid),
        CPSTEP_FIELD("move_dx_o", move_dx),       CPSTEP_FIELD("move_dy_o", move_dy),
        CPSTEP_FIELD("move_last_o", move_last),   CPSTEP_FIELD("move_x_o", move_x),
        CPSTEP_FIELD("move_y_o", move_y),
    };
#undef CPSTEP_FIELD
    return f;
  }
};

}  // namespace cpstep::sim

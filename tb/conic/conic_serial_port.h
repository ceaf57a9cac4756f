// SPDX-License-Identifier: MIT
// Port adaptor between a Verilated cp_conic_serial configuration and
// model::CpConicSerial (see sim/dut.h for what an adaptor provides), and the three
// configurations of rtl/CMakeLists.txt: the defaults, a narrow one, and the defaults
// with the length rule's divider (LEN = 1, a phase-timer core's walker).
#pragma once

#include <vector>

#include "Vcp_conic_serial.h"
#include "Vcp_conic_serial_len.h"
#include "Vcp_conic_serial_small.h"
#include "model/cp_conic_serial.h"
#include "sim/dut.h"

namespace cpstep::tb {

template <class V, unsigned QW, unsigned IW, unsigned XW, bool LEN = false>
struct ConicSerialPort {
  using Rtl = V;
  using Model = model::CpConicSerial;
  using In = model::CpConicSerialIn;
  using Out = model::CpConicSerialOut;

  static Model::Params model_params() { return {QW, IW, XW, LEN}; }

  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.clear_i = i.clear;
    r.wr_i = i.wr;
    r.wr_sel_i = i.wr_sel & 7;
    r.wr_data_i = i.wr_data;
    r.start_i = i.start;
    r.cont_i = i.cont;
    r.move_ready_i = i.move_ready;
    r.len_k_i = i.len_k;
    r.len_go_i = i.len_go;
  }

  static int step_of(unsigned v) { return (v & 2) ? -1 : int(v & 1); }

  static Out sample(const V& r) {
    Out o;
    o.busy = r.busy_o;
    o.move_valid = r.move_valid_o;
    o.move_dx = step_of(r.move_dx_o);
    o.move_dy = step_of(r.move_dy_o);
    o.move_end = r.move_end_o;
    o.len = r.len_o;
    return o;
  }

  static const std::vector<sim::Field<Out>>& fields() {
#define CPSTEP_FIELD(port, member) \
  sim::Field<Out> { port, [](const Out& o) { return uint64_t(o.member); } }
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("busy_o", busy),           CPSTEP_FIELD("move_valid_o", move_valid),
        CPSTEP_FIELD("move_dx_o", move_dx),     CPSTEP_FIELD("move_dy_o", move_dy),
        CPSTEP_FIELD("move_end_o", move_end),   CPSTEP_FIELD("len_o", len),
    };
#undef CPSTEP_FIELD
    return f;
  }
};

using ConicSerialDefault = ConicSerialPort<Vcp_conic_serial, 16, 40, 24>;
using ConicSerialSmall = ConicSerialPort<Vcp_conic_serial_small, 6, 12, 8>;
using ConicSerialLen = ConicSerialPort<Vcp_conic_serial_len, 16, 40, 24, true>;

}  // namespace cpstep::tb

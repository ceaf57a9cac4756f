// SPDX-License-Identifier: MIT
// Port adaptor between a Verilated cp_pulse configuration and model::CpPulse
// (see dut.h for what an adaptor provides).
#pragma once

#include <cstdint>
#include <vector>

#include "model/cp_pulse.h"
#include "sim/dut.h"

namespace cpstep::sim {

template <class V, unsigned TW, unsigned PW, bool STEP_POL_RESET = true, bool DIR_POL_RESET = true>
struct PulsePort {
  using Rtl = V;
  using Model = model::CpPulse;
  using In = model::CpPulseIn;
  using Out = model::CpPulseOut;

  static constexpr unsigned tw = TW;
  static constexpr unsigned pw = PW;

  static Model::Params model_params() { return {TW, PW, STEP_POL_RESET, DIR_POL_RESET}; }

  static void drive(V& r, const In& i) {
    // Verilator does not mask a port's unused upper bits: keep them zero.
    constexpr uint32_t m = TW >= 32 ? ~0u : (1u << TW) - 1;
    r.rst = i.rst;
    r.cfg_step_high_i = i.cfg_step_high & m;
    r.cfg_step_low_i = i.cfg_step_low & m;
    r.cfg_dir_setup_i = i.cfg_dir_setup & m;
    r.cfg_dir_hold_i = i.cfg_dir_hold & m;
    r.cfg_step_pol_i = i.cfg_step_pol;
    r.cfg_dir_pol_i = i.cfg_dir_pol;
    r.cfg_new_i = i.cfg_new;
    r.dir_i = i.dir;
    r.step_i = i.step;
  }

  static Out sample(const V& r) {
    Out o;
    o.ready = r.ready_o;
    o.step = r.step_o;
    o.dir = r.dir_o;
    o.position = r.position_o;
    o.busy = r.busy_o;
    return o;
  }

  static const std::vector<Field<Out>>& fields() {
#define CPSTEP_FIELD(port, member) \
  Field<Out> { port, [](const Out& o) { return uint64_t(o.member); } }
    static const std::vector<Field<Out>> f = {
        CPSTEP_FIELD("ready_o", ready), CPSTEP_FIELD("step_o", step),
        CPSTEP_FIELD("dir_o", dir),     CPSTEP_FIELD("position_o", position),
        CPSTEP_FIELD("busy_o", busy),
    };
#undef CPSTEP_FIELD
    return f;
  }
};

}  // namespace cpstep::sim

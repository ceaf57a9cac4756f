// The small cp_core of rtl/CMakeLists.txt (cpstep_rtl_core_small), for fast tests:
// 2 axes, W = 32, UMAX = 4095, KMAX = 3, a chunk queue of 8, active-low STEP and
// DIR-low-positive at reset.
#pragma once

#include "Vcp_core_small.h"
#include "model/cp_core.h"
#include "sim/core_port.h"

namespace cpstep::sim {

struct CoreSmall : CorePortBase<Vcp_core_small, 2> {
  using Model = model::CpCore;
  static Model::Params model_params() {
    Model::Params p;
    p.n = 2;
    p.w = 32;
    p.umax = 4095;
    p.kmax = 3;
    p.caw = 3;
    p.saw = 2;
    p.tw = 8;
    p.step_pol_reset = false;
    p.dir_pol_reset = false;
    return p;
  }
};

}  // namespace cpstep::sim

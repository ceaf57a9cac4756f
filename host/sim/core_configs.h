// The Verilated cp_core configurations built by rtl/CMakeLists.txt, with their model.
#pragma once

#include "Vcp_core.h"
#include "model/cp_core.h"
#include "sim/core_port.h"

namespace cpstep::sim {

// The defaults: 4 axes, W = 1024, UMAX = 2^20 - 1, KMAX = 8, a chunk queue of 64.
struct CoreDefault : CorePortBase<Vcp_core, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() { return {}; }
};

}  // namespace cpstep::sim

// The cp_core of rtl/CMakeLists.txt whose chunk check multiplies with `*` (MUL_DSP = 1:
// the UP5K's DSP blocks) at the default parameters otherwise (cpstep_rtl_core_dsp).
// The validation benches run against it and against the bit-serial default: the
// same model, cycle for cycle.
#pragma once

#include "Vcp_core_dsp.h"
#include "model/cp_core.h"
#include "sim/core_port.h"

namespace cpstep::sim {

struct CoreDsp : CorePortBase<Vcp_core_dsp, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() { return {}; }
};

}  // namespace cpstep::sim

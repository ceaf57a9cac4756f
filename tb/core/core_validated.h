// The core the validation benches (test_core_reject.cpp, test_core_add2.cpp) run
// against: the default one, or with CPSTEP_TB_CORE_DSP (test_core_dsp in
// CMakeLists.txt) the one whose chunk check multiplies in DSP blocks.
#pragma once

#include "sim/core_configs.h"
#ifdef CPSTEP_TB_CORE_DSP
#include "core/core_dsp.h"
#endif

namespace cpstep::tb {
#ifdef CPSTEP_TB_CORE_DSP
using ValidatedCore = sim::CoreDsp;
#else
using ValidatedCore = sim::CoreDefault;
#endif
}  // namespace cpstep::tb

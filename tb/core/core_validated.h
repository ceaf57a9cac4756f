// SPDX-License-Identifier: MIT
// The core the validation benches (test_core_reject.cpp, test_core_add2.cpp) run
// against: the HX8K's build (the iCEBreaker's own core runs the random lockstep
// jobs and, as a synthesized netlist, tb/netlist); with CPSTEP_TB_CORE_SKIP (test_core_skip) the
// HX8K's build against the model with event skipping (sim::Skipping), as the
// fast engine runs it (docs/SIM.md). test_core_faults.cpp runs against it too.
#pragma once

#include "sim/core_configs.h"

namespace cpstep::tb {
#if defined(CPSTEP_TB_CORE_SKIP)
using ValidatedCore = sim::Skipping<sim::CoreDefault>;
#else
using ValidatedCore = sim::CoreDefault;
#endif
}  // namespace cpstep::tb

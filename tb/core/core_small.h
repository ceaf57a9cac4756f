// SPDX-License-Identifier: MIT
// The small cp_core of rtl/builds.json (build "small"), for fast tests: 2 axes,
// W = 32, UMAX = 4095, KMAX = 3, a chunk queue of 8, active-low STEP and
// DIR-low-positive at reset.
#pragma once

#include "Vcp_core_small.h"
#include "sim/core_configs.h"

namespace cpstep::sim {

using CoreSmall = CoreOf<builds::small, Vcp_core_small>;

}  // namespace cpstep::sim

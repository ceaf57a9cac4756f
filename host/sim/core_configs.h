// SPDX-License-Identifier: MIT
// The Verilated cp_core of every build in rtl/builds.json (rtl/CMakeLists.txt
// makes cpstep_rtl_core_<build>), each with its golden model's parameters from
// the same table.
#pragma once

#include "cpstep/board_models.h"
#include "cpstep/builds.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "sim/core_port.h"

namespace cpstep::sim {

template <const builds::Build& B, class V>
struct CoreOf : CorePortBase<V, B.n> {
  using Model = model::CpCore;
  static constexpr const builds::Build& kBuild = B;
  static Model::Params model_params() { return model::core_params(B); }
};

// The iCEBreaker's build: W = 256, UMAX = 65535, a chunk queue of 32, TW = 10,
// the chunk check's multiplier in DSP blocks.
using CoreIcebreaker = CoreOf<builds::icebreaker, Vcp_core_icebreaker>;
// The iCE40-HX8K breakout's build: the RTL's default parameters (W = 1024,
// UMAX = 2^20 - 1, KMAX = 8, a chunk queue of 64, TW = 16, bit-serial multiplier).
using CoreHx8k = CoreOf<builds::hx8k, Vcp_core_hx8k>;
// The benches' default core.
using CoreDefault = CoreHx8k;

// (sim::Skipping<Core>, sim/core_port.h: any of them against the model with event skipping.)

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// The Verilated cp_card of every board in rtl/builds.json (rtl/CMakeLists.txt
// makes cpstep_rtl_card_<build>).
#pragma once

#include "cpstep/board_models.h"
#include "cpstep/builds.h"
#include "sim/card_port.h"

namespace cpstep::sim {

template <const builds::Build& B, class V>
struct CardOf : CardPortBase<V, B.n> {
  static constexpr const builds::Build& kBuild = B;
  static constexpr unsigned kCbufWords = 1u << B.cbuf_aw;
};

using CardIcebreaker = CardOf<builds::icebreaker, Vcp_card_icebreaker>;
using CardHx8k = CardOf<builds::hx8k, Vcp_card_hx8k>;
// The benches' default card: the RTL's default parameters (the HX8K's build).
using CardDefault = CardHx8k;

}  // namespace cpstep::sim

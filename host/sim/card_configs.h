// SPDX-License-Identifier: MIT
// The Verilated cp_card of every board in rtl/builds.json (rtl/CMakeLists.txt
// makes cpstep_rtl_card_<build>), each with its golden model (model::CpCard behind
// the card's pins, sim/card_model.h) and the model's parameters from the same table.
#pragma once

#include "cpstep/board_models.h"
#include "cpstep/builds.h"
#include "sim/card_model.h"
#include "sim/card_port.h"

namespace cpstep::sim {

template <const builds::Build& B, class V>
struct CardOf : CardPortBase<V, B.n> {
  using Model = CardModel;
  static constexpr const builds::Build& kBuild = B;
  static constexpr unsigned kCbufWords = 1u << B.cbuf_aw;
  static Model::Params model_params() { return model::card_params(B); }
};

using CardIcebreaker = CardOf<builds::icebreaker, Vcp_card_icebreaker>;
using CardHx8k = CardOf<builds::hx8k, Vcp_card_hx8k>;
using CardHx8kPt = CardOf<builds::hx8k_pt, Vcp_card_hx8k_pt>;  // the phase-timer card
// The benches' default card: the RTL's default parameters (the HX8K's build).
using CardDefault = CardHx8k;

}  // namespace cpstep::sim

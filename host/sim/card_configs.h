// The Verilated cp_card configurations built by rtl/CMakeLists.txt.
#pragma once

#include "Vcp_card.h"
#include "sim/card_port.h"

namespace cpstep::sim {

// The defaults: 4 axes, W = 1024, UMAX = 2^20 - 1, KMAX = 8, a chunk queue of 64,
// a command buffer of 512 words.
struct CardDefault : CardPortBase<Vcp_card, 4> {
  static constexpr unsigned kCbufWords = 512;
};

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// The card's golden model (model::CpCard) behind the card port's pins (CardIn,
// CardOut), so ModelDut and Lockstep step it like the Verilated card (dut.h:
// `model_.in = in`, `model_.outputs()`, `model_.tick()`). A thin wrapper: the pins
// are copied through, nothing else.
#pragma once

#include "model/cp_card.h"
#include "sim/card_port.h"

namespace cpstep::sim {

class CardModel {
 public:
  using Params = model::CpCardParams;

  explicit CardModel(const Params& params = {}) : card_(params) {}

  CardIn in;

  CardOut outputs() const {
    card_.in = in;
    const model::CpCardOut m = card_.outputs();
    CardOut o;
    o.miso = m.miso;
    o.miso_oe = m.miso_oe;
    o.step = m.step;
    o.dir = m.dir;
    o.torch = m.torch;
    o.enable = m.enable;
    o.running = m.running;
    o.fault = m.fault;
    o.stretched = m.stretched;
    o.err_code = m.err_code;
    static_assert(kCardMaxAxes == model::kCoreMaxAxes);
    o.position = m.position;
    return o;
  }
  void tick() {
    card_.in = in;
    card_.tick();
  }

  model::CpCard& card() { return card_; }
  const model::CpCard& card() const { return card_; }

 private:
  // outputs() is const like every model's; the card's `in` is the copy of ours.
  mutable model::CpCard card_;
};

}  // namespace cpstep::sim

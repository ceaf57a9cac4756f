// SPDX-License-Identifier: MIT
// The fast engine (docs/SIM.md "Engines"): the card's golden model (CardModel,
// model::CpCard) stepped like the Verilated card, and advanced event to event
// wherever the pins are held: when nothing but counters can change until a known
// cycle (model::CpCard::quiet_for — the move timer waiting for the next move,
// pulse timers counting, the SPI front end with nothing on its pins, the queues
// full or empty), it jumps there at once (skip). Same pins, counters and faults
// as the RTL on every cycle: tb/e2e/test_engines.cpp proves it against the
// Verilated card, cycle by cycle and edge by edge.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string_view>
#include <vector>

#include "sim/card_configs.h"
#include "sim/card_model.h"
#include "sim/spi_master.h"

namespace cpstep::sim {

template <class Card>
class FastCardDut {
 public:
  using Params = model::CpCardParams;
  explicit FastCardDut(const Params& params = Card::model_params()) : model_(params) {
    model_.card().core().set_lazy(true);
  }

  // One clock, as RtlDut::step: the outputs before the edge, then the edge.
  CardOut step(const CardIn& in) {
    model_.in = in;
    const CardOut out = model_.outputs();
    model_.tick();
    ++cycle_;
    return out;
  }

  // `cycles` clocks with the pins `in`; on_span(first cycle, count, outputs) for
  // each run of clocks taken at once (count 1 where the model clocks normally).
  template <class OnSpan>
  void advance(const CardIn& in, uint64_t cycles, OnSpan&& on_span) {
    model_.in = in;
    // Inside a frame (CS low) with the core quiet throughout: the SPI front end
    // alone, in one go (model::CpCard::clock_front_end).
    if (!in.cs_n && cycles > 0) {
      const CardOut out = model_.outputs();
      if (model_.card().clock_front_end(cycles, nullptr)) {
        on_span(cycle_, cycles, out);
        cycle_ += cycles;
        front_end_ += cycles;
        return;
      }
    }
    while (cycles > 0) {
      const CardOut out = model_.outputs();
      // The core, lazy, finds its quiet stretches as it clocks (CpCore::set_lazy);
      // the card adds its own conditions (pins settled, buffer still).
      uint64_t n = model_.card().quiet_for(cycles);
      if (n > 0) {
        model_.card().skip(n);
        skipped_ += n;
      } else {
        model_.tick();
        n = 1;
      }
      on_span(cycle_, n, out);
      cycle_ += n;
      cycles -= n;
    }
  }

  // A whole SPI transfer's pins (SpiMaster::transfer_bits): sampled[p] gets the
  // MISO of phase p's first cycle (1 when undriven); on_span(first cycle,
  // count, pins, outputs) as for advance(). Phases inside the frame with the
  // core quiet throughout run in the front end alone, one span for a run of them.
  template <class OnSpan>
  void run_phases(const std::vector<SpiPhase>& phases, std::vector<uint8_t>& sampled, OnSpan&& on_span) {
    size_t p = 0;
    while (p < phases.size()) {
      if (phases[p].cycles == 0) {
        ++p;
        continue;
      }
      // Inside the frame with the core quiet: as many phases as can, in the front
      // end alone (model::CpCard::clock_front_end), one span for them all.
      if (!phases[p].pins.cs_n) {
        model_.in = phases[p].pins;
        const CardOut out = model_.outputs();  // the others' are the same but for MISO
        const size_t k = model_.card().clock_front_end(phases.data() + p, phases.size() - p, sampled.data() + p);
        if (k > 0) {
          uint64_t run = 0;
          for (size_t q = p; q < p + k; ++q) run += phases[q].cycles;
          on_span(cycle_, run, phases[p + k - 1].pins, out);
          cycle_ += run;
          front_end_ += run;
          p += k;
          continue;
        }
      }
      const SpiPhase& ph = phases[p];
      bool any = false;
      advance(ph.pins, ph.cycles, [&](uint64_t c, uint64_t n, const CardOut& o) {
        if (!any) sampled[p] = !o.miso_oe || o.miso;
        any = true;
        on_span(c, n, ph.pins, o);
      });
      ++p;
    }
  }

  uint64_t cycle() const { return cycle_; }
  // Clocks advanced by skipping rather than clocking, and clocks of frames with
  // the front end clocked alone (model::CpCard::clock_front_end).
  uint64_t skipped() const { return skipped_; }
  uint64_t front_end_cycles() const { return front_end_; }
  CardModel& model() { return model_; }

 private:
  CardModel model_;
  uint64_t cycle_ = 0, skipped_ = 0, front_end_ = 0;
};

// A card port whose model is the fast engine: Lockstep<Fast<CardSmall>> compares
// the fast engine with the Verilated card in every cycle, spans included
// (tb/spi/test_card_model.cpp). Inside a frame a span holds every output but MISO.
template <class Card>
struct Fast : Card {
  using ModelStepper = FastCardDut<Fast>;
  static bool span_holds(std::string_view signal) { return signal != "spi_miso_o"; }
};

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// Both engines in lockstep behind one set of pins (`cpstep run --engine
// lockstep`, docs/SIM.md "Engines"): every cycle goes to the Verilated card and to
// the fast engine, and every output of the card is compared in every cycle — in
// the fast engine's skipped spans too, cycle by cycle (MISO: where the master
// samples it, the first cycle of each span inside a frame). The first difference
// throws EngineMismatch naming the cycle, the signal, the fast engine's value
// (expected) and the RTL's (actual).
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "sim/dut.h"
#include "sim/fast_card.h"

namespace cpstep::sim {

struct EngineMismatch : std::runtime_error {
  EngineMismatch(uint64_t c, std::string s, uint64_t e, uint64_t a)
      : std::runtime_error(fmt::format("the engines differ at cycle {}: {} is {} on the fast engine (the "
                                       "model), {} on the Verilated card",
                                       c, s, e, a)),
        cycle(c),
        signal(std::move(s)),
        expected(e),
        actual(a) {}
  uint64_t cycle;
  std::string signal;
  uint64_t expected, actual;
};

template <class Card>
class TwinCardDut {
 public:
  // The fast engine with `params` (the card's own by default; tests give it
  // another card's to see the mismatch reported).
  explicit TwinCardDut(const model::CpCardParams& params = Card::model_params()) : fast_(params) {}

  CardOut step(const CardIn& in) {
    const uint64_t c = rtl_.cycle();
    const CardOut want = fast_.step(in);
    const CardOut got = rtl_.step(in);
    compare(c, want, got, true);
    return got;
  }
  template <class OnSpan>
  void advance(const CardIn& in, uint64_t cycles, OnSpan&& on_span) {
    fast_.advance(in, cycles, [&](uint64_t c, uint64_t n, const CardOut& want) {
      for (uint64_t i = 0; i < n; ++i) compare(c + i, want, rtl_.step(in), i == 0);
      on_span(c, n, want);
    });
  }
  uint64_t cycle() const { return rtl_.cycle(); }
  uint64_t skipped() const { return fast_.skipped(); }

 private:
  // In a span inside a frame the fast engine gives MISO for its first cycle only
  // (the master samples it there; model::CpCard::clock_front_end): MISO is
  // compared in the first cycle of each span, every other output in every cycle.
  static void compare(uint64_t cycle, const CardOut& want, const CardOut& got, bool first) {
    for (const auto& f : Card::fields()) {
      if (!first && std::string_view(f.name) == "spi_miso_o") continue;
      const uint64_t e = f.get(want), a = f.get(got);
      if (e != a) throw EngineMismatch(cycle, f.name, e, a);
    }
  }
  FastCardDut<Card> fast_;
  RtlDut<Card> rtl_;
};

}  // namespace cpstep::sim

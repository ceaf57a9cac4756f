// SPDX-License-Identifier: MIT
// Fuzz target: the machine file (host/plan/machine.h, parse_machine), then, when it
// is accepted, bind_card() against one of a few cards and gcode_options(). The
// first byte picks the card; the rest is the TOML text. Invariants: a refused
// file has errors; an accepted one has an axis, every present axis with finite
// positive steps/mm and limits, travel_min < travel_max and pulse times >= 0;
// bind_card either refuses (leaving the machine as it was) or binds to the card's
// clock with pulse cycles that cover the datasheet times and fit the card's fields.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "fuzz_util.h"
#include "plan/gcode.h"
#include "plan/machine.h"

using namespace cpstep;

namespace {

bool covers(std::uint32_t cycles, double ns, double clock_hz) {
  // cycles is ceil(ns * clock / 1e9), up to the rounding ns_to_cycles allows.
  const double need = ns * clock_hz / 1e9;
  return double(cycles) >= need - 1e-6 * std::max(1.0, need) && double(cycles) < need + 1.0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  const uint8_t pick = in.u8();
  const std::string_view text = in.rest();

  plan::Result<plan::Machine> r = plan::parse_machine(text, "fuzz.toml");
  if (!r.ok()) {
    FUZZ_CHECK(!r.errors.empty(), "refused without an error");
    return 0;
  }
  plan::Machine m = *r.value;
  bool any = false;
  for (const plan::AxisConfig& ax : m.axes) {
    if (!ax.present) continue;
    any = true;
    FUZZ_CHECK(std::isfinite(ax.steps_per_mm) && ax.steps_per_mm > 0, "steps_per_mm %g", ax.steps_per_mm);
    FUZZ_CHECK(std::isfinite(ax.travel_min_mm) && std::isfinite(ax.travel_max_mm) &&
                   ax.travel_min_mm < ax.travel_max_mm,
               "travel %g..%g", ax.travel_min_mm, ax.travel_max_mm);
    FUZZ_CHECK(ax.max_velocity > 0 && ax.max_accel > 0 && ax.max_jerk > 0, "limits");
    FUZZ_CHECK(std::isfinite(ax.max_velocity) && std::isfinite(ax.max_accel) && std::isfinite(ax.max_jerk),
               "limits not finite");
    const plan::PulseTimingNs& p = ax.pulse_ns;
    FUZZ_CHECK(p.step_high > 0 && p.step_low > 0 && p.dir_setup >= 0 && p.dir_hold >= 0, "pulse times");
  }
  FUZZ_CHECK(any, "accepted without an axis");

  static const plan::CardFacts cards[] = {
      {"icebreaker", 16.5e6, 1024, 8, 16},
      {"small", 48e6, 32, 3, 8},
      {"fast", 200e6, 65536, 16, 32},
  };
  const plan::CardFacts& card = cards[pick % std::size(cards)];
  const plan::Machine before = m;
  const std::vector<plan::Diagnostic> errors = plan::bind_card(m, card);
  if (!errors.empty()) {
    FUZZ_CHECK(!m.card.bound && m.card.clock_hz == before.card.clock_hz, "a refused bind changed the machine");
  } else {
    FUZZ_CHECK(m.card.bound && m.card.clock_hz == card.clock_hz, "bound to %g Hz", m.card.clock_hz);
    FUZZ_CHECK(m.card.pattern_capacity <= card.pattern_capacity && m.card.max_doubling <= card.max_doubling,
               "W %u KMAX %u above the card's", m.card.pattern_capacity, m.card.max_doubling);
    FUZZ_CHECK(m.chunk_tolerance_cycles() >= 1.0, "chunk tolerance %g cycles", m.chunk_tolerance_cycles());
    const double max_cycles = card.timing_bits >= 32 ? 4294967295.0 : double((1ull << card.timing_bits) - 1);
    for (const plan::AxisConfig& ax : m.axes) {
      if (!ax.present) continue;
      const std::uint32_t c[] = {ax.pulse.step_high, ax.pulse.step_low, ax.pulse.dir_setup, ax.pulse.dir_hold};
      const double ns[] = {ax.pulse_ns.step_high, ax.pulse_ns.step_low, ax.pulse_ns.dir_setup, ax.pulse_ns.dir_hold};
      for (int f = 0; f < 4; ++f) {
        FUZZ_CHECK(c[f] <= max_cycles, "pulse field %d: %u cycles", f, c[f]);
        FUZZ_CHECK(covers(c[f], ns[f], card.clock_hz), "pulse field %d: %u cycles for %g ns", f, c[f], ns[f]);
      }
      FUZZ_CHECK(std::isfinite(ax.max_step_rate_hz(card.clock_hz)), "step rate");
    }
  }
  const plan::GcodeOptions o = plan::gcode_options(m);
  FUZZ_CHECK(o.z_words == m.gcode.z_words, "z_words");
  return 0;
}

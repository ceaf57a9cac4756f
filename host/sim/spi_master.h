// SPDX-License-Identifier: MIT
// A pin-level SPI master (mode 0, MSB first) for the simulated card: it drives
// SCK, CS and MOSI of a card stepper cycle by cycle and samples MISO, so a byte
// vector goes out and the card's reply comes back exactly as on the wire
// (docs/PROTOCOL.md).
//
// Stepper: anything with `CardOut step(const CardIn&)` and `uint64_t cycle()`,
// e.g. RtlDut<CardDefault>. A stepper that can also advance many cycles at once
// with the pins held (`advance(in, cycles, on_span)`, calling on_span(first
// cycle, count, outputs) for each run of cycles whose outputs stay the same: the
// fast engine, fast_card.h) is advanced so wherever the master holds the pins,
// and the observer sees spans: set_span_observer(). One SCK period is sck_low + sck_high clock cycles
// (default 4 + 4: clk/8, the card's limit). MOSI changes in the first cycle SCK is
// low (or at CS fall for the first bit); MISO is sampled in the first cycle SCK is
// high, i.e. at the rising edge. An undriven MISO (miso_oe low) reads 1, like a
// pulled-up line with no card.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <stdexcept>
#include <vector>

#include "sim/card_port.h"

namespace cpstep::sim {

// `cycles` clocks with these pins (`pins`); MISO is sampled in the first if `sample`.
using SpiPhase = model::CpPinPhase;

struct SpiTiming {
  unsigned sck_low = 4;   // clock cycles SCK is low per bit
  unsigned sck_high = 4;  // clock cycles SCK is high per bit
  unsigned cs_setup = 4;  // CS fall (first MOSI bit set) to the first SCK rise
  unsigned cs_hold = 4;   // the last SCK fall to CS rise
  unsigned cs_idle = 4;   // CS high after the transfer, before the next one may start
};

template <class Stepper>
class SpiMaster {
 public:
  using Observer = std::function<void(uint64_t cycle, const CardIn&, const CardOut&)>;
  // `count` cycles from `cycle` on, with these pins and these outputs in each
  // (MISO excepted: a span inside a frame shows the MISO of its first cycle).
  using SpanObserver = std::function<void(uint64_t cycle, uint64_t count, const CardIn&, const CardOut&)>;

  explicit SpiMaster(Stepper& dut, SpiTiming timing = {}, Observer observe = nullptr)
      : dut_(dut), observe_(std::move(observe)) {
    set_timing(timing);
  }

  // Replaces the per-cycle observer with one that sees runs of identical cycles.
  void set_span_observer(SpanObserver s) {
    span_ = std::move(s);
    observe_ = nullptr;
  }

  // One clock with the given pins (E-stop and the inputs as last set).
  CardOut step(CardIn in) {
    slow_pins(in);
    const uint64_t c = dut_.cycle();
    last_ = dut_.step(in);
    if (observe_) observe_(c, in, last_);
    if (span_) span_(c, 1, in, last_);
    return last_;
  }
  void reset(unsigned cycles = 2) {
    CardIn in;
    in.rst = true;
    for (unsigned i = 0; i < cycles; ++i) step(in);
  }
  void idle(uint64_t cycles) { hold({}, cycles); }

  // One CS-low period: every byte of `mosi` out, as many bytes of MISO back.
  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) { return transfer_bits(mosi, 8 * mosi.size()); }

  // The first `bits` bits of `mosi` (MSB first), then CS rises: a cut frame.
  // Returns the MISO bits sampled, MSB first, the last byte padded with zeros.
  std::vector<uint8_t> transfer_bits(std::span<const uint8_t> mosi, size_t bits) {
    if (bits > 8 * mosi.size()) throw std::invalid_argument("SpiMaster: more bits than bytes given");
    auto bit = [&](size_t i) { return bool(mosi[i / 8] >> (7 - i % 8) & 1); };
    // The pins, phase by phase: CS falls with the first MOSI bit; each bit is an
    // SCK rise (MISO sampled in its first cycle) and, but for the last, a fall
    // with the next MOSI bit; CS hold, then CS high for the idle time.
    phases_.resize(bits > 0 ? 2 * bits + 2 : 3);
    SpiPhase* ph = phases_.data();
    CardIn in;
    slow_pins(in);
    in.cs_n = false;
    in.mosi = bits > 0 && bit(0);
    *ph++ = {in, t_.cs_setup, false};
    for (size_t i = 0; i < bits; ++i) {
      in.sck = true;
      *ph++ = {in, t_.sck_high, true};
      in.sck = false;
      if (i + 1 < bits) {
        in.mosi = bit(i + 1);
        *ph++ = {in, t_.sck_low, false};
      }
    }
    *ph++ = {in, t_.cs_hold, false};
    CardIn idle_pins;
    slow_pins(idle_pins);
    *ph++ = {idle_pins, t_.cs_idle, false};
    // A stepper that takes the whole schedule at once (the fast engine), else
    // phase by phase.
    sampled_.assign(phases_.size(), false);
    if constexpr (requires { dut_.run_phases(phases_, sampled_, [](uint64_t, uint64_t, const CardIn&, const CardOut&) {}); }) {
      dut_.run_phases(phases_, sampled_, [&](uint64_t c, uint64_t n, const CardIn& pins, const CardOut& out) {
        last_ = out;
        if (span_) span_(c, n, pins, out);
        if (observe_)
          for (uint64_t k = 0; k < n; ++k) observe_(c + k, pins, out);
      });
    } else {
      for (size_t p = 0; p < phases_.size(); ++p) {
        const CardOut o = hold(phases_[p].pins, phases_[p].cycles);
        sampled_[p] = !o.miso_oe || o.miso;
      }
    }
    std::vector<uint8_t> miso((bits + 7) / 8, 0);
    size_t i = 0;
    for (size_t p = 0; p < phases_.size(); ++p)
      if (phases_[p].sample) {
        if (sampled_[p]) miso[i / 8] |= uint8_t(0x80 >> (i % 8));
        ++i;
      }
    return miso;
  }

  void set_timing(const SpiTiming& t) {
    if (t.sck_low < 1 || t.sck_high < 1 || t.cs_setup < 1 || t.cs_idle < 1)
      throw std::invalid_argument("SpiMaster: every SCK phase, the CS setup and the CS idle time need a cycle");
    t_ = t;
  }
  const SpiTiming& timing() const { return t_; }
  void set_estop(bool on) { estop_ = on; }
  // The limit switches' pins (bit a: axis a) and the probe's, raw, from now on.
  void set_inputs(uint32_t lim_min, uint32_t lim_max, bool probe) {
    lim_min_ = lim_min;
    lim_max_ = lim_max;
    probe_ = probe;
  }
  const CardOut& last() const { return last_; }
  Stepper& dut() { return dut_; }

 private:
  // `cycles` clocks with the same pins (one advance() on a stepper that can);
  // returns the outputs of the first.
  CardOut hold(CardIn in, uint64_t cycles) {
    CardOut first{};
    if constexpr (requires { dut_.advance(in, cycles, [](uint64_t, uint64_t, const CardOut&) {}); }) {
      slow_pins(in);
      bool any = false;
      dut_.advance(in, cycles, [&](uint64_t c, uint64_t n, const CardOut& out) {
        if (!any) first = out;
        any = true;
        last_ = out;
        if (span_) span_(c, n, in, out);
        if (observe_)
          for (uint64_t i = 0; i < n; ++i) observe_(c + i, in, out);
      });
    } else {
      for (uint64_t i = 0; i < cycles; ++i) {
        const CardOut o = step(in);
        if (i == 0) first = o;
      }
    }
    return first;
  }

  Stepper& dut_;
  Observer observe_;
  SpanObserver span_;
  std::vector<SpiPhase> phases_;
  std::vector<uint8_t> sampled_;  // per phase: MISO (1 when undriven) in its first cycle
  SpiTiming t_;
  CardOut last_{};
  bool estop_ = false;
  uint32_t lim_min_ = 0, lim_max_ = 0;
  bool probe_ = false;
  // The pins the master holds across frames: the E-stop and the inputs.
  void slow_pins(CardIn& in) const {
    in.estop = estop_;
    in.lim_min = lim_min_;
    in.lim_max = lim_max_;
    in.probe = probe_;
  }
};

}  // namespace cpstep::sim

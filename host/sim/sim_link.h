// SPDX-License-Identifier: MIT
// The simulated card as a card::Link: frames go through the pin-level SPI
// master (spi_master.h), bit by bit on SCK/MOSI/MISO, and waiting clocks the card.
// Everything the card does meanwhile is seen by the master's observer, every
// clock cycle.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "card/link.h"
#include "sim/spi_master.h"

namespace cpstep::sim {

// SCK of `div` clock cycles per bit, split low/high (low gets the odd cycle);
// CS setup, hold and idle of 4 cycles (docs/PROTOCOL.md: SCK <= clk/8, 3 clk per
// level, setup 4, hold 2, idle 2).
inline SpiTiming spi_timing_for_divider(unsigned div) {
  if (div < 8) throw std::invalid_argument("the card needs SCK at clk/8 or slower (--sck-div 8 or more)");
  SpiTiming t;
  t.sck_high = div / 2;
  t.sck_low = div - t.sck_high;
  return t;
}

template <class Stepper>
class SimLink final : public card::Link {
 public:
  SimLink(SpiMaster<Stepper>& spi, double clock_hz) : spi_(spi), clock_hz_(clock_hz) {
    if (!(clock_hz > 0)) throw std::invalid_argument("SimLink: the clock must be positive");
  }

  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override {
    const uint64_t c0 = spi_.dut().cycle();
    std::vector<uint8_t> miso = spi_.transfer(mosi);
    busy_cycles_ += spi_.dut().cycle() - c0;
    return miso;
  }
  // Clocks the card with CS high for `seconds` (at least a cycle), never past the deadline.
  void wait(double seconds) override {
    uint64_t n = std::max<uint64_t>(1, uint64_t(std::ceil(seconds * clock_hz_)));
    const uint64_t now = spi_.dut().cycle();
    if (deadline_ > now) n = std::min(n, deadline_ - now);
    else if (deadline_ != kNoDeadline) n = 1;
    spi_.idle(n);
  }
  [[nodiscard]] double now_s() const override { return double(spi_.dut().cycle()) / clock_hz_; }
  [[nodiscard]] std::string name() const override { return "the simulated card"; }

  // wait() idles no further than this cycle (one cycle at a time past it).
  void set_deadline(uint64_t cycle) { deadline_ = cycle; }
  [[nodiscard]] uint64_t cycle() const { return spi_.dut().cycle(); }
  // Clock cycles spent in transfers (CS low, setup, hold and idle included).
  [[nodiscard]] uint64_t busy_cycles() const { return busy_cycles_; }
  SpiMaster<Stepper>& spi() { return spi_; }

 private:
  static constexpr uint64_t kNoDeadline = std::numeric_limits<uint64_t>::max();
  SpiMaster<Stepper>& spi_;
  double clock_hz_;
  uint64_t deadline_ = kNoDeadline;
  uint64_t busy_cycles_ = 0;
};

}  // namespace cpstep::sim

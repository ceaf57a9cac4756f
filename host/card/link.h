// SPDX-License-Identifier: MIT
// A byte link to the card: one call is one CS-low period of SPI (docs/PROTOCOL.md).
// The frame-level host code (card_client.h) runs over any Link: the simulated
// card's pins (host/sim/sim_link.h), a Linux spidev device (spidev.h), or a test
// double that damages bytes in flight.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace cpstep::card {

// A link that cannot do what it was asked (device missing, ioctl refused, ...).
class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Link {
 public:
  virtual ~Link() = default;

  // One CS-low period: every byte of `mosi` out, as many bytes of MISO back.
  virtual std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) = 0;
  // Lets `seconds` pass with CS high: the simulated card is clocked that long, a
  // real link sleeps. The card keeps running meanwhile.
  virtual void wait(double seconds) = 0;
  // Seconds on the link's clock since it was opened (the card clock on a sim).
  [[nodiscard]] virtual double now_s() const = 0;
  // What the link is, for messages: "sim", "/dev/spidev0.0".
  [[nodiscard]] virtual std::string name() const = 0;
};

}  // namespace cpstep::card

// SPDX-License-Identifier: MIT
// A card on a Linux spidev device (/dev/spidevB.C): SPI mode 0, 8-bit words,
// MSB first, at a given SCK rate; one full-duplex SPI_IOC_MESSAGE per frame.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "card/link.h"

namespace cpstep::card {

// spidev's default transfer limit (module parameter bufsiz): frames are kept
// below it.
constexpr size_t kSpidevMaxTransfer = 4096;

class SpidevLink final : public Link {
 public:
  // Opens the device and sets mode 0, 8 bits per word, MSB first and `speed_hz`.
  // Throws LinkError naming the device: it is missing (ENOENT), not permitted
  // (EACCES), or not an SPI device (an ioctl refused, e.g. ENOTTY on a plain
  // file). Nothing is sent.
  SpidevLink(std::string device, uint32_t speed_hz);
  ~SpidevLink() override;
  SpidevLink(const SpidevLink&) = delete;
  SpidevLink& operator=(const SpidevLink&) = delete;

  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override;
  void wait(double seconds) override;
  [[nodiscard]] double now_s() const override;
  [[nodiscard]] std::string name() const override { return device_; }
  [[nodiscard]] uint32_t speed_hz() const { return speed_hz_; }

 private:
  std::string device_;
  uint32_t speed_hz_;
  int fd_ = -1;
  std::chrono::steady_clock::time_point opened_;
};

}  // namespace cpstep::card

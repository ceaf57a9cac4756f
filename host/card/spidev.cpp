// SPDX-License-Identifier: MIT
#include "card/spidev.h"

#include <fcntl.h>
#include <linux/spi/spidev.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>

namespace cpstep::card {

namespace {

std::string errno_text(int e) { return std::string(std::strerror(e)) + " (errno " + std::to_string(e) + ")"; }

}  // namespace

SpidevLink::SpidevLink(std::string device, uint32_t speed_hz)
    : device_(std::move(device)), speed_hz_(speed_hz), opened_(std::chrono::steady_clock::now()) {
  if (speed_hz_ == 0) throw LinkError(device_ + ": the SPI clock must be at least 1 Hz");
  fd_ = ::open(device_.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    std::string hint;
    if (e == ENOENT)
      hint = ": no such device (is SPI enabled? on a Raspberry Pi: dtparam=spi=on in /boot/config.txt, "
             "then /dev/spidev0.0 is SPI0 with CE0)";
    else if (e == EACCES)
      hint = ": permission denied (add the user to group spi, or run as root)";
    throw LinkError("cannot open " + device_ + ": " + errno_text(e) + hint);
  }
  const auto set = [&](unsigned long request, const void* value, const char* what) {
    if (::ioctl(fd_, request, value) < 0) {
      const int e = errno;
      ::close(fd_);
      fd_ = -1;
      throw LinkError(device_ + ": cannot set " + what + ": " + errno_text(e) +
                      (e == ENOTTY || e == EINVAL ? " (not an spidev device?)" : ""));
    }
  };
  const uint8_t mode = SPI_MODE_0, bits = 8, lsb_first = 0;
  set(SPI_IOC_WR_MODE, &mode, "SPI mode 0 (SPI_IOC_WR_MODE)");
  set(SPI_IOC_WR_BITS_PER_WORD, &bits, "8 bits per word (SPI_IOC_WR_BITS_PER_WORD)");
  set(SPI_IOC_WR_LSB_FIRST, &lsb_first, "MSB first (SPI_IOC_WR_LSB_FIRST)");
  set(SPI_IOC_WR_MAX_SPEED_HZ, &speed_hz_, "the SPI clock (SPI_IOC_WR_MAX_SPEED_HZ)");
}

SpidevLink::~SpidevLink() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<uint8_t> SpidevLink::transfer(std::span<const uint8_t> mosi) {
  std::vector<uint8_t> miso(mosi.size(), 0);
  if (mosi.empty()) return miso;
  if (mosi.size() > kSpidevMaxTransfer)
    throw LinkError(device_ + ": a transfer of " + std::to_string(mosi.size()) + " bytes exceeds spidev's " +
                    std::to_string(kSpidevMaxTransfer) + "-byte limit (module parameter bufsiz)");
  spi_ioc_transfer t;
  std::memset(&t, 0, sizeof t);
  t.tx_buf = reinterpret_cast<uintptr_t>(mosi.data());
  t.rx_buf = reinterpret_cast<uintptr_t>(miso.data());
  t.len = uint32_t(mosi.size());
  t.speed_hz = speed_hz_;
  t.bits_per_word = 8;
  if (::ioctl(fd_, SPI_IOC_MESSAGE(1), &t) < 0)
    throw LinkError(device_ + ": SPI transfer of " + std::to_string(mosi.size()) +
                    " bytes failed (SPI_IOC_MESSAGE): " + errno_text(errno));
  return miso;
}

void SpidevLink::wait(double seconds) {
  if (seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}

double SpidevLink::now_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - opened_).count();
}

}  // namespace cpstep::card

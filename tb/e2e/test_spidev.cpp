// SPDX-License-Identifier: MIT
// The spidev link's refusals, on what this machine has: a device path that does
// not exist, a plain file and /dev/null in its place (the SPI ioctls fail), and
// a file without permission. Each is a LinkError naming the path, and nothing is
// written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "card/spidev.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

std::string error_of(const std::string& device) {
  try {
    card::SpidevLink link(device, 6'000'000);
  } catch (const card::LinkError& e) {
    return e.what();
  }
  return "";
}

bool starts_with(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

TEST(Spidev, AMissingDeviceIsNamedWithTheHint) {
  const std::string e = error_of("/dev/spidev9.9-not-here");
  EXPECT_TRUE(starts_with(e, "cannot open /dev/spidev9.9-not-here: No such file or directory (errno 2): no such "
                             "device (is SPI enabled?"))
      << e;
}

TEST(Spidev, APlainFileIsNotAnSpiDeviceAndStaysUntouched) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "spidev";
  fs::create_directories(dir);
  const fs::path file = dir / "not_a_device";
  std::ofstream(file, std::ios::trunc) << "unchanged";
  const std::string e = error_of(file.string());
  EXPECT_EQ(e, file.string() + ": cannot set SPI mode 0 (SPI_IOC_WR_MODE): Inappropriate ioctl for device "
                               "(errno 25) (not an spidev device?)");
  std::ifstream in(file);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "unchanged");
  EXPECT_EQ(fs::file_size(file), 9u);
}

TEST(Spidev, DevNullRefusesTheSpiIoctls) {
  const std::string e = error_of("/dev/null");
  EXPECT_TRUE(starts_with(e, "/dev/null: cannot set SPI mode 0 (SPI_IOC_WR_MODE): ")) << e;
}

TEST(Spidev, NoPermissionIsNamedWithTheHint) {
  if (::geteuid() == 0) GTEST_SKIP() << "root opens any file";
  const fs::path file = fs::path(CPSTEP_TEST_DIR) / "spidev" / "no_permission";
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::trunc).close();
  fs::permissions(file, fs::perms::none);
  const std::string e = error_of(file.string());
  EXPECT_TRUE(starts_with(e, "cannot open " + file.string() + ": Permission denied (errno 13): permission denied "
                                                              "(add the user to group spi"))
      << e;
  fs::permissions(file, fs::perms::owner_all);
}

TEST(Spidev, AZeroClockIsRefusedBeforeOpening) {
  try {
    card::SpidevLink link("/dev/null", 0);
    ADD_FAILURE();
  } catch (const card::LinkError& e) {
    EXPECT_EQ(std::string(e.what()), "/dev/null: the SPI clock must be at least 1 Hz");
  }
}

}  // namespace
}  // namespace cpstep::tb

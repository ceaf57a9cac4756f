// SPDX-License-Identifier: MIT
// `cpstep conic`: one arc (or any conic) through the combined-step conic engine
// (docs/CONIC.md), on the Verilated RTL, the model or the geometric oracle.
#pragma once

#include <array>
#include <optional>
#include <string>

namespace cpstep::cli {

struct ConicOptions {
  std::array<double, 2> from{}, to{};
  std::optional<std::array<double, 2>> center;  // circle form
  std::optional<std::array<double, 6>> coeffs;  // general form A B C D E F
  bool ccw = false;
  std::string engine = "rtl";
  bool json = false;
};

// Exit codes as the other subcommands: 0 done, 2 refused (one line on stderr).
int run_conic(const ConicOptions& o);

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// `cpstep conic`: one arc (or any conic) through the combined-step conic engine
// (docs/CONIC.md), on the Verilated RTL, the model or the geometric oracle.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

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

// The moves the Verilated conic engine (rtl/cp_conic.v, default widths) makes for the
// conic A..F (integers) from node `start` to node `end` (a full turn when equal),
// clockwise or not; `err` is its refusal code (model::ConicError), 0 when it ran.
struct ConicRun {
  std::vector<std::pair<int, int>> moves;
  uint32_t err = 0;
};
ConicRun conic_rtl_moves(const std::array<int64_t, 6>& k, std::array<int64_t, 2> start, std::array<int64_t, 2> end,
                         bool cw);

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// `cpstep interp`: every NURBS block (G5, G5.1, G5.2..G5.3) of a job
// interpolated at a fixed period along one S-curve over its length, with the
// three parameter updates of seed 002, and measured: worst relative feed
// fluctuation and worst chord error (docs/CURVES.md). Needs no card.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct InterpCliOptions {
  std::string job, machine, method, ngc;
  double period_ms = 1.0;
  bool json = false;
};

CLI::App* add_interp_command(CLI::App& app, InterpCliOptions& options);

// Exit codes: 0 measured; 2 refused input (the job or the machine, a job
// without NURBS blocks; one line each on stderr).
int run_interp(const InterpCliOptions& options);

}  // namespace cpstep::cli

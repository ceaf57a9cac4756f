// SPDX-License-Identifier: MIT
// `cpstep check`: a STEP/DIR trace (VCD) of any device held against cpstep's
// plan of the same job, with a JSON verdict (docs/VALIDATING.md, section 4).
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct CheckOptions {
  std::string vcd, job, machine, map, json;
  std::string board;  // the card build the plan is made for ("": the default board)
  std::optional<double> time_tol_cycles, skew_cycles;
};

CLI::App* add_check_command(CLI::App& app, CheckOptions& options);

// Exit codes: 0 the trace conforms; 1 it does not (findings); 2 bad input
// (the VCD, the map, the job or the machine refused; one line each on stderr).
int run_check(const CheckOptions& options);

}  // namespace cpstep::cli

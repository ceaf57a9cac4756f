// SPDX-License-Identifier: MIT
// cpstep built without the RTL (CPSTEP_WITH_RTL=OFF): the subcommands that need
// no simulated card.
//
//   cpstep check --vcd TRACE.vcd --job JOB.ngc --machine M.toml [--map PINS.toml] [--json OUT.json]
//
// Exit codes as the full program's (host/cli/main.cpp): 0 success, 1 findings,
// 2 refused input.
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <exception>

#include "cli/check_command.h"

int main(int argc, char** argv) {
  constexpr int kExitRefused = 2;
  CLI::App app{"cpstep (built without the RTL): check a STEP/DIR trace against cpstep's plan"};
  app.require_subcommand(1);
  cpstep::cli::CheckOptions co;
  auto* chkc = cpstep::cli::add_check_command(app, co);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : kExitRefused;
  }
  try {
    if (*chkc) return cpstep::cli::run_check(co);
  } catch (const std::exception& e) {
    fmt::print(stderr, "cpstep: internal error: {}\n", e.what());
    return 1;
  }
  return 0;
}

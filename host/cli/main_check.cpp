// SPDX-License-Identifier: MIT
// cpstep built without the RTL (CPSTEP_WITH_RTL=OFF): the subcommands that need
// no simulated card.
//
//   cpstep check --vcd TRACE.vcd --job JOB.ngc --machine M.toml [--map PINS.toml] [--json OUT.json]
//   cpstep interp JOB.ngc --machine M.toml [--method taylor1|taylor2|milne] [--period-ms T] [--json]
//   cpstep cam PART.dxf... --sheet SHEET.toml [-o JOB.ngc] [--svg PREVIEW.svg]   (no --run)
//
// Exit codes as the full program's (host/cli/main.cpp): 0 success, 1 findings,
// 2 refused input.
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <exception>

#include "cli/cam_command.h"
#include "cli/check_command.h"
#include "cli/interp_command.h"

int main(int argc, char** argv) {
  constexpr int kExitRefused = 2;
  CLI::App app{"cpstep (built without the RTL): check a STEP/DIR trace against cpstep's plan"};
  app.require_subcommand(1);
  cpstep::cli::CheckOptions co;
  auto* chkc = cpstep::cli::add_check_command(app, co);
  cpstep::cli::InterpCliOptions io;
  auto* intc = cpstep::cli::add_interp_command(app, io);
  cpstep::cli::CamOptions camo;  // `cam` without --run (no simulated card here)
  auto* camc = cpstep::cli::add_cam_command(app, camo);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : kExitRefused;
  }
  try {
    if (*chkc) return cpstep::cli::run_check(co);
    if (*intc) return cpstep::cli::run_interp(io);
    if (*camc) return cpstep::cli::run_cam(camo);
  } catch (const std::exception& e) {
    fmt::print(stderr, "cpstep: internal error: {}\n", e.what());
    return 1;
  }
  return 0;
}

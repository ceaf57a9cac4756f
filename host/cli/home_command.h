// SPDX-License-Identifier: MIT
// `cpstep home`: the machine's homing cycle (docs/HOST.md "Homing") on the simulated
// card, its switches placed where the machine file's home.sim_switch_mm says; the
// trips, offsets and final positions printed (or --json).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct HomeOptions {
  std::string machine, board, engine = "model";
  bool json = false;
};

CLI::App* add_home_command(CLI::App& app, HomeOptions& options);

// Exit codes: 0 every axis homed and the pins agree with the card's counters;
// 1 homing failed (a switch not found, a card fault, pins and counters apart);
// 2 refused input (the machine file, a board without inputs; nothing ran).
int run_home(const HomeOptions& options);

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// `cpstep sim`: runs a script of raw segments and commands (docs/SIM.md) on the
// Verilated card, through its SPI pins, and reports its final state.
#pragma once

#include <cstdint>
#include <string>

namespace cpstep::cli {

struct SimOptions {
  std::string file;
  std::string vcd;                      // "" for no waveform
  uint64_t max_cycles = 100'000'000;    // clock cycles, reset included
  std::string board;                    // rtl/builds.json's board; "": the default board
  uint64_t clock_hz = 0;                // 0: the board's; otherwise it must be the board's
  unsigned sck_div = 8;                 // clock cycles per SCK period (8 or more)
  std::string engine = "rtl";           // rtl (the Verilated card) or model (the fast engine)
};

// Exit codes: 0 the run ended without a fault; 1 it ended with a fault, or did
// not end within max_cycles; 2 the script or an option was refused (nothing sent).
int run_sim(const SimOptions& options);

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// `cpstep run` and `cpstep plan`: a G-code job planned for the card, then run
// on a transport (the simulated card through its SPI pins, a card on a Linux
// spidev device, or a file of command words), with a summary, a JSON report, a
// pin VCD and plots (docs/HOST.md).
#pragma once

#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct RunOptions {
  std::string job, machine;
  std::string transport = "sim";   // sim | spidev | file
  std::string board;               // sim: the board simulated; file: the board planned for ("": default)
  std::string engine = "model";    // sim: model (fast), rtl (Verilated) or lockstep (both, compared)
  std::string fst;                 // sim, rtl engine: an FST waveform of every RTL signal
  std::string out;                 // file transport: the command stream
  std::string vcd, report, plots;  // sim transport: optional outputs (spidev: the report)
  uint64_t max_cycles = 0;         // 0: twice the planned time plus 10^7 cycles
  unsigned sck_div = 8;            // sim: clock cycles per SCK period
  std::string device;              // spidev: the device ("": /dev/spidev0.0)
  uint64_t spi_hz = 0;             // spidev: SCK rate; 0: the card's clock / 8
  bool no_progress = false;
  bool klipper = false;  // --klipper: Klipper's queue_step bytes beside the card's (RunMeter)
  bool ack_estop = false;  // spidev: acknowledge an E-stop the card latched (its input released)
  double watchdog_s = 0.1;  // sim, spidev: the card's watchdog while the job runs (0: off)
  // Feed (cards with FEED, docs/CORE.md "Feed hold and override"): the override from
  // the start, and sim events "T:hold,T:resume,T:override=P" (seconds from START).
  double override_pct = 100;
  std::string feed;
  // A cut job by contours (docs/PLASMA.md "Resume"): sim and spidev.
  std::string state;               // write the run's state here (contours completed, position)
  std::string resume;              // continue the run this state file records
  size_t stop_after_contours = 0;  // sim: end the run after this contour; 0: at the job's end
};

struct PlanOptions {
  std::string job, machine, out;
  std::string board;               // the board planned for ("": the default board)
};

// Registers the subcommands on `app`; the options are filled when they parse.
CLI::App* add_run_command(CLI::App& app, RunOptions& options);
CLI::App* add_plan_command(CLI::App& app, PlanOptions& options);

// Exit codes: 0 success; 1 the card faulted or a check against the plan failed
// (or an output could not be written); 2 the job, the machine or an option was
// refused: nothing was sent and no output written.
int run_job(const RunOptions& options);
int plan_only(const PlanOptions& options);

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// A small VCD (IEEE 1364 value change dump) writer: named signals in one scope,
// values written only when they change. Used by `cpstep sim --vcd` to give each
// pin its own name (Verilator's tracer names signals by the RTL hierarchy).
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace cpstep::sim {

class VcdWriter {
 public:
  // timescale: a VCD time unit such as "1ps"; scope: the module name shown.
  VcdWriter(std::ostream& out, std::string timescale, std::string scope);

  // Declares a signal of 1..64 bits (before the first sample); returns its handle.
  int add_signal(const std::string& name, unsigned width = 1);
  // Sets a signal's value for the next sample.
  void set(int signal, uint64_t value);
  // Records every signal at `time` (non-decreasing): the first call writes the
  // header and every value, later calls only the values that changed.
  void sample(uint64_t time);

 private:
  struct Signal {
    std::string name, code;
    unsigned width;
    uint64_t value = 0, written = 0;
  };
  void write_value(const Signal& s);

  std::ostream& out_;
  std::string timescale_, scope_;
  std::vector<Signal> signals_;
  bool started_ = false;
  uint64_t last_time_ = 0;
};

// Start of clock cycle `cycle` at `clock_hz` in picoseconds, rounded to the
// nearest: the time axis of the pin VCDs (timescale 1ps).
uint64_t cycle_start_ps(uint64_t cycle, uint64_t clock_hz);

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// The text format of `cpstep sim` (docs/SIM.md): raw segments, chunks and
// commands for the card, one per line. Parsing checks syntax and field widths
// only; values the card refuses (v > U, interval 0, ...) pass through unchanged.
#pragma once

#include <cstdint>
#include <istream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace cpstep::sim {

// Command words to send (a segment with its chunks, a CONFIG, a CONTROL).
struct SendWords {
  std::vector<uint32_t> words;
};
// Idle for this many clock cycles.
struct Wait {
  uint64_t cycles = 0;
};
// Idle until the card is not running.
struct RunToStop {};
// Set the E-stop input.
struct Estop {
  bool on = false;
};
// Set the limit switch and probe pins (raw levels; bit a: axis a).
struct Inputs {
  uint32_t lim_min = 0, lim_max = 0;
  bool probe = false;
};
// An URGENT frame (docs/PROTOCOL.md "Out of band"): card::urgent bits.
struct Urgent {
  uint32_t word = 0;
};

struct ScriptStep {
  unsigned line = 0;  // 1-based line of the script it came from
  std::variant<SendWords, Wait, RunToStop, Estop, Urgent, Inputs> action;
};

// A syntax error: "<file>:<line>:<column>: error: <message>" in what().
class ScriptError : public std::runtime_error {
 public:
  ScriptError(const std::string& file, unsigned line, unsigned column, const std::string& message);
  unsigned line, column;
};

// Axis names of the default card, in axis order.
inline constexpr const char* kSimAxisNames[] = {"x", "y", "z", "a"};
inline constexpr unsigned kSimAxes = 4;

// Parses a whole script; `file` names it in errors. Throws ScriptError.
std::vector<ScriptStep> parse_sim_script(std::istream& in, const std::string& file);

}  // namespace cpstep::sim

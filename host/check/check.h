// SPDX-License-Identifier: MIT
// `cpstep check`: a STEP/DIR trace of any device held against cpstep's own
// plan of the same job (docs/VALIDATING.md, section 4).
//
// The trace's pins become leading STEP edges (each ±1 by the DIR level at
// that edge), pulse widths and DIR changes (read_pins). Leading edges are
// grouped into move events (every move steps its major axis, so each event
// has at least one edge): an event starts at the earliest edge not yet taken
// and takes every edge of another axis that follows it within the skew window.
// Move event k is then held against planned move k, in order (check_trace).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "check/pin_map.h"
#include "check/vcd.h"
#include "plan/common.h"
#include "run/card_job.h"

namespace cpstep::check {

// One axis's pins in the trace, times in card clock cycles from the trace's
// time 0 (the machine's clock_hz).
struct AxisPinTrace {
  bool present = false;                // both signals found
  std::string step_name, dir_name;     // the signals' full paths
  bool step_active_high = true, dir_positive_high = true;
  std::vector<double> leading;         // leading STEP edges (into the active level)
  std::vector<double> trailing;        // the trailing edge after each; NaN if the trace ends first
  std::vector<int8_t> dir;             // at each leading edge: +1, -1, or 0 (DIR unknown: x/z)
  std::vector<double> dir_changes;     // every time the DIR pin flipped between 0 and 1
};

struct PinTrace {
  std::string file;
  plan::PerAxis<AxisPinTrace> axes;
  double unit_s = 0;                   // one trace time unit
  double resolution_cycles = 0;        // what one time step of the trace can hide
  double end_cycles = 0;               // the trace's last time
  // The torch pin (a signal named `torch`, docs/CORE.md "Torch"), when the trace
  // has one: every change of its level, in cycles (it starts off).
  bool torch_present = false;
  std::string torch_name;
  std::vector<double> torch_changes;
};

// Finds each axis's pins by the map (default: step_<axis>, dir_<axis>) and
// extracts its edges. An axis the plan moves needs both pins; other axes are
// read when their pins are there. Errors: a signal the map names (or a moving
// axis needs) that is not in the trace, a name several signals match, a pin
// wider than one bit.
plan::Result<PinTrace> read_pins(const VcdTrace& vcd, const PinMap& map, const run::CardJob& job);

struct CheckOptions {
  std::optional<double> time_tol_cycles;  // default kDefaultTimeTolCycles
  std::optional<double> skew_cycles;      // default: a quarter of the shortest planned interval
};
inline constexpr double kDefaultTimeTolCycles = 3;

enum class FindingKind {
  move_count,   // move events in the trace != planned moves
  endpoint,     // an axis off the plan's position when a segment's planned move count is reached
  deviation,    // an axis farther from the planned line than cpstep's own string goes
  move_string,  // the axes stepping at a move differ from cpstep's string
  direction,    // a step whose DIR is opposite to the segment's planned direction
  timing,       // a move event farther from its planned time than the tolerance
  step_high,    // a STEP pulse shorter than the driver's step high time
  step_low,     // a STEP space (trailing to next leading edge) shorter than the step low time
  dir_setup,    // a DIR change closer before a leading edge than the DIR setup time
  dir_hold,     // a DIR change closer after a leading edge than the DIR hold time
  torch,        // the torch pin switched other than at its planned move boundary
};
const char* finding_name(FindingKind k);

// One finding, aggregated per kind, card segment and axis: `count` occurrences,
// the first of them named by move and time, the worst by `actual`.
struct Finding {
  FindingKind kind{};
  size_t segment = 0;         // 1-based planned card segment; 0: none (after the plan, or global)
  int line = 0;               // its G-code line
  int axis = -1;              // axis index, -1: none
  uint64_t move = 0;          // 1-based move event of the first occurrence (0: none)
  uint64_t segment_move = 0;  // the same, counted within its segment
  double cycle = -1;          // trace time of the first occurrence, card cycles (-1: none)
  uint64_t count = 1;
  double expected = 0, actual = 0;  // kind-specific (below); `actual` is the worst occurrence
  std::string message;
};
// expected/actual: move_count, endpoint: moves/steps; deviation: limit and worst
// |deviation| in steps; move_string: 0/0 (the message names the axes); direction:
// the planned sign and the step's; timing: tolerance and worst deviation in cycles
// (signed, + late); step_high ... dir_hold: minimum and worst measured time in ns.

struct AxisSummary {
  bool present = false;
  std::string step_name, dir_name;
  bool step_active_high = true, dir_positive_high = true;
  uint64_t pulses = 0;
  int64_t final_position = 0, planned_final = 0;
  double max_deviation = 0;    // steps, from the planned lines
  double deviation_limit = 0;  // the largest limit of its segments
  double min_high_ns = -1, min_low_ns = -1, min_setup_ns = -1, min_hold_ns = -1;  // -1: none seen
  bool driver = false;         // the machine has this axis: `required` holds its driver's minimums
  plan::PulseTimingNs required;
};

struct Verdict {
  std::string trace, job, machine, map;
  double clock_hz = 0, unit_s = 0, resolution_cycles = 0;
  double skew_cycles = 0, time_tol_cycles = 0;
  size_t segments = 0;
  uint64_t planned_moves = 0, move_events = 0;
  size_t segments_on_endpoint = 0, segments_bit_exact = 0;
  double time_offset_cycles = 0;  // trace time of START implied by the moves (median)
  double max_early_cycles = 0, max_late_cycles = 0;
  uint64_t max_early_move = 0, max_late_move = 0, moves_off_time = 0;
  plan::PerAxis<AxisSummary> axes;
  // The torch pin against the plan's switches (run::check_torch), when the trace has one.
  bool torch_checked = false;
  uint64_t torch_planned = 0, torch_edges = 0;
  double torch_max_delay_cycles = 0;
  std::vector<Finding> findings;
  std::vector<std::string> warnings;  // the planner's

  [[nodiscard]] bool conforms() const { return findings.empty(); }
};

Verdict check_trace(const run::CardJob& job, const PinTrace& trace, const CheckOptions& options = {});

// The verdict as JSON (docs/VALIDATING.md lists the fields) and as the short
// summary `cpstep check` prints; at most `listed` findings are spelled out.
nlohmann::ordered_json verdict_json(const Verdict& v);
std::string verdict_summary(const Verdict& v, size_t listed = 10);

}  // namespace cpstep::check

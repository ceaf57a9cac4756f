// SPDX-License-Identifier: MIT
// Which trace signals are which axis's STEP and DIR, their polarity, and the
// trace's time base: cpstep's own names by default (`cpstep run --vcd` writes
// step_<axis> and dir_<axis>, polarity as the machine file says), or a map
// file (TOML) for another device's capture:
//
//   timescale = "20.833 ns"     # optional: one trace time unit (overrides $timescale)
//   clock_hz = 48_000_000       # optional, instead: one trace time unit is a cycle of this clock
//   sample_hz = 24_000_000      # optional: the capture's sample rate (its time resolution)
//
//   [axes.x]
//   step = "D0"                 # signal name: its last hierarchical component or its full path
//   dir = "D1"
//   step_active_high = false    # optional: the machine file's polarity otherwise
//   dir_positive_high = true
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "plan/common.h"

namespace cpstep::check {

struct AxisPins {
  std::string step, dir;                       // signal names
  std::optional<bool> step_active_high;        // unset: the machine file's
  std::optional<bool> dir_positive_high;
  plan::SourceLoc step_loc, dir_loc;           // where the map names them (line 0: default)
};

struct PinMap {
  std::string file;                            // empty: the default names
  plan::PerAxis<AxisPins> axes;
  std::optional<double> unit_s;                // one trace time unit, seconds
  std::optional<double> sample_s;              // the trace's time resolution, seconds
};

// step_<axis> / dir_<axis> for every axis letter, no overrides.
PinMap default_pin_map();

// A map file held in memory (`file` names it in errors), or read from disk.
// Every problem is reported with its line, column and field; axes the map does
// not name keep the default names.
plan::Result<PinMap> parse_pin_map(std::string_view text, std::string_view file);
plan::Result<PinMap> load_pin_map(const std::filesystem::path& path);

}  // namespace cpstep::check

// SPDX-License-Identifier: MIT
// The state a run of `cpstep run --state FILE` leaves behind, and that `cpstep
// run --resume FILE` continues from (docs/PLASMA.md "Resume"): which job, how
// many of its contours the card completed, and where the machine stopped. A
// small JSON file, written atomically (a temporary file renamed over it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "plan/common.h"

namespace cpstep::run {

// How a run ended.
enum class RunEnd {
  finished,  // the whole job ran, no fault: nothing is left to resume
  stopped,   // --stop-after-contours ended it, no fault
  fault,     // the card or a host check faulted (or nothing could be sent)
};
const char* run_end_name(RunEnd e);

struct RunState {
  static constexpr int kVersion = 1;
  std::string job;                       // the G-code file, as given
  std::string job_fnv1a64;               // FNV-1a 64 of its bytes, 16 lowercase hex digits
  std::string machine;                   // the machine file, as given
  plan::PerAxis<bool> axes{};            // the machine's axes (the keys of the per-axis objects)
  plan::PerAxis<double> steps_per_mm{};  // the machine's, per axis
  uint64_t contours = 0;                 // contours in the job
  uint64_t contours_completed = 0;       // contours whose every move the card made, from the job's start
  int last_m5_line = 0;                  // the M5 line of the last completed contour; 0 when none is
  plan::PerAxis<int64_t> job_start{};    // steps where the job's first run began (G91 jobs depend on it)
  plan::PerAxis<int64_t> position{};     // steps where the machine stopped (the card's counters)
  RunEnd ended = RunEnd::fault;

  // position in mm (steps / steps_per_mm; 0 on absent axes).
  [[nodiscard]] plan::PerAxis<double> position_mm() const;
};

// FNV-1a 64 of `bytes`, as 16 lowercase hex digits.
std::string fnv1a64_hex(std::string_view bytes);

// The file's bytes; nullopt when it cannot be read.
std::optional<std::string> read_bytes(const std::filesystem::path& path);

// The state as JSON text.
std::string state_text(const RunState& state);
// A state from JSON text; every error names `file` and the field.
plan::Result<RunState> parse_state(std::string_view text, const std::string& file);
// read_bytes() and parse_state().
plan::Result<RunState> read_state(const std::filesystem::path& path);
// Writes the state to `path` through a temporary file in its directory, synced
// and renamed over it, so a reader sees the old state or the new one, whole.
// Returns "" or why it failed.
std::string write_state(const std::filesystem::path& path, const RunState& state);

}  // namespace cpstep::run

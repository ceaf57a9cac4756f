// SPDX-License-Identifier: MIT
// The torch output (docs/CORE.md "Torch"): where a planned job switches it, and
// a trace's torch pin held against that. Each wire segment carries the torch's
// level while it runs (H0[16]); the card's pin takes a segment's level in the
// cycle after the last move event of the segment before (the cycle that
// segment's last STEP edge shows on its pin), or, when the segment was not yet
// built then, when it loads: never after its own first move. It is off before
// START, and from the cycle after the last move of the run.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "plan/common.h"
#include "run/card_job.h"

namespace cpstep::run {

// One change of the torch pin the plan makes, in card cycles from START (the
// cycle the pin shows it): at `earliest` when the segment is built in time,
// at `latest` at the last.
struct TorchSwitch {
  size_t segment = 0;      // the wire segment that brings the new level (== size(): the run's end)
  bool on = false;
  uint64_t earliest = 0, latest = 0;
  plan::SourceLoc loc;     // its G-code block
};
std::vector<TorchSwitch> torch_switches(const CardJob& job);

// A change of a trace's torch pin, in card cycles from START.
struct TorchEdge {
  double cycle = 0;
  bool on = false;
};

struct TorchVerdict {
  uint64_t planned = 0, edges = 0;
  double max_delay_cycles = 0;            // the latest edge after its `earliest`
  std::optional<double> min_pierce_cycles;  // the shortest time from a torch-on edge to the next move event
  double on_cycles = 0;                   // time the torch was on
  std::vector<std::string> errors;        // at most `listed`, then a count
  [[nodiscard]] bool ok() const { return errors.empty(); }
};

// The edges against the plan's switches: as many, each the right way and within
// [earliest - tol, latest + tol]. `moves` are the trace's move events (cycles
// from START, increasing) for the pierce figure.
TorchVerdict check_torch(const CardJob& job, const std::vector<TorchEdge>& edges, const std::vector<double>& moves,
                         double tol_cycles, size_t listed = 5);

}  // namespace cpstep::run

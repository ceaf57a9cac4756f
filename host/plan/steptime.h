// SPDX-License-Identifier: MIT
// Ideal times of move events: move i (1..T) of a segment happens when the
// path reaches i/T of the segment's length.
#pragma once

#include <cstdint>
#include <vector>

#include "plan/planner.h"

namespace cpstep::plan {

// Absolute ideal times, in card clock cycles from the job start, of moves
// first+1 .. first+count of a segment of `total_moves` moves.
std::vector<double> ideal_move_times(const PlannedSegment& seg, std::uint64_t total_moves,
                                     std::uint64_t first, std::uint64_t count, double clock_hz);

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// Card segments: GCD reduction of each axis's pattern against the major axis
// and, where a reduced pattern exceeds the card's capacity W, a split into
// sub-segments whose ends are lattice points close to the ideal line.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "plan/common.h"

namespace cpstep::plan {

struct CardSegment {
    int major = 0;                       // first axis of max |delta|
    std::uint32_t moves = 0;             // T: moves of this (sub-)segment
    PerAxis<bool> dir_positive{};        // true for delta >= 0
    PerAxis<std::uint32_t> u{};          // reduced pattern length; 1 on the major axis
    PerAxis<std::uint32_t> v{};          // reduced step count; 1 on the major axis
    PerAxis<std::int64_t> delta{};       // signed steps of this sub-segment (= moves*v/u)
    std::uint32_t first_move = 0;        // offset of its first move in the parent segment
    SourceLoc loc;
    std::size_t step_segment = 0;        // index of the parent step segment
    // Moves that step no axis (every v = 0): a pause the card times, for a dwell
    // longer than one move interval can be (2^32 - 1 cycles) or after the last
    // move (docs/PLANNING.md "Dwells"). Not counted in the job's moves: the pins
    // never show them.
    bool pause = false;
};

struct SplitResult {
    std::vector<CardSegment> parts;
    // Largest |ideal - lattice| over the split points, in steps.
    double endpoint_error = 0;
    // Proved bound on max_deviation(delta, parts): the largest per-part bound
    // (chord between the part's lattice ends plus the chord's rounding). At most
    // 1/2 when the segment fits whole; at most 1/2 + epsilon when parts of that
    // bound average at least min(32, W/4) moves; otherwise the smallest bound up
    // to 1 step that reaches that average (a long line along a slope close to a
    // short fraction, or several minor axes that are seldom near a lattice point
    // at once).
    double deviation_bound = 0;
};

// Reduce one segment of integer deltas. `capacity` is W; `epsilon` is the
// extra deviation beyond half a step the split aims for.
SplitResult reduce_segment(const PerAxis<std::int64_t>& delta, std::uint32_t capacity,
                           double epsilon);

// Exact worst distance, in steps over all axes and moves, between what the
// card emits for `parts` (SPEC section 1 closed form, per part) and the ideal
// line of the original segment `delta`.
double max_deviation(const PerAxis<std::int64_t>& delta, std::span<const CardSegment> parts);

}  // namespace cpstep::plan

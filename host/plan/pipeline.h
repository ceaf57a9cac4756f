// SPDX-License-Identifier: MIT
// The whole core in one call: job + machine -> card segments with chunks.
// Pure: no I/O, everything it needs is in its arguments.
#pragma once

#include <memory>
#include <vector>

#include "plan/arc_fit.h"
#include "plan/chunks.h"
#include "plan/conic_arc.h"
#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/planner.h"
#include "plan/reduce.h"
#include "plan/segments.h"

namespace cpstep::plan {

struct PlannedCardSegment {
    CardSegment segment;
    std::vector<Chunk> chunks;   // their counts sum to segment.moves
    // A CONIC segment (an arc's piece, plan/conic_arc.h): the plane's walk, every
    // move's ideal time; segment.step_segment is the arc's first chord.
    std::shared_ptr<const ConicWalk> conic;
};

struct PlanStats {
    std::uint64_t moves = 0;         // moves that step (what the pins show)
    std::uint64_t pause_moves = 0;   // moves of pause segments (CardSegment::pause): the card counts them too
    std::uint64_t chunks = 0;
    std::uint64_t step_segments = 0;
    std::uint64_t card_segments = 0;
    double worst_split_error = 0;   // steps, beyond half a step
    std::uint64_t conic_arcs = 0;     // arcs the card walks (CONIC segments)
    std::uint64_t conic_segments = 0; // their pieces
    std::uint64_t chord_arcs = 0;     // arcs sent as chords (planner.arcs, the card, or a reason)
    ConicArcStats conic;              // the walks' deviations
    ArcFitStats fit;                  // G1 chains fitted (planner.fit_arcs_mm)
    double duration_s = 0;
    [[nodiscard]] double moves_per_chunk() const {
        return chunks ? static_cast<double>(moves) / static_cast<double>(chunks) : 0;
    }
};

struct PlannedJob {
    std::vector<StepSegment> step_segments;
    std::vector<PlannedSegment> feeds;       // one per step segment
    std::vector<PlannedCardSegment> card;    // in execution order
    PlanStats stats;
};

struct PlanOptions {
    ChunkLimits chunk_limits;                // enable_add2 defaults from the machine
    bool add2_from_machine = true;
};

Result<PlannedJob> plan_job(const Job& job, const Machine& machine, const PlanOptions& options = {});

// The ideal time of every move of a planned job, in card clock cycles from the
// job start, in execution order: what the chunks realize within the chunk
// tolerance (never late). For measuring the card against the plan itself.
std::vector<double> ideal_times(const PlannedJob& job, double clock_hz);

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// The whole core in one call: job + machine -> card segments with chunks.
// Pure: no I/O, everything it needs is in its arguments.
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "plan/arc_fit.h"
#include "plan/chunks.h"
#include "plan/conic_arc.h"
#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/phases.h"
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
    // The chunk time of the move before it, cycles from the job start, and the
    // moves of its step segment (all of its parts: each move is timed against them).
    std::int64_t prev_event = 0;
    std::uint64_t step_moves = 0;
    // PlanOptions::conic_rule_unit_mm: a conic's length word {S, K} (its arc's),
    // plan::conic_rule_lengths.
    std::uint32_t rule_word = 0;
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
    // PlanOptions::conic_length_rule: the largest shift of a conic move's time,
    // card cycles, and of its path position, steps of the walk's u axis.
    double conic_rule_shift_cycles = 0;
    double conic_rule_shift_steps = 0;
    // ... and the shortest time between two of an arc's moves so timed (cycles; the
    // walker needs conic_gap_cycles).
    double conic_rule_min_gap_cycles = std::numeric_limits<double>::infinity();
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
    ChunkLimits chunk_limits;                // what the chunks were compressed with
};

struct PlanOptions {
    ChunkLimits chunk_limits;                // enable_add2 defaults from the machine
    bool add2_from_machine = true;
    // A measurement hook (plan_figures phases): each card segment's ideal move
    // times (absolute clocks) as the card loop times them, each move's length
    // along the path (mm), and the clock at which its motion starts from rest
    // (-1: it continues). Pause moves are not shown.
    // With them, the feed plan's phases that the batch's motion brings (each
    // phase of its step segments' profiles), once per step segment.
    std::function<void(std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                       std::span<const PlanJerk> plan)>
        on_move_times;
    // Each pause's moves (a dwell longer than a move interval holds, or one after
    // the last move: docs/PLANNING.md "Dwells"), as the card loop makes its card
    // segment: their ideal times (absolute clocks), before the moves after them.
    std::function<void(std::span<const double> ideal)> on_pause_times;
    // on_move_times: a conic's moves as a card would time them by the length
    // rule of plan::conic_rule_divisors (one K per arc, its moves' lengths summing
    // to the arc's path), each at the plan's time for its position, instead of
    // where the true curve passes its node. PlanStats::conic_rule_shift_cycles
    // says how far that moves them.
    bool conic_length_rule = false;
    // ... > 0: the rule as a phase-timer card applies it, exactly: each arc's
    // {S, K} (plan::conic_rule_lengths, PlannedCardSegment::rule_word) and its moves'
    // lengths floor(K 2^S / m) in 2^-30 of this unit (the phases' path unit, mm),
    // each move at the plan's time for the sum of the lengths before it. 0: the
    // rule's proportions in real numbers, scaled to the arc's path (a projection).
    double conic_rule_unit_mm = 0;
};

// The whole job planned: its blocks pushed through a PlanStream (after G1 chains
// are fitted with arcs where the machine file asks), everything it hands out
// kept. (A job too long to keep: run::CardJob::streamed, run::PlanCursor.)
Result<PlannedJob> plan_job(const Job& job, const Machine& machine, const PlanOptions& options = {});

// A step segment through the card loop, with its feed (PlannedJob::step_segments
// and feeds, index `index`).
struct StreamedStep {
    std::size_t index = 0;
    StepSegment segment;
    PlannedSegment feed;
};

// The plan made as the blocks arrive, one at a time (a job read as it is
// planned): StepSegmenter, FeedPlanner and the card loop in a chain, each
// holding a window, not the job. It hands out the step segments (with their
// feeds) and the card segments (with their chunks and walks) of plan_job(),
// bit for bit, in order; a card segment only once every step segment up to
// its own has been handed out (next_step() until none, then next_card()).
// The card loop waits for a conic arc's last chord and for the next move
// after it (whether the walk must end on the arc's end step). After an error
// nothing more is handed out; errors() are those plan_job() would give.
class PlanStream {
public:
    PlanStream(const Machine& m, std::string job_file, const PlanOptions& options = {});
    ~PlanStream();
    PlanStream(PlanStream&&) noexcept;
    PlanStream& operator=(PlanStream&&) noexcept;
    PlanStream(const PlanStream&) = delete;
    PlanStream& operator=(const PlanStream&) = delete;

    // The job's next block; `index` is its place among the job's blocks.
    void push(const MotionBlock& block, std::size_t index);
    void finish();  // the job has no more
    std::optional<StreamedStep> next_step();
    std::optional<PlannedCardSegment> next_card();

    [[nodiscard]] bool done() const;  // finished and through the card loop, no error
    [[nodiscard]] std::vector<Diagnostic> warnings() const;
    [[nodiscard]] std::vector<Diagnostic> errors() const;
    // The errors came from a stage before the card loop (step segments, feeds,
    // the job's length): plan_job() made those whole before the loop began.
    [[nodiscard]] bool refused_before_the_card_loop() const;
    [[nodiscard]] const PlanStats& stats() const;  // whole once done() (but `fit`: plan_job()'s)
    [[nodiscard]] const ChunkLimits& chunk_limits() const;
    // Step segments, feeds and polyline points held, and what is made but not handed out.
    [[nodiscard]] std::size_t held() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The ideal time of every move of a planned job, in card clock cycles from the
// job start, in execution order: what the chunks realize within the chunk
// tolerance (never late). For measuring the card against the plan itself.
std::vector<double> ideal_times(const PlannedJob& job, double clock_hz);

}  // namespace cpstep::plan

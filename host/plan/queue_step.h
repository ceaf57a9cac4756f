// SPDX-License-Identifier: MIT
// What the same steps would cost on Klipper's wire: its per-stepper step
// compression (queue_step interval, count, add: step i of a message comes
// interval + i*add cycles after step i-1, each step in [ideal - max_error,
// ideal]) and its message encoding, for comparing the card's command bytes
// with it (issue 13, docs/BENCHMARKS.md "The wire against Klipper's").
//
// The messages are counted by plan::compress without add2 (the greedy longest
// chunk, at least as long as Klipper's bisection finds: the count is a lower
// bound of Klipper's), the bytes by Klipper's encoding as its docs/Protocol.md
// states it: every integer a variable-length quantity (-32..95 one byte,
// -4096..12287 two, -524288..1572863 three, -67108864..201326591 four, else
// five), a message its command id and its arguments, messages packed into
// blocks of at most 64 bytes with 5 bytes of header and trailer each.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "plan/chunks.h"

namespace cpstep::plan {

struct PlannedJob;
struct PlannedSegment;
struct StepSegment;

// One stepper's steps: the cycle of each step and its direction (+1 / -1).
struct StepperSteps {
    std::vector<std::uint64_t> cycles;   // increasing
    std::vector<std::int8_t> dirs;       // one per step
};

struct QueueStepCost {
    std::uint64_t steps = 0;
    std::uint64_t queue_step = 0;        // queue_step oid interval count add
    std::uint64_t set_next_step_dir = 0; // set_next_step_dir oid dir, one per direction change
    std::uint64_t reset_step_clock = 0;  // reset_step_clock oid clock, one per stepper that steps
    std::uint64_t message_bytes = 0;     // the messages alone
    std::uint64_t blocks = 0;
    std::uint64_t bytes = 0;             // with the blocks' header and trailer
    std::string error;                   // a step no message can time (empty: none)
    friend bool operator==(const QueueStepCost&, const QueueStepCost&) = default;
};

// Every axis's steps where Klipper places them: each step at the time the
// planned path passes the middle between its two step positions (step k of
// an axis that moves d steps along a segment at (k - 1/2)/|d| of the
// segment's length, timed by the segment's feed profile), in cycles of
// `clock_hz` from the job start. Arcs the card walks as conics count as their
// chords (Klipper cuts arcs into lines too). One entry per axis that steps.
std::vector<StepperSteps> path_steps(const PlannedJob& job, double clock_hz);
// The same steps one at a time, each stepper's in increasing time (the axis
// index as the stepper): for QueueStepCounter, in bounded memory.
void for_each_path_step(const PlannedJob& job, double clock_hz,
                        const std::function<void(int axis, std::uint64_t cycle, std::int8_t dir)>& step);
// The steps of one step segment with its feed (a plan streamed segment by segment).
void for_each_segment_step(const StepSegment& s, const PlannedSegment& feed, double clock_hz,
                           const std::function<void(int axis, std::uint64_t cycle, std::int8_t dir)>& step);

// Bytes of one integer in Klipper's variable-length encoding.
unsigned klipper_vlq_bytes(std::int64_t v);

// Klipper's queue_step fields as chunk limits: interval u32, count u16, add
// s16, no add2.
ChunkLimits klipper_chunk_limits();

// The cost of all `steppers`' steps at `max_error_cycles`, the step times
// counted in cycles of the same clock (the card's: Klipper's MCU clock is then
// taken to be the card's). Command ids and oids are one byte each.
QueueStepCost queue_step_cost(std::span<const StepperSteps> steppers, double max_error_cycles);

// The same with other chunk limits (tests: a small max_count); the messages
// still carry interval, count and add alone.
QueueStepCost queue_step_cost(std::span<const StepperSteps> steppers, double max_error_cycles,
                              const ChunkLimits& limits);

// queue_step_cost() fed one step at a time, in bounded memory: each stepper's
// steps in increasing time (steppers in any interleaving), the result equal to
// queue_step_cost() of the same steps, steppers ordered by their index (empty
// ones left out, as path_steps() leaves them).
//
// Per stepper it buffers the steps of the open run (one direction) not yet in
// a counted message, at most `window` of them. When the buffer is full it
// compresses it and counts the messages whose choice is already final: a chunk
// from move s depends on the moves s .. s + max_count - 1 and on how many
// remain only up to max_count, so a chunk with at least max_count buffered
// moves from its start is the one compress() picks on the whole run. A
// direction change or finish() compresses the rest of the run. The 64-byte
// blocks are packed per stepper from every fill the messages before can leave
// (each stepper's messages follow all of the previous stepper's), and chained
// in stepper order by finish().
class QueueStepCounter {
 public:
    explicit QueueStepCounter(double max_error_cycles);
    // Tests: other chunk limits (as queue_step_cost()'s overload takes them)
    // and window (0: 2 max_count; at least max_count).
    QueueStepCounter(double max_error_cycles, const ChunkLimits& limits, std::size_t window);
    QueueStepCounter(QueueStepCounter&&) noexcept;
    QueueStepCounter& operator=(QueueStepCounter&&) noexcept;
    ~QueueStepCounter();

    // The next step of `stepper` (0..kAxes-1, plan/common.h) at `cycle`,
    // direction `dir` (+1 / -1). Throws std::out_of_range for another stepper.
    void add(int stepper, std::uint64_t cycle, std::int8_t dir);
    // The cost of every step added; call once, after the last add().
    QueueStepCost finish();

 private:
    struct Stepper;
    void flush(Stepper& s, bool run_ends);

    double max_error_;
    ChunkLimits limits_;
    std::size_t window_;
    std::vector<Stepper> steppers_;   // one per axis
};

}  // namespace cpstep::plan

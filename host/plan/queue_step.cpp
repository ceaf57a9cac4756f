// SPDX-License-Identifier: MIT
#include "plan/queue_step.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "plan/chunks.h"
#include "plan/pipeline.h"

namespace cpstep::plan {

void for_each_segment_step(const StepSegment& s, const PlannedSegment& f, double clock_hz,
                           const std::function<void(int, std::uint64_t, std::int8_t)>& step) {
    const PerAxis<std::int64_t> d = s.delta();
    for (int a = 0; a < kAxes; ++a) {
        if (d[a] == 0) continue;
        const std::int64_t n = d[a] < 0 ? -d[a] : d[a];
        for (std::int64_t k = 1; k <= n; ++k) {
            const double at = f.length * (static_cast<double>(k) - 0.5) / static_cast<double>(n);
            step(a, static_cast<std::uint64_t>(std::llround((f.t_start + f.profile.time_at(at)) * clock_hz)),
                 d[a] < 0 ? -1 : 1);
        }
    }
}

void for_each_path_step(const PlannedJob& job, double clock_hz,
                        const std::function<void(int, std::uint64_t, std::int8_t)>& step) {
    for (std::size_t i = 0; i < job.step_segments.size() && i < job.feeds.size(); ++i)
        for_each_segment_step(job.step_segments[i], job.feeds[i], clock_hz, step);
}

std::vector<StepperSteps> path_steps(const PlannedJob& job, double clock_hz) {
    PerAxis<StepperSteps> axes;
    for_each_path_step(job, clock_hz, [&](int a, std::uint64_t cycle, std::int8_t dir) {
        axes[a].cycles.push_back(cycle);
        axes[a].dirs.push_back(dir);
    });
    std::vector<StepperSteps> out;
    for (StepperSteps& a : axes)
        if (!a.cycles.empty()) out.push_back(std::move(a));
    return out;
}

unsigned klipper_vlq_bytes(std::int64_t v) {
    if (v >= -32 && v < 96) return 1;
    if (v >= -4096 && v < 12288) return 2;
    if (v >= -524288 && v < 1572864) return 3;
    if (v >= -67108864 && v < 201326592) return 4;
    return 5;
}

namespace {

// Klipper's message blocks: at most 64 bytes, 5 of them header and trailer.
constexpr unsigned kBlockMax = 64, kBlockOverhead = 5;

// The messages' bytes: command id and oid, then the arguments.
unsigned reset_step_clock_bytes() { return 2 + klipper_vlq_bytes(0); }   // clock 0: the job's start
constexpr unsigned kSetNextStepDirBytes = 2 + 1;
unsigned queue_step_bytes(const Chunk& ch) {
    return 2 + klipper_vlq_bytes(ch.interval) + klipper_vlq_bytes(ch.count) + klipper_vlq_bytes(ch.add);
}

// The greedy packing of one more message: a new block when it does not fit in
// the open one (`fill` bytes; kBlockMax also when none is open yet).
void pack(unsigned message, unsigned& fill, std::uint64_t& blocks) {
    if (fill + message > kBlockMax) {
        ++blocks;
        fill = kBlockOverhead;
    }
    fill += message;
}

// The error of the run from step `run_start`, as queue_step_cost() words it.
std::string run_error(std::uint64_t run_start, const std::string& error) {
    return fmt::format("step {}: {}", run_start, error);
}

}  // namespace

ChunkLimits klipper_chunk_limits() {
    ChunkLimits lim;
    lim.max_count = 65535;
    lim.add_min = INT16_MIN;
    lim.add_max = INT16_MAX;
    lim.enable_add2 = false;
    return lim;
}

QueueStepCost queue_step_cost(std::span<const StepperSteps> steppers, double max_error_cycles) {
    return queue_step_cost(steppers, max_error_cycles, klipper_chunk_limits());
}

QueueStepCost queue_step_cost(std::span<const StepperSteps> steppers, double max_error_cycles,
                              const ChunkLimits& lim) {
    QueueStepCost c;
    std::vector<unsigned> messages;   // each message's bytes, in order
    for (const StepperSteps& s : steppers) {
        if (s.cycles.empty()) continue;
        c.steps += s.cycles.size();
        ++c.reset_step_clock;
        messages.push_back(reset_step_clock_bytes());
        std::int64_t prev = 0;
        std::int8_t dir = 0;
        std::size_t i = 0;
        while (i < s.cycles.size()) {
            std::size_t j = i;
            while (j < s.cycles.size() && s.dirs[j] == s.dirs[i]) ++j;
            if (s.dirs[i] != dir) {
                dir = s.dirs[i];
                ++c.set_next_step_dir;
                messages.push_back(kSetNextStepDirBytes);
            }
            std::vector<double> ideal(s.cycles.begin() + std::ptrdiff_t(i), s.cycles.begin() + std::ptrdiff_t(j));
            ChunkResult r = compress(ideal, prev, max_error_cycles, lim);
            if (!r.ok()) {
                c.error = run_error(i, r.error);
                return c;
            }
            for (const Chunk& ch : r.chunks) {
                ++c.queue_step;
                messages.push_back(queue_step_bytes(ch));
            }
            prev = r.last_event;
            i = j;
        }
    }
    unsigned fill = kBlockMax;   // the open block's bytes; none open yet
    for (unsigned m : messages) {
        c.message_bytes += m;
        pack(m, fill, c.blocks);
    }
    c.bytes = c.message_bytes + kBlockOverhead * c.blocks;
    return c;
}

namespace {

// The greedy packing of one stepper's messages from every state the messages
// before them can leave: the open block's fill f in kBlockOverhead..kBlockMax
// (kBlockMax standing also for none open: no message fits in either, so both
// pack alike), and from each the blocks the messages open and the fill after.
struct Packing {
    static constexpr unsigned kStates = kBlockMax - kBlockOverhead + 1;
    std::array<std::uint64_t, kStates> blocks{};
    std::array<unsigned, kStates> fill{};
    Packing() {
        for (unsigned k = 0; k < kStates; ++k) fill[k] = kBlockOverhead + k;
    }
    void add(unsigned message) {
        for (unsigned k = 0; k < kStates; ++k) pack(message, fill[k], blocks[k]);
    }
};

// compress()'s error names a move by its place in the moves it was given (the
// buffer): name it by its place in the run, as queue_step_cost() does.
std::string in_run(const std::string& error, std::uint64_t buffer_start) {
    const std::size_t at = error.find("move ");
    if (at == std::string::npos || buffer_start == 0) return error;
    const std::size_t b = at + 5;
    std::size_t e = b;
    while (e < error.size() && error[e] >= '0' && error[e] <= '9') ++e;
    if (e == b) return error;
    const std::uint64_t move = std::stoull(error.substr(b, e - b)) + buffer_start;
    return error.substr(0, b) + std::to_string(move) + error.substr(e);
}

}  // namespace

struct QueueStepCounter::Stepper {
    std::uint64_t steps = 0;
    std::uint64_t queue_step = 0;          // messages of the runs compressed to their end
    std::uint64_t run_queue_step = 0;      // messages of the open run counted so far
    std::uint64_t set_next_step_dir = 0;
    std::uint64_t message_bytes = 0;
    Packing packing;
    std::int8_t dir = 0;                   // the open or last run's direction (0: none yet)
    bool run_open = false;
    std::uint64_t run_start = 0;           // the open run's first step, counted from this stepper's first
    std::uint64_t buffer_start = 0;        // buffer[0]'s place in the open run
    std::vector<double> buffer;            // the open run's steps after the counted messages
    std::int64_t prev = 0;                 // realized time of the last counted message's last step
    std::string error;                     // as queue_step_cost() gives it (empty: none)

    void message(unsigned bytes) {
        message_bytes += bytes;
        packing.add(bytes);
    }
};

QueueStepCounter::QueueStepCounter(double max_error_cycles)
    : QueueStepCounter(max_error_cycles, klipper_chunk_limits(), 0) {}

QueueStepCounter::QueueStepCounter(double max_error_cycles, const ChunkLimits& limits, std::size_t window)
    : max_error_(max_error_cycles),
      limits_(limits),
      window_(std::max<std::size_t>({window == 0 ? 2 * std::size_t{limits.max_count} : window, limits.max_count, 1})),
      steppers_(kAxes) {}

QueueStepCounter::QueueStepCounter(QueueStepCounter&&) noexcept = default;
QueueStepCounter& QueueStepCounter::operator=(QueueStepCounter&&) noexcept = default;
QueueStepCounter::~QueueStepCounter() = default;

void QueueStepCounter::add(int stepper, std::uint64_t cycle, std::int8_t dir) {
    Stepper& s = steppers_.at(static_cast<std::size_t>(stepper));
    if (s.steps++ == 0) s.message(reset_step_clock_bytes());
    if (!s.error.empty()) return;   // queue_step_cost() stops at the error: so do the counts
    if (s.run_open && dir != s.dir) flush(s, true);   // a direction change ends the run
    if (!s.error.empty()) return;
    if (!s.run_open) {
        s.run_open = true;
        s.run_start = s.steps - 1;
        s.buffer_start = 0;
        if (dir != s.dir) {
            s.dir = dir;
            ++s.set_next_step_dir;
            s.message(kSetNextStepDirBytes);
        }
    }
    s.buffer.push_back(static_cast<double>(cycle));
    if (s.buffer.size() >= window_) flush(s, false);
}

// Compress the buffered steps and count the messages that are final: all of
// them when the run ends here, else those from a move with at least max_count
// buffered moves from it on (compress(), chunk_loop(): the chunk from move s
// reads the moves s .. s + min(remaining, max_count) - 1 alone). Their first
// unfinal one starts past buffer.size() - max_count, so fewer than max_count
// moves stay buffered, and at least one chunk (from move 0) is final.
void QueueStepCounter::flush(Stepper& s, bool run_ends) {
    const ChunkResult r = compress(s.buffer, s.prev, max_error_, limits_);
    std::size_t final_chunks = 0, final_moves = 0;
    for (const Chunk& ch : r.chunks) {
        if (!run_ends && s.buffer.size() - final_moves < limits_.max_count) break;
        ++final_chunks;
        final_moves += ch.count;
    }
    // An error after final chunks alone is final too: it is the first move of a
    // chunk that cannot start (its window and the previous event decide that),
    // or a move without a whole cycle in its tolerance, found before any chunk.
    // compress() of the whole run looks for the latter in all the run first;
    // with whole-cycle step times only a negative tolerance leaves a move none,
    // and then the run's first move already (times grow, so the rounding that
    // could hide it does too): the run's first buffer finds it alike.
    if (!r.ok() && final_chunks == r.chunks.size()) {
        s.error = run_error(s.run_start, in_run(r.error, s.buffer_start));
        return;
    }
    const std::span<const Chunk> counted(r.chunks.data(), final_chunks);
    for (const Chunk& ch : counted) s.message(queue_step_bytes(ch));
    s.run_queue_step += final_chunks;
    if (final_chunks > 0) s.prev = expand(counted, s.prev, limits_.frac_bits).back();
    s.buffer.erase(s.buffer.begin(), s.buffer.begin() + std::ptrdiff_t(final_moves));
    s.buffer_start += final_moves;
    if (run_ends) {
        // queue_step_cost() counts a run's messages once the whole run compresses.
        s.queue_step += s.run_queue_step;
        s.run_queue_step = 0;
        s.run_open = false;
    }
}

QueueStepCost QueueStepCounter::finish() {
    QueueStepCost c;
    unsigned fill = kBlockMax;   // the open block's bytes; none open yet
    for (Stepper& s : steppers_) {
        if (s.steps == 0) continue;
        if (s.error.empty() && s.run_open) flush(s, true);
        c.steps += s.steps;
        ++c.reset_step_clock;
        c.set_next_step_dir += s.set_next_step_dir;
        c.queue_step += s.queue_step;
        if (!s.error.empty()) {
            // queue_step_cost() returns at the first error, the blocks not packed.
            c.message_bytes = c.blocks = 0;
            c.error = s.error;
            return c;
        }
        c.message_bytes += s.message_bytes;
        c.blocks += s.packing.blocks[fill - kBlockOverhead];
        fill = s.packing.fill[fill - kBlockOverhead];
    }
    c.bytes = c.message_bytes + kBlockOverhead * c.blocks;
    return c;
}

}  // namespace cpstep::plan

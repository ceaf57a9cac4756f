// SPDX-License-Identifier: MIT
#include "plan/queue_step.h"

#include <cmath>

#include <fmt/format.h>

#include "plan/chunks.h"
#include "plan/pipeline.h"

namespace cpstep::plan {

std::vector<StepperSteps> path_steps(const PlannedJob& job, double clock_hz) {
    PerAxis<StepperSteps> axes;
    for (std::size_t i = 0; i < job.step_segments.size() && i < job.feeds.size(); ++i) {
        const StepSegment& s = job.step_segments[i];
        const PlannedSegment& f = job.feeds[i];
        const PerAxis<std::int64_t> d = s.delta();
        for (int a = 0; a < kAxes; ++a) {
            if (d[a] == 0) continue;
            const std::int64_t n = d[a] < 0 ? -d[a] : d[a];
            for (std::int64_t k = 1; k <= n; ++k) {
                const double at = f.length * (static_cast<double>(k) - 0.5) / static_cast<double>(n);
                axes[a].cycles.push_back(
                    static_cast<std::uint64_t>(std::llround((f.t_start + f.profile.time_at(at)) * clock_hz)));
                axes[a].dirs.push_back(d[a] < 0 ? -1 : 1);
            }
        }
    }
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

QueueStepCost queue_step_cost(std::span<const StepperSteps> steppers, double max_error_cycles) {
    QueueStepCost c;
    constexpr unsigned kBlockMax = 64, kBlockOverhead = 5;
    std::vector<unsigned> messages;   // each message's bytes, in order
    // Klipper's queue_step fields: interval u32, count u16, add s16.
    ChunkLimits lim;
    lim.max_count = 65535;
    lim.add_min = INT16_MIN;
    lim.add_max = INT16_MAX;
    lim.enable_add2 = false;
    for (const StepperSteps& s : steppers) {
        if (s.cycles.empty()) continue;
        c.steps += s.cycles.size();
        ++c.reset_step_clock;
        messages.push_back(2 + klipper_vlq_bytes(0));   // reset_step_clock at the job's start
        std::int64_t prev = 0;
        std::int8_t dir = 0;
        std::size_t i = 0;
        while (i < s.cycles.size()) {
            std::size_t j = i;
            while (j < s.cycles.size() && s.dirs[j] == s.dirs[i]) ++j;
            if (s.dirs[i] != dir) {
                dir = s.dirs[i];
                ++c.set_next_step_dir;
                messages.push_back(2 + 1);
            }
            std::vector<double> ideal(s.cycles.begin() + std::ptrdiff_t(i), s.cycles.begin() + std::ptrdiff_t(j));
            ChunkResult r = compress(ideal, prev, max_error_cycles, lim);
            if (!r.ok()) {
                c.error = fmt::format("step {}: {}", i, r.error);
                return c;
            }
            for (const Chunk& ch : r.chunks) {
                ++c.queue_step;
                messages.push_back(2 + klipper_vlq_bytes(ch.interval) + klipper_vlq_bytes(ch.count) +
                                   klipper_vlq_bytes(ch.add));
            }
            prev = r.last_event;
            i = j;
        }
    }
    unsigned fill = kBlockMax;   // the open block's bytes; none open yet
    for (unsigned m : messages) {
        c.message_bytes += m;
        if (fill + m > kBlockMax) {
            ++c.blocks;
            fill = kBlockOverhead;
        }
        fill += m;
    }
    c.bytes = c.message_bytes + kBlockOverhead * c.blocks;
    return c;
}

}  // namespace cpstep::plan

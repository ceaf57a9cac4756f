// SPDX-License-Identifier: MIT
#include "plan/pipeline.h"

#include <cmath>

#include <fmt/format.h>

#include "plan/chunks.h"
#include "plan/steptime.h"

namespace cpstep::plan {

Result<PlannedJob> plan_job(const Job& job, const Machine& m, const PlanOptions& options) {
    Result<PlannedJob> result;
    if (!(m.card.clock_hz > 0)) {
        result.errors.push_back({m.file, {}, "no card clock: the machine file gives no [card] clock_hz and no "
                                             "card was asked (plan::bind_card())"});
        return result;
    }
    auto segs = make_step_segments(job, m);
    result.warnings = segs.warnings;
    if (!segs.ok()) {
        result.errors = segs.errors;
        return result;
    }
    auto feeds = plan_feeds(*segs.value, m, job.file);
    result.warnings.insert(result.warnings.end(), feeds.warnings.begin(), feeds.warnings.end());
    if (!feeds.ok()) {
        result.errors = feeds.errors;
        return result;
    }
    PlannedJob pj;
    pj.step_segments = std::move(*segs.value);
    pj.feeds = std::move(*feeds.value);
    ChunkLimits lim = options.chunk_limits;
    if (options.add2_from_machine) lim.enable_add2 = m.planner.chunk_add2;
    const double tol = m.chunk_tolerance_cycles();
    std::int64_t prev = 0;  // the job starts at cycle 0
    // Dwells since the last move: the card times a pause as the next move's first
    // interval, at most 2^32 - 1 cycles; a longer one, and one after the last
    // move, as pause moves (moves that step no axis) in between.
    constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::size_t dwell_first = kNone;
    double dwell_s = 0;
    // Pause moves from `prev` to cycle `until`, in `n` equal steps of at most
    // 2^32 - 1 cycles (the last at `until`), as one card segment of their own.
    const auto add_pause = [&](double until, std::uint64_t n, std::size_t dwell) -> bool {
        std::vector<double> times(n);
        for (std::uint64_t j = 0; j < n; ++j)
            times[j] = double(prev) + (until - double(prev)) * double(j + 1) / double(n);
        auto chunks = compress(times, prev, tol, lim);
        if (!chunks.ok()) {
            result.errors.push_back({job.file, pj.step_segments[dwell].loc, fmt::format("pause timing: {}", chunks.error)});
            return false;
        }
        CardSegment pause;
        pause.moves = static_cast<std::uint32_t>(n);
        pause.u.fill(1);
        pause.dir_positive.fill(true);
        pause.loc = pj.step_segments[dwell].loc;
        pause.step_segment = dwell;
        pause.pause = true;
        prev = chunks.last_event;
        pj.stats.pause_moves += n;
        pj.stats.chunks += chunks.chunks.size();
        pj.card.push_back({pause, std::move(chunks.chunks)});
        return true;
    };
    // Equal intervals, each under 2^32 - 1 cycles, that make up `cycles`.
    const auto intervals = [](double cycles) {
        return static_cast<std::uint64_t>(std::floor(cycles / double(kMaxMoveDelayCycles))) + 1;
    };
    for (std::size_t i = 0; i < pj.step_segments.size(); ++i) {
        const StepSegment& s = pj.step_segments[i];
        if (s.kind == MotionKind::dwell) {  // a pause shows as a longer first interval
            if (dwell_first == kNone) dwell_first = i;
            dwell_s += s.dwell_s;
            continue;
        }
        auto split = reduce_segment(s.delta(), m.card.pattern_capacity, m.planner.split_epsilon_steps);
        pj.stats.worst_split_error = std::max(pj.stats.worst_split_error, split.deviation_bound - 0.5);
        std::uint64_t total = 0;
        for (const auto& part : split.parts) total += part.moves;
        for (auto& part : split.parts) {
            part.loc = s.loc;
            part.step_segment = i;
            const auto ideal = ideal_move_times(pj.feeds[i], total, part.first_move, part.moves,
                                                m.card.clock_hz);
            if (dwell_first != kNone && !ideal.empty() &&
                ideal.front() - double(prev) > double(kMaxMoveDelayCycles)) {
                // Longer than one interval: pause moves split the gap, the move
                // after them times the last part (each at most 2^32 - 1 cycles).
                const double gap = ideal.front() - double(prev);
                const std::uint64_t parts = intervals(gap);
                if (!add_pause(double(prev) + gap * double(parts - 1) / double(parts), parts - 1, dwell_first))
                    return result;
            }
            auto chunks = compress(ideal, prev, tol, lim);
            if (!chunks.ok()) {
                result.errors.push_back({job.file, s.loc, fmt::format("timing: {}", chunks.error)});
                return result;
            }
            prev = chunks.last_event;
            pj.stats.moves += part.moves;
            pj.stats.chunks += chunks.chunks.size();
            pj.card.push_back({part, std::move(chunks.chunks)});
        }
        dwell_first = kNone;
        dwell_s = 0;
    }
    // The job ends with its last move, or with the dwells after it: pause moves
    // up to their end (the card runs until the last one).
    double end_s = 0;
    for (std::size_t i = pj.feeds.size(); i-- > 0;) {
        if (pj.step_segments[i].kind == MotionKind::dwell) continue;
        end_s = pj.feeds[i].t_start + pj.feeds[i].duration;
        break;
    }
    if (dwell_first != kNone && dwell_s > 0) {
        const double until = double(prev) + dwell_s * m.card.clock_hz;
        if (!add_pause(until, intervals(until - double(prev)), dwell_first)) return result;
        end_s = double(prev) / m.card.clock_hz;
    }
    pj.stats.step_segments = pj.step_segments.size();
    pj.stats.card_segments = pj.card.size();
    pj.stats.duration_s = end_s;
    result.value = std::move(pj);
    return result;
}

std::vector<double> ideal_times(const PlannedJob& job, double clock_hz) {
    std::vector<double> out;
    out.reserve(job.stats.moves);
    for (std::size_t c = 0; c < job.card.size();) {
        // The parts of one step segment are consecutive; move i of the whole
        // segment is timed against its total.
        const std::size_t step_segment = job.card[c].segment.step_segment;
        std::size_t end = c;
        std::uint64_t total = 0;
        while (end < job.card.size() && job.card[end].segment.step_segment == step_segment)
            total += job.card[end++].segment.moves;
        for (; c < end; ++c) {
            const CardSegment& part = job.card[c].segment;
            if (part.pause) continue;  // the pins show no pause move
            const auto t = ideal_move_times(job.feeds[step_segment], total, part.first_move,
                                            part.moves, clock_hz);
            out.insert(out.end(), t.begin(), t.end());
        }
    }
    return out;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/pipeline.h"

#include <cmath>

#include <fmt/format.h>

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
    for (std::size_t i = 0; i < pj.step_segments.size(); ++i) {
        const StepSegment& s = pj.step_segments[i];
        if (s.kind == MotionKind::dwell) continue;  // a pause shows as a longer first interval
        auto split = reduce_segment(s.delta(), m.card.pattern_capacity, m.planner.split_epsilon_steps);
        pj.stats.worst_split_error = std::max(pj.stats.worst_split_error, split.endpoint_error);
        std::uint64_t total = 0;
        for (const auto& part : split.parts) total += part.moves;
        for (auto& part : split.parts) {
            part.loc = s.loc;
            part.step_segment = i;
            const auto ideal = ideal_move_times(pj.feeds[i], total, part.first_move, part.moves,
                                                m.card.clock_hz);
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
    }
    pj.stats.step_segments = pj.step_segments.size();
    pj.stats.card_segments = pj.card.size();
    if (!pj.feeds.empty()) pj.stats.duration_s = pj.feeds.back().t_start + pj.feeds.back().duration;
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
            const auto t = ideal_move_times(job.feeds[step_segment], total, part.first_move,
                                            part.moves, clock_hz);
            out.insert(out.end(), t.begin(), t.end());
        }
    }
    return out;
}

}  // namespace cpstep::plan

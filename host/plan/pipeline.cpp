// SPDX-License-Identifier: MIT
#include "plan/pipeline.h"

#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <variant>

#include <fmt/format.h>

#include "plan/arc_fit.h"
#include "plan/chunks.h"
#include "plan/steptime.h"

namespace cpstep::plan {

namespace {

ChunkLimits job_chunk_limits(const Machine& m, const PlanOptions& options) {
    ChunkLimits lim = options.chunk_limits;
    if (options.add2_from_machine) lim.enable_add2 = m.planner.chunk_add2;
    return lim;
}

// The ideal times of a pause's `n` moves from `prev` to `until`, in equal steps.
std::vector<double> pause_times(std::int64_t prev, double until, std::uint64_t n) {
    std::vector<double> times(n);
    for (std::uint64_t j = 0; j < n; ++j) times[j] = double(prev) + (until - double(prev)) * double(j + 1) / double(n);
    return times;
}

// What plan_conic_arc() takes for the arc of step segments [first, end).
ConicArcInput arc_input(const PlannedJob& pj, const MotionBlock& block, std::size_t first, std::size_t end,
                        const PerAxis<std::int64_t>& start, bool last_motion, const Machine& m) {
    ConicArcInput in;
    in.block = &block;
    in.chords = std::span<const StepSegment>(pj.step_segments).subspan(first, end - first);
    in.feeds = std::span<const PlannedSegment>(pj.feeds).subspan(first, end - first);
    in.first_step_segment = first;
    in.start = start;
    in.last_motion = last_motion;
    in.ciw = m.card.conic_width;
    in.umax = m.card.max_moves;
    in.w = m.card.pattern_capacity;
    in.clock_hz = m.card.clock_hz;
    in.tolerance_cycles = m.chunk_tolerance_cycles();
    return in;
}

}  // namespace

Result<PlannedJob> plan_job(const Job& given, const Machine& m, const PlanOptions& options) {
    Result<PlannedJob> result;
    // Chains of G1 lines as arcs where the machine file asks (plan/arc_fit.h): the
    // rest of the plan is of the fitted job.
    ArcFitStats fit;
    Job fitted;
    if (m.planner.fit_arcs_mm > 0) fitted = fit_arcs(given, m.planner.fit_arcs_mm, &fit);
    const Job& job = m.planner.fit_arcs_mm > 0 ? fitted : given;
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
    // The card's time is counted in cycles from the job start (64-bit on the
    // host): a job that would run past 2^62 of them (some 3,000 years at 48 MHz:
    // a dwell or a feed no machine means) is refused where it passes that.
    const double limit_s = std::ldexp(1.0, 62) / m.card.clock_hz;
    for (std::size_t i = 0; i < feeds->size(); ++i) {
        const PlannedSegment& f = (*feeds.value)[i];
        if (!(f.t_start + f.duration <= limit_s)) {
            result.errors.push_back({job.file, (*segs.value)[i].loc,
                                     fmt::format("the job would last past {:.3g} s here (2^62 cycles of the card's "
                                                 "{:g} Hz clock): a dwell or feed no job can run",
                                                 limit_s, m.card.clock_hz)});
            return result;
        }
    }
    PlannedJob pj;
    pj.step_segments = std::move(*segs.value);
    pj.feeds = std::move(*feeds.value);
    const ChunkLimits lim = job_chunk_limits(m, options);
    pj.chunk_limits = lim;
    // A card segment made: to the sink, then kept (without its chunks and walk
    // when the sink is all that needs them).
    const auto emit = [&](PlannedCardSegment& c) -> bool {
        if (options.on_segment) {
            if (auto e = options.on_segment(pj, pj.card.size() - 1)) {
                result.errors.push_back(std::move(*e));
                return false;
            }
        }
        if (!options.keep_chunks) {
            std::vector<Chunk>().swap(c.chunks);
            c.conic.reset();
        }
        return true;
    };
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
        auto chunks = compress(pause_times(prev, until, n), prev, tol, lim);
        if (!chunks.ok()) {
            result.errors.push_back({job.file, pj.step_segments[dwell].loc, fmt::format("pause timing: {}", chunks.error)});
            return false;
        }
        const std::int64_t before = prev;
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
        PlannedCardSegment& c = pj.card.emplace_back(PlannedCardSegment{pause, std::move(chunks.chunks), nullptr});
        c.prev_event = before;
        c.step_moves = n;
        c.pause_until = until;
        return emit(c);
    };
    // Equal intervals, each under 2^32 - 1 cycles, that make up `cycles`.
    const auto intervals = [](double cycles) {
        return static_cast<std::uint64_t>(std::floor(cycles / double(kMaxMoveDelayCycles))) + 1;
    };
    // Where the card is: a conic's walk may end a step off its arc's rounded end,
    // and the segment after it starts from there.
    PerAxis<std::int64_t> pos{};
    if (!pj.step_segments.empty()) pos = pj.step_segments.front().start;
    // The last move of the last CONIC segment: the next one's first move comes
    // conic_gap_cycles() after it at the earliest.
    std::int64_t last_conic_event = std::numeric_limits<std::int64_t>::min() / 2;
    const bool conics = m.planner.arcs == ArcMode::conic && m.card.conic_width > 0;
    std::size_t chords_until = 0;  // an arc left to chords: its step segments up to here
    // A pause before the move at `first_ideal` when it is further than one
    // interval can time.
    const auto pause_before = [&](double first_ideal) -> bool {
        if (dwell_first != kNone && first_ideal - double(prev) > double(kMaxMoveDelayCycles)) {
            // Longer than one interval: pause moves split the gap, the move
            // after them times the last part (each at most 2^32 - 1 cycles).
            const double gap = first_ideal - double(prev);
            const std::uint64_t parts = intervals(gap);
            return add_pause(double(prev) + gap * double(parts - 1) / double(parts), parts - 1, dwell_first);
        }
        return true;
    };
    for (std::size_t i = 0; i < pj.step_segments.size(); ++i) {
        StepSegment& s = pj.step_segments[i];
        if (s.kind == MotionKind::dwell) {  // a pause shows as a longer first interval
            if (dwell_first == kNone) dwell_first = i;
            dwell_s += s.dwell_s;
            s.start = s.end = pos;
            continue;
        }
        const bool arc = s.kind == MotionKind::arc_cw || s.kind == MotionKind::arc_ccw;
        if (arc && m.planner.arcs == ArcMode::conic && i >= chords_until) {
            // The arc's chords: the step segments of its block.
            std::size_t e = i + 1;
            while (e < pj.step_segments.size() && pj.step_segments[e].block == s.block) ++e;
            bool last_motion = true;
            for (std::size_t n = e; n < pj.step_segments.size(); ++n)
                if (pj.step_segments[n].kind != MotionKind::dwell) last_motion = false;
            const ConicArcInput in = arc_input(pj, job.blocks[s.block], i, e, pos, last_motion, m);
            std::variant<std::vector<ConicPiece>, std::string> pieces = std::string("the card has no conic walker");
            ConicArcStats arc_stats;
            if (conics) pieces = plan_conic_arc(in, m, &arc_stats);
            if (auto* list = std::get_if<std::vector<ConicPiece>>(&pieces)) {
                const double first = list->front().walk->ideal.front();
                if (first - tol < double(last_conic_event) + double(conic_gap_cycles(m.card.conic_width)))
                    pieces = std::string("its first move comes too soon after the conic before it");
            }
            if (auto* list = std::get_if<std::vector<ConicPiece>>(&pieces)) {
                if (!pause_before(list->front().walk->ideal.front())) return result;
                auto source = std::make_shared<ArcSource>(ArcSource{*in.block, i, e, in.start, in.last_motion});
                for (std::size_t p = 0; p < list->size(); ++p) {
                    ConicPiece& piece = (*list)[p];
                    const std::int64_t before = prev;
                    auto chunks = compress(piece.walk->ideal, prev, tol, lim);
                    if (!chunks.ok()) {
                        result.errors.push_back({job.file, s.loc, fmt::format("timing: {}", chunks.error)});
                        return result;
                    }
                    prev = chunks.last_event;
                    pj.stats.moves += piece.segment.moves;
                    pj.stats.chunks += chunks.chunks.size();
                    ++pj.stats.conic_segments;
                    for (int a = 0; a < kAxes; ++a) pos[a] += piece.segment.delta[a];
                    PlannedCardSegment& c = pj.card.emplace_back(
                        PlannedCardSegment{piece.segment, std::move(chunks.chunks), std::move(piece.walk)});
                    c.prev_event = before;
                    c.step_moves = piece.segment.moves;
                    c.arc = source;
                    c.arc_piece = p;
                    if (!emit(c)) return result;
                }
                last_conic_event = prev;
                ++pj.stats.conic_arcs;
                pj.stats.conic.max_node_deviation =
                    std::max(pj.stats.conic.max_node_deviation, arc_stats.max_node_deviation);
                pj.stats.conic.max_other_deviation =
                    std::max(pj.stats.conic.max_other_deviation, arc_stats.max_other_deviation);
                // The chords' step segments stay as the feed plan's record: they
                // make no card segment of their own.
                for (std::size_t c = i; c < e; ++c) pj.step_segments[c].conic = true;
                i = e - 1;
                dwell_first = kNone;
                dwell_s = 0;
                continue;
            }
            ++pj.stats.chord_arcs;
            chords_until = e;
            if (conics)
                result.warnings.push_back({job.file, s.loc,
                                           "arc sent as chords: " + std::get<std::string>(pieces)});
        }
        s.start = pos;  // after a conic, where its walk ended
        auto split = reduce_segment(s.delta(), m.card.pattern_capacity, m.planner.split_epsilon_steps);
        pj.stats.worst_split_error = std::max(pj.stats.worst_split_error, split.deviation_bound - 0.5);
        std::uint64_t total = 0;
        for (const auto& part : split.parts) total += part.moves;
        for (auto& part : split.parts) {
            part.loc = s.loc;
            part.step_segment = i;
            const auto ideal = ideal_move_times(pj.feeds[i], total, part.first_move, part.moves,
                                                m.card.clock_hz);
            if (!ideal.empty() && !pause_before(ideal.front())) return result;
            const std::int64_t before = prev;
            auto chunks = compress(ideal, prev, tol, lim);
            if (!chunks.ok()) {
                result.errors.push_back({job.file, s.loc, fmt::format("timing: {}", chunks.error)});
                return result;
            }
            prev = chunks.last_event;
            pj.stats.moves += part.moves;
            pj.stats.chunks += chunks.chunks.size();
            for (int a = 0; a < kAxes; ++a) pos[a] += part.delta[a];
            PlannedCardSegment& c = pj.card.emplace_back(PlannedCardSegment{part, std::move(chunks.chunks), nullptr});
            c.prev_event = before;
            c.step_moves = total;
            if (!emit(c)) return result;
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
    pj.stats.fit = fit;
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
            if (job.card[c].conic) {
                out.insert(out.end(), job.card[c].conic->ideal.begin(), job.card[c].conic->ideal.end());
                continue;
            }
            const auto t = ideal_move_times(job.feeds[step_segment], total, part.first_move,
                                            part.moves, clock_hz);
            out.insert(out.end(), t.begin(), t.end());
        }
    }
    return out;
}

}  // namespace cpstep::plan

namespace cpstep::plan {

RebuiltCardSegment rebuild_card_segment(const PlannedJob& job, std::size_t s, const Machine& m) {
    const PlannedCardSegment& c = job.card.at(s);
    const ChunkLimits& lim = job.chunk_limits;
    const double tol = m.chunk_tolerance_cycles();
    RebuiltCardSegment out;
    std::vector<double> ideal;
    if (c.segment.pause) {
        ideal = pause_times(c.prev_event, c.pause_until, c.segment.moves);
    } else if (c.arc) {
        const ArcSource& a = *c.arc;
        auto pieces = plan_conic_arc(arc_input(job, a.block, a.first, a.end, a.start, a.last_motion, m), m);
        auto* list = std::get_if<std::vector<ConicPiece>>(&pieces);
        if (!list || c.arc_piece >= list->size())
            throw std::logic_error(fmt::format("rebuild_card_segment: card segment {}: its arc is not walked again", s));
        out.conic = std::move((*list)[c.arc_piece].walk);
        ideal = out.conic->ideal;
    } else {
        ideal = ideal_move_times(job.feeds.at(c.segment.step_segment), c.step_moves, c.segment.first_move,
                                 c.segment.moves, m.card.clock_hz);
    }
    auto chunks = compress(ideal, c.prev_event, tol, lim);
    if (!chunks.ok())
        throw std::logic_error(fmt::format("rebuild_card_segment: card segment {}: {}", s, chunks.error));
    out.chunks = std::move(chunks.chunks);
    return out;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/pipeline.h"

#include <algorithm>

#include <cmath>
#include <deque>
#include <limits>
#include <span>
#include <stdexcept>
#include <variant>

#include <fmt/format.h>

#include "plan/arc_fit.h"
#include "plan/chunks.h"
#include "plan/steptime.h"
#include "plan/window.h"

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

// What plan_conic_arc() takes for the arc of the given chords and feeds
// (step segments [first, first + chords.size())).
ConicArcInput arc_input(const MotionBlock& block, std::span<const StepSegment> chords,
                        std::span<const PlannedSegment> feeds, std::size_t first, const PerAxis<std::int64_t>& start,
                        bool last_motion, const Machine& m) {
    ConicArcInput in;
    in.block = &block;
    in.chords = chords;
    in.feeds = feeds;
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

// The most pause moves one pause may take (a dwell longer than one move
// interval: docs/PLANNING.md "Dwells"): a chunk's count.
constexpr std::uint64_t kMaxPauseMoves = 65535;

// Equal intervals, each under 2^32 - 1 cycles, that make up `cycles`.
std::uint64_t intervals(double cycles) {
    return static_cast<std::uint64_t>(std::floor(cycles / double(kMaxMoveDelayCycles))) + 1;
}

}  // namespace

struct PlanStream::Impl {
    const Machine& m;
    std::string file;
    ChunkLimits lim;
    double tol;
    std::function<void(std::span<const double>, std::span<const double>, double, std::span<const PlanJerk>)>
        on_move_times;
    std::function<void(std::span<const double>)> on_pause_times;
    double arc_path_done = 0;   // on_move_times: the path length of the arc's pieces so far
    bool conic_length_rule = false;
    double rule_unit_mm = 0;       // conic_rule_unit_mm
    std::vector<double> rule_at;   // conic_length_rule: the arc's moves' path positions (mm)
    std::vector<double> rule_len;  // ... and lengths (mm), exact for the card (rule_unit_mm)
    std::uint32_t rule_word = 0;   // ... the arc's {S, K} (rule_unit_mm)
    std::size_t rule_next = 0;     // the next move's in rule_at
    double rule_last_time = 0;     // the last rule-timed move's time (cycles)
    StepSegmenter segmenter;
    FeedPlanner feeds;
    std::vector<Diagnostic> loop_warnings, loop_errors, time_errors;
    double limit_s = 0;
    PlanStats stats;
    bool finished = false;
    bool ended = false;  // the card loop reached the job's end

    // Step segments made and not yet through the card loop, with their feeds
    // as the feed planner hands them out (feed_end: feeds known for [.., feed_end)).
    detail::Window<StepSegment> segs;
    detail::Window<PlannedSegment> plan;
    std::size_t feed_end = 0;
    // The blocks of arcs whose chords are not yet through the loop (what
    // plan_conic_arc() walks), by their index.
    std::deque<std::pair<std::size_t, MotionBlock>> arc_blocks;

    // Made, not yet handed out.
    std::deque<StreamedStep> steps_out;
    std::deque<PlannedCardSegment> cards_out;
    std::uint64_t cards_made = 0;

    // The card loop (plan_job()'s comments).
    std::size_t i = 0;  // the next step segment
    std::int64_t prev = 0;  // the job starts at cycle 0
    static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::size_t dwell_first = kNone;
    SourceLoc dwell_loc;
    double dwell_s = 0;
    PerAxis<std::int64_t> pos{};
    bool have_pos = false;
    std::int64_t last_conic_event = std::numeric_limits<std::int64_t>::min() / 2;
    bool conics = false;
    std::size_t chords_until = 0;
    double end_s = 0;  // the end of the last motion's feed

    Impl(const Machine& machine, std::string job_file, const PlanOptions& options)
        : m(machine),
          file(std::move(job_file)),
          lim(job_chunk_limits(machine, options)),
          tol(machine.chunk_tolerance_cycles()),
          on_move_times(options.on_move_times),
          on_pause_times(options.on_pause_times),
          conic_length_rule(options.conic_length_rule),
          rule_unit_mm(options.conic_rule_unit_mm),
          segmenter(machine, file),
          feeds(machine, file) {
        conics = m.planner.arcs == ArcMode::conic && m.card.conic_width > 0;
        limit_s = std::ldexp(1.0, 62) / m.card.clock_hz;
    }

    // on_move_times: a feed's jerk changes, absolute clocks.
    void jerk_changes(const PlannedSegment& f, std::vector<PlanJerk>& out) const {
        for (const Phase& ph : f.profile.phases)
            if (ph.duration > 0) out.push_back({(f.t_start + ph.t0) * m.card.clock_hz, ph.jerk, ph.v0, ph.a0});
    }

    [[nodiscard]] bool failed() const {
        return !segmenter.errors().empty() || !feeds.errors().empty() || !time_errors.empty() || !loop_errors.empty();
    }

    // Step segments to the feed planner, feeds to the loop.
    void pump() {
        while (auto s = segmenter.next()) {
            feeds.push(*s);
            segs.push_back(std::move(*s));
        }
        if (finished && segmenter.done()) feeds.finish();
        while (time_errors.empty()) {
            auto f = feeds.next();
            if (!f) break;
            // The card's time is counted in cycles from the job start (64-bit on
            // the host): a job that would run past 2^62 of them (some 3,000 years
            // at 48 MHz: a dwell or a feed no machine means) is refused where it
            // passes that, before the card loop times it.
            if (!(f->t_start + f->duration <= limit_s)) {
                time_errors.push_back({file, segs[feed_end].loc,
                                       fmt::format("the job would last past {:.3g} s here (2^62 cycles of the card's "
                                                   "{:g} Hz clock): a dwell or feed no job can run",
                                                   limit_s, m.card.clock_hz)});
                break;
            }
            plan.push_back(std::move(*f));
            ++feed_end;
        }
    }

    // Step segment s done with (after the loop set where it starts): handed out.
    void done_with(std::size_t s) { steps_out.push_back({s, segs[s], plan[s]}); }

    void card(PlannedCardSegment&& c) {
        cards_out.push_back(std::move(c));
        ++cards_made;
    }

    // Pause moves from `prev` to cycle `until`, in `n` equal steps of at most
    // 2^32 - 1 cycles (the last at `until`), as one card segment of their own.
    bool add_pause(double until, std::uint64_t n, double pause_cycles) {
        // At most kMaxPauseMoves of them: a longer pause (the dwells from
        // dwell_loc on, together) is refused before its moves are made.
        if (n > kMaxPauseMoves) {
            const double longest = double(kMaxPauseMoves + 1) * double(kMaxMoveDelayCycles) / m.card.clock_hz;
            loop_errors.push_back(
                {file, dwell_loc,
                 fmt::format("a pause of {:.6g} s (the dwells from here to the next move) is longer than the "
                             "card times: at most {} pause moves of 2^32 - 1 cycles and the move after them, "
                             "{:.6g} s at its {:g} Hz clock",
                             pause_cycles / m.card.clock_hz, kMaxPauseMoves,
                             longest, m.card.clock_hz)});
            return false;
        }
        const std::vector<double> times = pause_times(prev, until, n);
        if (on_pause_times) on_pause_times(times);
        auto chunks = compress(times, prev, tol, lim);
        if (!chunks.ok()) {
            loop_errors.push_back({file, dwell_loc, fmt::format("pause timing: {}", chunks.error)});
            return false;
        }
        const std::int64_t before = prev;
        CardSegment pause;
        pause.moves = static_cast<std::uint32_t>(n);
        pause.u.fill(1);
        pause.dir_positive.fill(true);
        pause.loc = dwell_loc;
        pause.step_segment = dwell_first;
        pause.pause = true;
        prev = chunks.last_event;
        stats.pause_moves += n;
        stats.chunks += chunks.chunks.size();
        PlannedCardSegment c{pause, std::move(chunks.chunks), nullptr};
        c.prev_event = before;
        c.step_moves = n;
        card(std::move(c));
        return true;
    }

    // A pause before the move at `first_ideal` when it is further than one
    // interval can time.
    bool pause_before(double first_ideal) {
        if (dwell_first != kNone && first_ideal - double(prev) > double(kMaxMoveDelayCycles)) {
            // Longer than one interval: pause moves split the gap, the move
            // after them times the last part (each at most 2^32 - 1 cycles).
            const double gap = first_ideal - double(prev);
            const std::uint64_t parts = intervals(gap);
            return add_pause(double(prev) + gap * double(parts - 1) / double(parts), parts - 1, gap);
        }
        return true;
    }

    // The card loop, as far as the step segments and feeds made allow.
    void run() {
        while (!failed() && !ended) {
            const bool all_made = finished && segmenter.done() && feeds.done();
            if (i >= feed_end) {
                if (all_made) end();
                return;
            }
            StepSegment& s = segs[i];
            if (!have_pos) {
                pos = s.start;  // where the first step segment starts
                have_pos = true;
            }
            if (s.kind == MotionKind::dwell) {  // a pause shows as a longer first interval
                if (dwell_first == kNone) {
                    dwell_first = i;
                    dwell_loc = s.loc;
                }
                dwell_s += s.dwell_s;
                s.start = s.end = pos;
                done_with(i++);
                continue;
            }
            const bool arc = s.kind == MotionKind::arc_cw || s.kind == MotionKind::arc_ccw;
            if (arc && m.planner.arcs == ArcMode::conic && i >= chords_until) {
                // The arc's chords: the step segments of its block (all made
                // once a segment of another block is, or the job has ended).
                std::size_t e = i + 1;
                while (e < segs.end() && segs[e].block == s.block) ++e;
                if (e == segs.end() && !(finished && segmenter.done())) return;
                if (e > feed_end) return;
                // No motion after it: known at the next step segment that moves.
                bool last_motion = true, known = false;
                for (std::size_t n = e; n < segs.end(); ++n) {
                    if (segs[n].kind != MotionKind::dwell) {
                        last_motion = false;
                        known = true;
                        break;
                    }
                }
                if (!known && !(finished && segmenter.done())) return;
                if (!arc_segment(e, last_motion)) return;
                continue;
            }
            if (!line_segment()) return;
        }
    }

    // Step segments [i, e): one arc, walked by the card as a conic or sent as chords.
    bool arc_segment(std::size_t e, bool last_motion) {
        StepSegment& s = segs[i];
        while (!arc_blocks.empty() && arc_blocks.front().first < s.block) arc_blocks.pop_front();
        if (arc_blocks.empty() || arc_blocks.front().first != s.block)
            throw std::logic_error("plan stream: an arc's block was not kept");
        const MotionBlock& block = arc_blocks.front().second;
        std::vector<StepSegment> chords;
        std::vector<PlannedSegment> chord_feeds;
        for (std::size_t c = i; c < e; ++c) {
            chords.push_back(segs[c]);
            chord_feeds.push_back(plan[c]);
        }
        const ConicArcInput in = arc_input(block, chords, chord_feeds, i, pos, last_motion, m);
        std::variant<std::vector<ConicPiece>, std::string> pieces = std::string("the card has no conic walker");
        ConicArcStats arc_stats;
        if (conics) pieces = plan_conic_arc(in, m, &arc_stats);
        if (auto* list = std::get_if<std::vector<ConicPiece>>(&pieces)) {
            const double first = list->front().walk->ideal.front();
            if (first - tol < double(last_conic_event) + double(conic_gap_cycles(m.card.conic_width)))
                pieces = std::string("its first move comes too soon after the conic before it");
        }
        if (auto* list = std::get_if<std::vector<ConicPiece>>(&pieces)) {
            if (!pause_before(list->front().walk->ideal.front())) return false;
            for (std::size_t p = 0; p < list->size(); ++p) {
                ConicPiece& piece = (*list)[p];
                const std::int64_t before = prev;
                if (on_move_times) {
                    // Each move's length along the arc: the path's position at its
                    // ideal time by the chords' feeds.
                    auto path_at = [&](double cycles) {
                        const double t = cycles / m.card.clock_hz;
                        double done_mm = 0;
                        for (const PlannedSegment& f : in.feeds) {
                            if (t <= f.t_start + f.duration || &f == &in.feeds.back())
                                return done_mm + f.profile.at(std::clamp(t - f.t_start, 0.0, f.duration)).s;
                            done_mm += f.length;
                        }
                        return done_mm;
                    };
                    std::vector<double> lengths;
                    double last = p == 0 ? 0.0 : arc_path_done;
                    std::span<const double> ideal = piece.walk->ideal;
                    std::vector<double> rule_ideal;
                    if (conic_length_rule) {
                        if (p == 0 && !rule_positions(*list, in.feeds, s.loc)) return false;   // before any piece's walk is handed on
                        for (std::size_t n = 0; n < piece.walk->ideal.size(); ++n) {
                            const double here = rule_at[rule_next++];
                            const double t = time_at(in.feeds, here);
                            stats.conic_rule_shift_cycles =
                                std::max(stats.conic_rule_shift_cycles, std::abs(t - piece.walk->ideal[n]));
                            const double true_here = path_at(piece.walk->ideal[n]);
                            stats.conic_rule_shift_steps = std::max(
                                stats.conic_rule_shift_steps,
                                std::abs(here - true_here) * m.axes[std::size_t(piece.walk->axis_u)].steps_per_mm);
                            if (!rule_ideal.empty() || rule_next > 1)
                                stats.conic_rule_min_gap_cycles =
                                    std::min(stats.conic_rule_min_gap_cycles, t - rule_last_time);
                            rule_last_time = t;
                            rule_ideal.push_back(t);
                            lengths.push_back(rule_len[rule_next - 1]);
                            last = here;
                        }
                        ideal = rule_ideal;
                        if (rule_unit_mm > 0) {
                            // The card times them so: the plan's times for the rule's
                            // positions are the walk's (PlanStats::conic_rule_shift_*
                            // keep how far they are from the true curve's).
                            auto timed = std::make_shared<ConicWalk>(*piece.walk);
                            timed->ideal = rule_ideal;
                            piece.walk = std::move(timed);
                            ideal = piece.walk->ideal;
                        }
                    } else {
                        for (double c : piece.walk->ideal) {
                            const double here = path_at(c);
                            lengths.push_back(here - last);
                            last = here;
                        }
                    }
                    arc_path_done = last;
                    std::vector<PlanJerk> changes;
                    if (p == 0)
                        for (const PlannedSegment& f : in.feeds) jerk_changes(f, changes);
                    on_move_times(ideal, lengths,
                                  p == 0 && in.feeds.front().profile.v_entry == 0
                                      ? in.feeds.front().t_start * m.card.clock_hz
                                      : -1.0,
                                  changes);
                }
                auto chunks = compress(piece.walk->ideal, prev, tol, lim);
                if (!chunks.ok()) {
                    loop_errors.push_back({file, s.loc, fmt::format("timing: {}", chunks.error)});
                    return false;
                }
                prev = chunks.last_event;
                stats.moves += piece.segment.moves;
                stats.chunks += chunks.chunks.size();
                ++stats.conic_segments;
                for (int a = 0; a < kAxes; ++a) pos[a] += piece.segment.delta[a];
                PlannedCardSegment c{piece.segment, std::move(chunks.chunks), std::move(piece.walk)};
                c.rule_word = conic_length_rule ? rule_word : 0;
                c.prev_event = before;
                c.step_moves = piece.segment.moves;
                card(std::move(c));
            }
            last_conic_event = prev;
            ++stats.conic_arcs;
            stats.conic.max_node_deviation = std::max(stats.conic.max_node_deviation, arc_stats.max_node_deviation);
            stats.conic.max_other_deviation =
                std::max(stats.conic.max_other_deviation, arc_stats.max_other_deviation);
            // The chords' step segments stay as the feed plan's record: they
            // make no card segment of their own.
            for (std::size_t c = i; c < e; ++c) {
                segs[c].conic = true;
                end_s = plan[c].t_start + plan[c].duration;
                done_with(c);
            }
            i = e;
            dwell_first = kNone;
            dwell_s = 0;
            return true;
        }
        ++stats.chord_arcs;
        chords_until = e;
        if (conics) loop_warnings.push_back({file, s.loc, "arc sent as chords: " + std::get<std::string>(pieces)});
        return line_segment();
    }

    // conic_length_rule: every move of the arc's pieces at its position along the
    // arc's path (mm), move n's length K 2^S / m_n (plan::conic_rule_divisors), K
    // such that the last move ends the arc's path, as the feeds plan it: in real
    // numbers, or (rule_unit_mm) exactly as the card divides (plan::conic_rule_lengths;
    // an error when the rule cannot measure the arc).
    bool rule_positions(const std::vector<ConicPiece>& pieces, std::span<const PlannedSegment> arc_feeds,
                        const SourceLoc& loc) {
        double total = 0;
        for (const PlannedSegment& f : arc_feeds) total += f.length;
        std::vector<std::uint64_t> divisors;
        for (const ConicPiece& piece : pieces)
            for (std::uint64_t d : conic_rule_divisors(*piece.walk)) divisors.push_back(d);
        rule_at.clear();
        rule_len.clear();
        rule_next = 0;
        if (rule_unit_mm > 0) {
            const double unit = std::ldexp(rule_unit_mm, -30);
            auto lengths = conic_rule_lengths(divisors, total / unit);
            if (auto* e = std::get_if<std::string>(&lengths)) {
                loop_errors.push_back({file, loc, "arc as a conic on a phase-timer card: " + *e});
                return false;
            }
            const ConicRuleLengths& rl = std::get<ConicRuleLengths>(lengths);
            rule_word = rl.word;
            std::uint64_t acc = 0;   // (exact: 2^30 units of path per unit, sums under 2^64)
            for (std::uint32_t l : rl.lengths) {
                acc += l;
                rule_at.push_back(double(acc) * unit);
                rule_len.push_back(double(l) * unit);
            }
            return true;
        }
        std::vector<double> w;
        for (std::uint64_t d : divisors) w.push_back(1.0 / double(std::max<std::uint64_t>(d, 1)));
        double sum = 0;
        for (double x : w) sum += x;
        double acc = 0;
        for (double x : w) {
            acc += x;
            rule_at.push_back(total * acc / sum);
        }
        if (!rule_at.empty()) rule_at.back() = total;
        double last = 0;
        for (double x : rule_at) {
            rule_len.push_back(x - last);
            last = x;
        }
        return true;
    }
    // The card cycle at which the feeds reach `s` mm along the arc's path.
    [[nodiscard]] double time_at(std::span<const PlannedSegment> arc_feeds, double s) const {
        double done = 0;
        for (const PlannedSegment& f : arc_feeds) {
            if (s <= done + f.length || &f == &arc_feeds.back())
                return (f.t_start + f.profile.time_at(std::clamp(s - done, 0.0, f.length))) * m.card.clock_hz;
            done += f.length;
        }
        return 0;
    }

    // Step segment i as card segments: its parts of at most the pattern capacity.
    bool line_segment() {
        StepSegment& s = segs[i];
        s.start = pos;  // after a conic, where its walk ended
        auto split = reduce_segment(s.delta(), m.card.pattern_capacity, m.planner.split_epsilon_steps);
        stats.worst_split_error = std::max(stats.worst_split_error, split.deviation_bound - 0.5);
        std::uint64_t total = 0;
        for (const auto& part : split.parts) total += part.moves;
        for (auto& part : split.parts) {
            part.loc = s.loc;
            part.step_segment = i;
            const auto ideal = ideal_move_times(plan[i], total, part.first_move, part.moves, m.card.clock_hz);
            if (!ideal.empty() && !pause_before(ideal.front())) return false;
            const std::int64_t before = prev;
            if (on_move_times) {
                const std::vector<double> lengths(ideal.size(), plan[i].length / double(total));
                std::vector<PlanJerk> changes;
                if (part.first_move == 0) jerk_changes(plan[i], changes);
                on_move_times(ideal, lengths,
                              part.first_move == 0 && plan[i].profile.v_entry == 0 ? plan[i].t_start * m.card.clock_hz
                                                                                 : -1.0,
                              changes);
            }
            auto chunks = compress(ideal, prev, tol, lim);
            if (!chunks.ok()) {
                loop_errors.push_back({file, s.loc, fmt::format("timing: {}", chunks.error)});
                return false;
            }
            prev = chunks.last_event;
            stats.moves += part.moves;
            stats.chunks += chunks.chunks.size();
            for (int a = 0; a < kAxes; ++a) pos[a] += part.delta[a];
            PlannedCardSegment c{part, std::move(chunks.chunks), nullptr};
            c.prev_event = before;
            c.step_moves = total;
            card(std::move(c));
        }
        end_s = plan[i].t_start + plan[i].duration;
        dwell_first = kNone;
        dwell_s = 0;
        done_with(i++);
        return true;
    }

    // The job ends with its last move, or with the dwells after it: pause moves
    // up to their end (the card runs until the last one).
    void end() {
        ended = true;
        if (dwell_first != kNone && dwell_s > 0) {
            const double until = double(prev) + dwell_s * m.card.clock_hz;
            if (!add_pause(until, intervals(until - double(prev)), until - double(prev))) return;
            end_s = double(prev) / m.card.clock_hz;
        }
        stats.step_segments = i;
        stats.card_segments = cards_made;
        stats.duration_s = end_s;
    }

    void advance() {
        pump();
        run();
        // What the loop no longer reads: step segments before the next, arcs'
        // blocks before its block.
        // (Step segments come in the order of their blocks.)
        const std::size_t block = i < segs.end() ? segs[i].block : i > 0 ? segs[i - 1].block : 0;
        while (!arc_blocks.empty() && arc_blocks.front().first < block) arc_blocks.pop_front();
        segs.drop_before(i > 0 ? i - 1 : 0);
        plan.drop_before(i);
    }
};

PlanStream::PlanStream(const Machine& m, std::string job_file, const PlanOptions& options)
    : impl_(std::make_unique<Impl>(m, std::move(job_file), options)) {}
PlanStream::~PlanStream() = default;
PlanStream::PlanStream(PlanStream&&) noexcept = default;
PlanStream& PlanStream::operator=(PlanStream&&) noexcept = default;

void PlanStream::push(const MotionBlock& block, std::size_t index) {
    Impl& p = *impl_;
    if (p.finished) throw std::logic_error("PlanStream::push after finish");
    if ((block.kind == MotionKind::arc_cw || block.kind == MotionKind::arc_ccw) && p.m.planner.arcs == ArcMode::conic)
        p.arc_blocks.emplace_back(index, block);
    p.segmenter.push(block, index);
    p.advance();
}

void PlanStream::finish() {
    Impl& p = *impl_;
    if (p.finished) return;
    p.finished = true;
    p.segmenter.finish();
    p.advance();
}

std::optional<StreamedStep> PlanStream::next_step() {
    Impl& p = *impl_;
    if (p.steps_out.empty()) return std::nullopt;
    std::optional<StreamedStep> s = std::move(p.steps_out.front());
    p.steps_out.pop_front();
    return s;
}

std::optional<PlannedCardSegment> PlanStream::next_card() {
    Impl& p = *impl_;
    if (p.cards_out.empty() || !p.steps_out.empty()) return std::nullopt;
    std::optional<PlannedCardSegment> c = std::move(p.cards_out.front());
    p.cards_out.pop_front();
    return c;
}

bool PlanStream::done() const { return impl_->ended && !impl_->failed(); }

std::vector<Diagnostic> PlanStream::warnings() const {
    std::vector<Diagnostic> w = impl_->feeds.warnings();
    w.insert(w.end(), impl_->loop_warnings.begin(), impl_->loop_warnings.end());
    return w;
}

std::vector<Diagnostic> PlanStream::errors() const {
    // The first stage's that has any: the step segments', the feed plan's, a
    // job past the card's time, the card loop's (plan_job() made each stage
    // whole before the next, so an earlier stage's errors are the job's).
    if (!impl_->segmenter.errors().empty()) return impl_->segmenter.errors();
    if (!impl_->feeds.errors().empty()) return impl_->feeds.errors();
    if (!impl_->time_errors.empty()) return impl_->time_errors;
    return impl_->loop_errors;
}

bool PlanStream::refused_before_the_card_loop() const {
    return !impl_->segmenter.errors().empty() || !impl_->feeds.errors().empty() || !impl_->time_errors.empty();
}

const PlanStats& PlanStream::stats() const { return impl_->stats; }
const ChunkLimits& PlanStream::chunk_limits() const { return impl_->lim; }
std::size_t PlanStream::held() const {
    return impl_->segs.held() + impl_->feeds.held() + impl_->segmenter.held_points() + impl_->steps_out.size() +
           impl_->cards_out.size();
}

Result<PlannedJob> plan_job(const Job& given, const Machine& m, const PlanOptions& options) {
    Result<PlannedJob> result;
    // Chains of G1 lines as arcs where the machine file asks (plan/arc_fit.h): the
    // rest of the plan is of the fitted job.
    ArcFitStats fit;
    Job fitted;
    const ArcFitTolerances fit_tol = arc_fit_tolerances(m);
    if (fit_tol.any()) fitted = fit_arcs(given, fit_tol, &fit);
    const Job& job = fit_tol.any() ? fitted : given;
    if (!(m.card.clock_hz > 0)) {
        result.errors.push_back({m.file, {}, "no card clock: the machine file gives no [card] clock_hz and no "
                                             "card was asked (plan::bind_card())"});
        return result;
    }
    PlanStream stream(m, job.file, options);
    PlannedJob pj;
    // About a step segment and a card segment a block (a hint: arcs make more).
    pj.step_segments.reserve(job.blocks.size());
    pj.feeds.reserve(job.blocks.size());
    pj.card.reserve(job.blocks.size());
    pj.chunk_limits = stream.chunk_limits();
    const auto drain = [&] {
        for (;;) {
            while (auto s = stream.next_step()) {
                pj.step_segments.push_back(std::move(s->segment));
                pj.feeds.push_back(std::move(s->feed));
            }
            auto c = stream.next_card();
            if (!c) return;
            pj.card.push_back(std::move(*c));
        }
    };
    for (std::size_t b = 0; b < job.blocks.size(); ++b) {
        stream.push(job.blocks[b], b);
        drain();
    }
    stream.finish();
    drain();
    result.warnings = stream.warnings();
    if (!stream.errors().empty()) {
        result.errors = stream.errors();
        return result;
    }
    pj.stats = stream.stats();
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

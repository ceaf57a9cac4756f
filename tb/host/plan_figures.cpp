// SPDX-License-Identifier: MIT
// Measurements quoted in docs/PLANNING.md (not a test).
//   plan_figures chunks MACHINE JOB [BOARD F]  moves per chunk with and without add2 (the card's
//                                     chunk form; on BOARD, with F fractional bits in add and add2)
//   plan_figures split                worst split deviation, exhaustive + random
//   plan_figures bounds MACHINE JOB   planned time beside the lower bound (whole job and its
//                                     feed moves), groups, lookahead, windowed - whole-job time
//   plan_figures speed MACHINE JOB [reps]  planning throughput, G-code lines per second
//   plan_figures phases MACHINE JOB BOARD S F [UNIT [noreload] [greedy] [rule]] | wire MACHINE JOB BOARD [FIT_ARCS_MM]  moves timed by phases
//                                     of constant jerk (plan/phases.h): ticks of 2^S clocks, F
//                                     fractional bits, the path in UNIT mm (0: moves); without
//                                     reloads; the greedy fit alone (not the plan's phases)
#include <cstdio>
#include <numeric>
#include <random>
#include <string>

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <fstream>

#include <malloc.h>

#include "card/caps.h"
#include "card/job.h"
#include "card/ptimer_job.h"
#include "card/protocol.h"
#include "cpstep/builds.h"
#include "plan/phases.h"
#include "plan/pipeline.h"
#include "plan/steptime.h"
#include "run/card_job.h"

using namespace cpstep::plan;

namespace {

// The machine file bound to the default board's card (rtl/builds.json), as
// `cpstep plan` does when it asks no card.
Result<Machine> load_bound(const char* path, const char* board = nullptr) {
    auto m = load_machine(path);
    if (!m.ok()) return m;
    const cpstep::builds::Build& b = *cpstep::builds::find(board ? board : cpstep::builds::kDefaultBoard);
    CardFacts facts{std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw};
    if (b.conic) facts.conic_width = 40;   // the walker's width (READ 0x26)
    m.errors = bind_card(*m.value, facts);
    return m;
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Planning throughput, stage by stage, best of `reps` runs.
int speed(const char* mpath, const char* jpath, int reps) {
    auto m = load_bound(mpath);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    std::ifstream f(jpath);
    std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::size_t lines = 0;
    for (char c : text) lines += c == '\n';
    double best_parse = 1e9, best_segs = 1e9, best_feeds = 1e9, best_total = 1e9;
    double duration = 0;
    for (int r = 0; r < reps; ++r) {
        auto t0 = Clock::now();
        auto job = parse_gcode(text, jpath);
        best_parse = std::min(best_parse, since(t0));
        auto t1 = Clock::now();
        auto segs = make_step_segments(*job, *m);
        best_segs = std::min(best_segs, since(t1));
        auto t2 = Clock::now();
        auto feeds = plan_feeds(*segs.value, *m, jpath);
        best_feeds = std::min(best_feeds, since(t2));
        auto t3 = Clock::now();
        auto p = plan_job(*job, *m);
        best_total = std::min(best_total, since(t3) + since(t0) - since(t1));
        if (!p.ok()) { fmt::print(stderr, "{}\n", join(p.errors)); return 1; }
        duration = p->stats.duration_s;
    }
    fmt::print("{} {}: {} lines, planned {:.3f} s; parse {:.4f} s, segments {:.4f} s, feeds {:.4f} s, "
               "parse + plan_job {:.4f} s = {:.0f} lines/s\n",
               mpath, jpath, lines, duration, best_parse, best_segs, best_feeds, best_total,
               static_cast<double>(lines) / best_total);
    return 0;
}

int chunks(const char* mpath, const char* jpath, const char* board = nullptr, unsigned frac = 0) {
    auto m = load_bound(mpath, board);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    auto job = load_gcode(jpath, gcode_options(*m));  // the machine's tool lengths, G28 positions
    if (!job.ok()) {
        fmt::print(stderr, "{}\n", join(job.errors));
        return 1;
    }
    for (bool add2 : {false, true}) {
        PlanOptions o;
        o.add2_from_machine = false;
        o.chunk_limits.add_min = INT16_MIN;
        o.chunk_limits.add_max = INT16_MAX;
        o.chunk_limits.monotone = true;
        o.chunk_limits.enable_add2 = add2;
        if (frac) {
            o.chunk_limits.frac_bits = frac;
            o.chunk_limits.max_count = 4095;
            o.chunk_limits.add_min = std::int64_t{INT16_MIN} << frac;   // the whole-cycle range
            o.chunk_limits.add_max = std::int64_t{INT16_MAX} << frac;
            o.chunk_limits.add2_min = -(std::int64_t{512} << frac);   // +-512 cycles
            o.chunk_limits.add2_max = (std::int64_t{512} << frac) - 1;
            o.chunk_limits.monotone = true;
        }
        auto p = plan_job(*job, *m, o);
        if (!p.ok()) {
            fmt::print(stderr, "{}\n", join(p.errors));
            return 1;
        }
        const auto& s = p->stats;
        fmt::print("{} {} add2={}: step_segments={} card_segments={} moves={} chunks={} "
                   "moves/chunk={:.2f} duration={:.3f}s worst_split_error={:.4f}\n",
                   mpath, jpath, add2 ? "on" : "off", s.step_segments, s.card_segments, s.moves,
                   s.chunks, s.moves_per_chunk(), s.duration_s, s.worst_split_error);
    }
    return 0;
}

// Moves timed by phases of constant jerk (plan/phases.h): phases, rests and the
// registers' ranges for the job on BOARD, ticks of 2^S clocks, F fractional bits.
int phases(const char* mpath, const char* jpath, const char* board, unsigned s, unsigned f, double unit_mm,
           bool reload, bool plan_jerk, bool rule) {
    auto m = load_bound(mpath, board);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    auto job = load_gcode(jpath, gcode_options(*m));
    if (!job.ok()) { fmt::print(stderr, "{}\n", join(job.errors)); return 1; }
    PhaseFormat format;
    format.tick_log2 = s;
    format.frac_bits = f;
    format.path_unit_mm = unit_mm;
    format.reload = reload;
    format.clock_hz = m->card.clock_hz;
    format.plan_jerk = plan_jerk;
    PhaseFitter fitter(format, m->chunk_tolerance_cycles());
    std::uint64_t batches = 0;
    PlanOptions o;
    o.conic_length_rule = rule;
    o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths, double rest_at,
                          std::span<const PlanJerk> changes) {
        ++batches;
        fitter.push(ideal, lengths, rest_at, changes);
    };
    auto p = plan_job(*job, *m, o);
    if (!p.ok()) { fmt::print(stderr, "{}\n", join(p.errors)); return 1; }
    if (!fitter.finish()) { fmt::print(stderr, "{}: {}\n", jpath, fitter.error()); return 1; }
    const PhaseStats& st = fitter.stats();
    // Bytes in rtl/cp_ptimer.v's words: W0 and u (8), V and H (16 more), p (8 more);
    // a timed move W0 alone.
    const std::uint64_t bytes = 8 * (st.phases - st.timed) + 16 * (st.adjusts + st.reloads) + 8 * st.reloads + 4 * st.timed;
    fmt::print("{} {} s={} F={} unit={}: bytes={} conic_segments={} card_segments={} moves={} chunks={} phases={} plan_phases={} adjusts={} (max 2^{:.1f}) rests={} reloads={} timed={} moves/phase={:.1f} "
               "max_ticks={} max|j|={} (2^{:.1f}) max|a|=2^{:.1f} max_v=2^{:.1f} max_phase_moves={}\n",
               jpath, board, s, f, unit_mm, bytes, p->stats.conic_segments, p->stats.card_segments, st.moves, p->stats.chunks, st.phases, st.plan_phases, st.adjusts, std::log2(double(std::max<std::int64_t>(1, st.max_abs_adjust))), st.rests, st.reloads, st.timed,
               double(st.moves) / double(std::max<std::uint64_t>(1, st.phases)), st.max_ticks, st.max_abs_jerk,
               std::log2(double(std::max<std::int64_t>(1, st.max_abs_jerk))),
               std::log2(double(std::max<std::int64_t>(1, st.max_abs_accel))),
               std::log2(double(std::max<std::int64_t>(1, st.max_velocity))), st.max_phase_moves);
    if (rule)
        fmt::print("conic length rule: moves shifted by up to {:.1f} cycles ({:.3f} us), {:.4f} steps along the path; "
                   "moves at least {:.1f} cycles apart (the walker needs {})\n",
                   p->stats.conic_rule_shift_cycles, p->stats.conic_rule_shift_cycles / m->card.clock_hz * 1e6,
                   p->stats.conic_rule_shift_steps, p->stats.conic_rule_min_gap_cycles,
                   conic_gap_cycles(m->card.conic_width));
    return 0;
}

// A projection for the compact wire (issue 13), not a wire the card takes: every
// example job's bytes if each card segment's header were sent in a compact form
// and its moves timed by phases of constant jerk (rtl/cp_ptimer.v's words, the
// conics' moves by the length rule, plan::conic_rule_divisors) instead of chunks.
// The compact header of a wire segment (split at UMAX only: no chunk queue to fill):
//   H0, 4 bytes: opcode, end, torch, k, CONIC's cw, continuation and plane axes,
//       a mask of the axes that step, their directions, which of them has v = U;
//   U, then v_i of every other axis that steps: each an unsigned LEB128 varint;
//   a line's length per move, or a whole conic's K (the rule's constant), 4 bytes;
//   a whole conic's A, B, C, G, Gx, Gy, and any conic's du, dv: zigzag varints.
// The setup words (CONFIG, START, ...) are counted as today.
std::size_t varint_bytes(std::uint64_t x) {
    std::size_t n = 1;
    while (x >= 0x80) x >>= 7, ++n;
    return n;
}
std::size_t zigzag_bytes(std::int64_t x) { return varint_bytes(x < 0 ? (std::uint64_t(-(x + 1)) << 1) | 1 : std::uint64_t(x) << 1); }

std::size_t compact_header_bytes(const cpstep::card::WireSegment& w) {
    std::size_t b = 4 + varint_bytes(w.u);
    bool major_skipped = false, steps = false;
    for (std::uint32_t v : w.v) {
        if (v == 0) continue;
        steps = true;
        if (v == w.u && !major_skipped) { major_skipped = true; continue; }
        b += varint_bytes(v);
    }
    if (w.conic) {
        const auto& k = w.conic->words;
        const auto s24 = [](std::uint32_t x) { return std::int64_t(std::int32_t(x << 8) >> 8); };
        if (!w.conic->cont) {
            b += 4;   // K
            b += zigzag_bytes(std::int16_t(k[0] & 0xFFFF)) + zigzag_bytes(std::int16_t(k[0] >> 16)) +
                 zigzag_bytes(std::int16_t(k[1] & 0xFFFF));
            b += zigzag_bytes(std::int32_t(k[2])) + zigzag_bytes(std::int32_t(k[3])) + zigzag_bytes(std::int32_t(k[4]));
        }
        b += zigzag_bytes(s24(k[5])) + zigzag_bytes(s24(k[6]));
    } else if (steps) {
        b += 4;   // the length per move
    }
    return b;
}

int wire(const char* mpath, const char* jpath, const char* board, double fit_arcs_mm) {
    namespace card = cpstep::card;
    const auto caps = card::board_caps(board);
    if (!caps) { fmt::print(stderr, "no board {}\n", board); return 1; }
    auto m = cpstep::run::load_card_machine(mpath, *caps);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    if (fit_arcs_mm > 0) m.value->planner.fit_arcs_mm = fit_arcs_mm;
    auto job = cpstep::run::read_card_gcode(jpath, *m);
    if (!job.ok()) { fmt::print(stderr, "{}\n", join(job.errors)); return 1; }
    // Today's wire: every command word.
    auto cj = cpstep::run::plan_card_job(*job, *m, *caps);
    if (!cj.ok()) { fmt::print(stderr, "{}\n", join(cj.errors)); return 1; }
    std::size_t segment_words = 0;
    for (const card::WireSegment& w : cj->wire.segments) {
        std::vector<std::uint32_t> words;
        card::encode_segment(w, words);
        segment_words += words.size();
    }
    const std::size_t setup_bytes = 4 * (cj->words.size() - segment_words);
    // The compact headers: the planned card segments cut at UMAX only.
    card::CardLimits lim = card::limits(*caps);
    lim.chunk_queue = 1u << 30;
    std::size_t header_bytes = 0, wire_segments = 0;
    const auto& pj = cj->planned;
    for (std::size_t s = 0; s < pj.card.size(); ++s) {
        std::vector<card::WireSegment> out;
        if (auto d = card::to_wire_segment(pj, s, pj.card[s].chunks, pj.card[s].conic.get(), jpath, lim, out)) {
            fmt::print(stderr, "{}\n", d->message);
            return 1;
        }
        for (const card::WireSegment& w : out) header_bytes += compact_header_bytes(w);
        wire_segments += out.size();
    }
    // The phases: the same plan with the hook, conics by the length rule.
    PhaseFormat format;
    format.path_unit_mm = 0.0125;
    format.clock_hz = m->card.clock_hz;
    PhaseFitter fitter(format, m->chunk_tolerance_cycles());
    PlanOptions o;
    o.chunk_limits = card::chunk_limits(card::limits(*caps));
    o.conic_length_rule = true;
    o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths, double rest_at,
                          std::span<const PlanJerk> changes) { fitter.push(ideal, lengths, rest_at, changes); };
    auto p = plan_job(*job, *m, o);
    if (!p.ok()) { fmt::print(stderr, "{}\n", join(p.errors)); return 1; }
    if (!fitter.finish()) { fmt::print(stderr, "{}: {}\n", jpath, fitter.error()); return 1; }
    const PhaseStats& st = fitter.stats();
    const std::uint64_t phase_bytes =
        8 * (st.phases - st.timed) + 16 * (st.adjusts + st.reloads) + 8 * st.reloads + 4 * st.timed;
    fmt::print("{} {}{}: today {} bytes ({} wire segments); projected: setup {} + headers {} ({} segments, "
               "{:.1f} bytes each) + phases {} ({}) = {} bytes\n",
               jpath, board, fit_arcs_mm > 0 ? fmt::format(" fit_arcs_mm={}", fit_arcs_mm) : std::string(),
               4 * cj->words.size(), cj->wire.segments.size(), setup_bytes, header_bytes, wire_segments,
               double(header_bytes) / double(std::max<std::size_t>(1, wire_segments)), phase_bytes, st.phases,
               setup_bytes + header_bytes + phase_bytes);
    return 0;
}

// The wire a phase-timer card takes today (card::plan_phase_timer_job: arcs as chords,
// the segments in the compact axis form, the phases' words), measured, not projected:
// the setup words (CONFIG and the rest before the first command), then the segments'
// and the phases' bytes, against the same segments with every axis sent and with
// chunks. A job the card cannot time yet (pause moves) says why.
int ptimer(const char* mpath, const char* jpath, const char* board) {
    namespace card = cpstep::card;
    const auto caps = card::board_caps(board);
    if (!caps) { fmt::print(stderr, "no board {}\n", board); return 1; }
    auto m = cpstep::run::load_card_machine(mpath, *caps);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    m.value->planner.arcs = ArcMode::chords;
    auto job = cpstep::run::read_card_gcode(jpath, *m);
    if (!job.ok()) { fmt::print(stderr, "{}\n", join(job.errors)); return 1; }
    auto pj = card::plan_phase_timer_job(*job, *m, card::limits(*caps), jpath);
    if (!pj.ok()) { fmt::print("{} {}: {}\n", jpath, board, join(pj.errors)); return 0; }
    fmt::print("{} {}: {} moves; setup {} + segments {} ({}, {:.1f} bytes each; every axis sent {}, with chunks {}) "
               "+ phases {} ({}) = {} bytes\n",
               jpath, board, pj->fire_half_clocks.size(), 4 * pj->preamble.size() + 4, pj->segment_bytes,
               pj->segments, double(pj->segment_bytes) / double(std::max<std::size_t>(1, pj->segments)),
               pj->every_axis_bytes, pj->chunked_bytes, pj->bytes - pj->segment_bytes, pj->phases,
               4 * pj->preamble.size() + 4 + pj->bytes);
    return 0;
}

int split() {
    // Exhaustive: 2 axes, every T <= 300 and 0 <= D <= T, W in {4, 16, 64}.
    for (std::uint32_t W : {4u, 16u, 64u}) {
        double worst = 0, worst_ep = 0;
        std::uint64_t parts = 0, segs = 0;
        for (std::int64_t T = 1; T <= 300; ++T) {
            for (std::int64_t D = 0; D <= T; ++D) {
                const PerAxis<std::int64_t> d{T, D, 0, 0};
                auto r = reduce_segment(d, W, 0.02);
                worst = std::max(worst, max_deviation(d, r.parts) - 0.5);
                worst_ep = std::max(worst_ep, r.endpoint_error);
                parts += r.parts.size();
                ++segs;
            }
        }
        fmt::print("exhaustive 2-axis T<=300 W={}: worst deviation 0.5 + {:.4f} steps "
                   "(worst split-point error {:.4f}), {:.2f} parts/segment\n",
                   W, worst, worst_ep, static_cast<double>(parts) / static_cast<double>(segs));
    }
    // Random: 2 or 4 axes, |d| up to 2^19, W = 1024 (the default), 3 minor axes.
    for (int axes : {2, 4}) {
        std::mt19937_64 rng(1);
        double worst = 0;
        std::uint64_t parts = 0, split_segs = 0;
        const int N = 40;
        for (int k = 0; k < N; ++k) {
            PerAxis<std::int64_t> d{};
            for (int a = 0; a < axes; ++a) {
                d[static_cast<std::size_t>(a)] = static_cast<std::int64_t>(rng() % (1 << 20)) - (1 << 19);
            }
            auto r = reduce_segment(d, 1024, 0.02);
            worst = std::max(worst, max_deviation(d, r.parts) - 0.5);
            parts += r.parts.size();
            split_segs += r.parts.size() > 1;
        }
        fmt::print("random {}-axis |d|<2^19 W=1024 ({} segments, {} split): worst deviation "
                   "0.5 + {:.4f} steps, {:.1f} parts/segment\n",
                   axes, N, split_segs, worst, static_cast<double>(parts) / N);
    }
    return 0;
}

// Planned time beside the lower bound, for one machine and job.
int bounds(const char* mpath, const char* jpath) {
    auto m = load_bound(mpath);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    auto job = load_gcode(jpath, gcode_options(*m));  // the machine's tool lengths, G28 positions
    if (!job.ok()) {
        fmt::print(stderr, "{}\n", join(job.errors));
        return 1;
    }
    auto segs = make_step_segments(*job, *m);
    FeedStats st;
    auto feeds = plan_feeds(*segs.value, *m, jpath, {}, &st);
    if (!feeds.ok()) { fmt::print(stderr, "{}\n", join(feeds.errors)); return 1; }
    const double planned = feeds->back().t_start + feeds->back().duration;
    const double lb = time_lower_bound(*segs.value, *m);
    // The feed moves: from the first to the last G1/G2/G3/G5.x segment.
    std::size_t first = segs->size(), last = 0;
    for (std::size_t i = 0; i < segs->size(); ++i) {
        const auto k = (*segs.value)[i].kind;
        if (k == MotionKind::linear || k == MotionKind::arc_cw || k == MotionKind::arc_ccw ||
            k == MotionKind::nurbs) {
            first = std::min(first, i);
            last = i + 1;
        }
    }
    const auto& fd = *feeds.value;
    const double fplanned = first < last ? fd[last - 1].t_start + fd[last - 1].duration - fd[first].t_start : 0;
    const double flb = first < last ? time_lower_bound(*segs.value, *m, first, last) : 0;
    // The same job planned in one window (the whole job at once).
    FeedOptions whole;
    whole.window_stop_factor = std::numeric_limits<double>::infinity();
    whole.max_lookahead_s = std::numeric_limits<double>::infinity();
    auto wf = plan_feeds(*segs.value, *m, jpath, whole);
    const double wplanned = wf->back().t_start + wf->back().duration;
    fmt::print("| {} | {} | {} | {:.3f} s | {:.3f} s | {:.3f} | {:.3f} s | {:.3f} s | {:.3f} | {} | {:.1f} mm, {:.2f} s | {:+.1e} s |\n",
               mpath, jpath, segs->size(), planned, lb, planned / lb, fplanned, flb,
               flb > 0 ? fplanned / flb : 0.0, st.groups, st.max_lookahead_mm, st.max_lookahead_s,
               planned - wplanned);
    if (std::getenv("PLAN_FIGURES_DETAIL")) {
        // Planned time and bound-speed time per radius band (diagnostics).
        std::map<int, std::array<double, 3>> band;
        for (std::size_t i = 0; i < segs->size(); ++i) {
            const auto& s = (*segs.value)[i];
            const auto& f = (*feeds.value)[i];
            const int b = std::isfinite(s.radius_mm) ? static_cast<int>(std::floor(std::log2(s.radius_mm))) : 99;
            band[b][0] += f.duration;
            band[b][1] += f.length;
            band[b][2] += f.length / std::max(1e-9, f.cruise);
        }
        for (auto& [b, v] : band) fmt::print("  r 2^{}: planned {:.3f} s, {:.1f} mm, at cap {:.3f} s\n", b, v[0], v[1], v[2]);
    }
    return 0;
}

// A fingerprint of the step segments and the feed plan: FNV-1a over every
// step segment's and planned segment's bits, the feed statistics and the warnings (for checking that a change of the
// planner's code leaves its plans bit for bit as they were).
int fingerprint(const char* mpath, const char* jpath) {
    const char* board = std::getenv("PLAN_FIGURES_BOARD");  // the default board unless set
    auto m = load_bound(mpath, board && *board ? board : nullptr);
    if (!m.ok()) { fmt::print(stderr, "{}\n", join(m.errors)); return 1; }
    auto job = load_gcode(jpath, gcode_options(*m));
    if (!job.ok()) { fmt::print(stderr, "{}\n", join(job.errors)); return 1; }
    auto segs = make_step_segments(*job, *m);
    if (!segs.ok()) { fmt::print(stderr, "{}\n", join(segs.errors)); return 1; }
    std::uint64_t h = 1469598103934665603ULL;
    const auto mix = [&](const void* p, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i) {
            h ^= static_cast<const unsigned char*>(p)[i];
            h *= 1099511628211ULL;
        }
    };
    const auto num = [&](double x) { mix(&x, sizeof x); };
    for (const StepSegment& s : *segs.value) {
        mix(s.start.data(), sizeof s.start);
        mix(s.end.data(), sizeof s.end);
        mix(&s.block, sizeof s.block);
        for (double x : {s.feed, s.dwell_s, s.radius_mm, s.radius_ends_max_mm, s.radius_start_mm}) num(x);
        for (double x : s.from_mm) num(x);
        for (double x : s.to_mm) num(x);
        const int flags = int(s.kind) * 4 + s.spindle_on * 2 + s.torch;
        mix(&flags, sizeof flags);
    }
    FeedStats st;
    auto feeds = plan_feeds(*segs.value, *m, jpath, {}, &st);
    for (const auto& w : feeds.warnings) mix(w.message.data(), w.message.size());
    for (const auto& e : feeds.errors) mix(e.message.data(), e.message.size());
    if (feeds.ok()) {
        for (const PlannedSegment& f : *feeds.value) {
            for (double x : {f.length, f.radius, f.t_start, f.duration, f.cruise, f.limits.v, f.limits.a, f.limits.j,
                             f.profile.length, f.profile.v_entry, f.profile.v_exit, f.profile.v_peak,
                             f.profile.duration})
                num(x);
            for (const Phase& ph : f.profile.phases)
                for (double x : {ph.duration, ph.jerk, ph.t0, ph.s0, ph.v0, ph.a0}) num(x);
        }
    }
    for (std::size_t x : {st.spans, st.groups, st.windows, st.backward_steps, st.max_lookahead_spans}) mix(&x, sizeof x);
    num(st.max_lookahead_mm);
    num(st.max_lookahead_s);
    // The whole plan: its step segments after the card loop, card segments,
    // chunks, walks and statistics.
    auto pj = plan_job(*job, *m);
    for (const auto& w : pj.warnings) mix(w.message.data(), w.message.size());
    for (const auto& e : pj.errors) mix(e.message.data(), e.message.size());
    std::size_t cards = 0;
    if (pj.ok()) {
        for (const StepSegment& s : pj->step_segments) {
            mix(s.start.data(), sizeof s.start);
            mix(s.end.data(), sizeof s.end);
            const int conic = s.conic;
            mix(&conic, sizeof conic);
        }
        for (const PlannedSegment& f : pj->feeds) num(f.t_start);
        for (const PlannedCardSegment& c : pj->card) {
            const CardSegment& g = c.segment;
            const std::uint64_t ints[] = {std::uint64_t(g.major), g.moves, g.first_move, g.step_segment,
                                          std::uint64_t(g.pause), std::uint64_t(c.prev_event), c.step_moves,
                                          std::uint64_t(g.loc.line)};
            mix(ints, sizeof ints);
            for (std::size_t a = 0; a < kAxes; ++a) {
                const std::int64_t per[] = {g.dir_positive[a], g.u[a], g.v[a], g.delta[a]};
                mix(per, sizeof per);
            }
            for (const Chunk& k : c.chunks) mix(&k, sizeof k);
            if (c.conic) {
                mix(c.conic->moves.data(), c.conic->moves.size());
                for (double t : c.conic->ideal) num(t);
            }
        }
        const PlanStats& ps = pj->stats;
        const std::uint64_t counts[] = {ps.moves, ps.pause_moves, ps.chunks, ps.step_segments, ps.card_segments,
                                        ps.conic_arcs, ps.conic_segments, ps.chord_arcs};
        mix(counts, sizeof counts);
        for (double x : {ps.worst_split_error, ps.duration_s, ps.conic.max_node_deviation, ps.conic.max_other_deviation})
            num(x);
        cards = pj->card.size();
    }
    fmt::print("{} {} {} segments, {} warnings, {} errors; {} card segments, {} warnings, {} errors: {:016x}\n", mpath,
               jpath, segs->size(), feeds.warnings.size(), feeds.errors.size(), cards, pj.warnings.size(),
               pj.errors.size(), h);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    // The speed figures are planning's: memory freed between repetitions stays
    // in the process (glibc's defaults hand a freed top of the heap and large
    // blocks back to the system, and the next repetition faults them in again:
    // some 13 us a page on the machine docs/BENCHMARKS.md names, more than the
    // streaming feed planner's own time on dense.ngc).
    mallopt(M_MMAP_THRESHOLD, 64 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
    const std::string cmd = argc > 1 ? argv[1] : "";
    if (cmd == "chunks" && argc == 4) return chunks(argv[2], argv[3]);
    if (cmd == "chunks" && argc == 6) return chunks(argv[2], argv[3], argv[4], unsigned(std::atoi(argv[5])));
    if (cmd == "split") return split();
    if (cmd == "phases" && argc >= 7) {
        bool reload = true, plan_jerk = true, rule = false;
        for (int a = 8; a < argc; ++a) {
            reload = reload && std::string(argv[a]) != "noreload";
            plan_jerk = plan_jerk && std::string(argv[a]) != "greedy";
            rule = rule || std::string(argv[a]) == "rule";
        }
        return phases(argv[2], argv[3], argv[4], unsigned(std::atoi(argv[5])), unsigned(std::atoi(argv[6])),
                      argc >= 8 ? std::atof(argv[7]) : 0.0, reload, plan_jerk, rule);
    }
    if (cmd == "wire" && argc >= 5) return wire(argv[2], argv[3], argv[4], argc >= 6 ? std::atof(argv[5]) : 0.0);
    if (cmd == "ptimer" && argc == 5) return ptimer(argv[2], argv[3], argv[4]);
    if (cmd == "bounds" && argc == 4) return bounds(argv[2], argv[3]);
    if (cmd == "fingerprint" && argc == 4) return fingerprint(argv[2], argv[3]);
    if (cmd == "speed" && argc >= 4) return speed(argv[2], argv[3], argc > 4 ? std::atoi(argv[4]) : 5);
    fmt::print(stderr, "usage: plan_figures chunks MACHINE JOB | split | bounds MACHINE JOB | speed MACHINE JOB [reps] | fingerprint MACHINE JOB | phases MACHINE JOB BOARD S F [UNIT [noreload] [greedy] [rule]] | wire MACHINE JOB BOARD [FIT_ARCS_MM] | ptimer MACHINE JOB BOARD\n");
    return 2;
}

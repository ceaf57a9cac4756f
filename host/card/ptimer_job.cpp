// SPDX-License-Identifier: MIT
#include "card/ptimer_job.h"

#include <algorithm>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "card/protocol.h"
#include "plan/conic_arc.h"
#include "plan/phases.h"

namespace cpstep::card {

namespace {

constexpr uint64_t kPhaseTicksMax = (uint64_t{1} << 24) - 1;
// A pause segment's length per move: the path, which stands still, never reaches
// it; each of its moves is a timed move (plan::PhaseFitter::push_pause).
constexpr uint32_t kPauseLength = 0xFFFFFFFFu;

// A phase's length in the timer's half clocks (2^6 of them a tick; a timed move's in clocks).
int64_t phase_half_clocks(const plan::TimerPhase& ph) {
  const int64_t t = ph.ticks == 0 ? 1 : int64_t(ph.ticks);
  return ph.timed ? t : t << 6;
}

}  // namespace

plan::Result<PhaseTimerJob> plan_phase_timer_job(const plan::Job& job, const plan::Machine& machine,
                                                 const CardLimits& limits, const std::string& file) {
  plan::Result<PhaseTimerJob> r;
  const auto fail = [&](std::string message) {
    r.errors.push_back({file, {}, std::move(message)});
    r.value.reset();
    return r;
  };
  // The timer counts half clocks (rtl/cp_run.v, PTIMER): every time in them.
  plan::PhaseFormat fmt{6, 60, true, false, 0.0125};
  fmt.clock_hz = machine.card.clock_hz / 2;
  fmt.length_bits = 30;  // the segment word L: Q2.30 of the path unit
  plan::PhaseFitter fitter(fmt, machine.chunk_tolerance_cycles() / 2);
  // Per timed batch (a card segment): its first move's L, or none when its moves
  // differ (a conic's, whose L word is its arc's {S, K}; a line's must be one).
  std::vector<std::optional<uint32_t>> lengths;
  std::string hook_error;
  plan::PlanOptions o;
  // The chunks are not sent (to_wire checks them): no chunk queue to fill, so no
  // segment is cut to fit one (a conic goes whole, cut only where U would not fit).
  CardLimits unqueued = limits;
  unqueued.chunk_queue = 1u << 30;
  o.chunk_limits = chunk_limits(unqueued);
  // Conics (where the machine file and the card have them): each move's length by the
  // rule the card's walker applies, exactly (rtl/cp_conic_serial.v LEN).
  o.conic_length_rule = true;
  o.conic_rule_unit_mm = fmt.path_unit_mm;
  o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                        std::span<const plan::PlanJerk> changes) {
    if (!hook_error.empty()) return;
    std::vector<double> half(ideal.begin(), ideal.end());
    for (double& t : half) t /= 2;
    std::vector<plan::PlanJerk> ch(changes.begin(), changes.end());
    for (plan::PlanJerk& c : ch) c.at /= 2;
    const plan::i128 l = plan::move_length(lengths_mm.front(), fmt) >> 30;
    bool one = l > 0 && l < (plan::i128(1) << 32);
    for (double x : lengths_mm) one = one && (plan::move_length(x, fmt) >> 30) == l;
    lengths.push_back(one ? std::optional<uint32_t>(uint32_t(l)) : std::nullopt);
    if (!fitter.push(half, lengths_mm, rest_at < 0 ? rest_at : rest_at / 2, ch)) hook_error = fitter.error();
  };
  // A pause's moves (v all 0): timed moves at their clocks, rests between (one
  // batch each, with no length: its segment's L is kPauseLength).
  o.on_pause_times = [&](std::span<const double> ideal) {
    if (!hook_error.empty()) return;
    std::vector<double> half(ideal.begin(), ideal.end());
    for (double& t : half) t /= 2;
    lengths.push_back(std::nullopt);
    if (!fitter.push_pause(half)) hook_error = fitter.error();
  };
  auto planned = plan::plan_job(job, machine, o);
  r.warnings = planned.warnings;
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  if (!hook_error.empty()) return fail(hook_error);
  if (!fitter.finish()) return fail(fitter.error());
  auto wired = to_wire(*planned, file, unqueued);
  if (!wired.ok()) {
    r.errors = wired.errors;
    return r;
  }
  PhaseTimerJob& out = r.value.emplace();
  out.fire_half_clocks = fitter.fire_clocks();
  WireJob& wire = *wired.value;
  // Each wire segment's length per move is its planned card segment's (a batch each).
  std::vector<uint64_t> first_move;  // per wire segment: its first move's index
  uint64_t moves = 0;
  for (size_t i = 0; i < wire.segments.size(); ++i) {
    WireSegment& s = wire.segments[i];
    const size_t c = wire.source[i];
    if (c >= lengths.size()) return fail(fmt::format("card segment {} has no length per move", c));
    if (planned->card[c].segment.pause) {
      s.length = kPauseLength;
    } else if (planned->card[c].conic) {
      s.length = planned->card[c].rule_word;
    } else if (lengths[c]) {
      s.length = *lengths[c];
    } else {
      return fail(fmt::format("card segment {}: its moves are not of one length that fits the 32-bit L word", c));
    }
    first_move.push_back(moves);
    moves += uint64_t(s.u) << s.k;
    for (size_t a = 0; a < out.end.size() && a < s.v.size(); ++a)
      out.end[a] += (s.dir_positive[a] ? 1 : -1) * int64_t(uint64_t(s.v[a]) << s.k);
    if (s.conic) {   // the plane's axes step by the walk: its end minus its start (K5, K6)
      const auto s24 = [](uint32_t w) { return int64_t(int32_t(w << 8) >> 8); };
      if (s.conic->axis_u < out.end.size()) out.end[s.conic->axis_u] += s24(s.conic->words[5]);
      if (s.conic->axis_v < out.end.size()) out.end[s.conic->axis_v] += s24(s.conic->words[6]);
    }
  }
  if (moves != out.fire_half_clocks.size())
    return fail(fmt::format("{} moves on the wire, {} timed", moves, out.fire_half_clocks.size()));
  // The card hands its timer a move's length the clock after the move before fires
  // (rtl/cp_run.v): no move may be due in that clock.
  for (size_t n = 1; n < out.fire_half_clocks.size(); ++n)
    if (out.fire_half_clocks[n] <= out.fire_half_clocks[n - 1])
      return fail(fmt::format("moves {} and {} are due {} clocks apart: the card needs 2 at least", n, n + 1,
                              2 * (out.fire_half_clocks[n] - out.fire_half_clocks[n - 1])));
  // A conic's moves come from the walker, each after its pass and its length's
  // division (docs/CORE.md "Phase-timer builds"): each must be due that long after
  // the conic move before it, a walk's first also after its words.
  {
    const unsigned ciw = machine.card.conic_width;
    bool have = false;
    int64_t last = 0;
    for (size_t i = 0; i < wire.segments.size(); ++i) {
      const WireSegment& s = wire.segments[i];
      if (!s.conic) continue;
      const unsigned shift = *s.length >> 27;
      const uint64_t n = uint64_t(s.u) << s.k;
      for (uint64_t j = 0; j < n; ++j) {
        const int64_t at = 2 * out.fire_half_clocks[first_move[i] + j];
        const int64_t gap = j == 0 ? int64_t(plan::conic_gap_cycles(ciw)) + conic_division_cycles(shift)
                                   : conic_move_gap_cycles(ciw, shift);
        if (have && at - last < gap)
          return fail(fmt::format("an arc's move comes {} clocks after the one before it, sooner than the card's "
                                  "walker gives it ({}): plan arcs as chords ([planner] arcs)",
                                  at - last, gap));
        have = true;
        last = at;
      }
    }
  }
  if (wire.segments.empty()) return fail("no motion");
  wire.segments.back().end = true;

  encode_preamble(machine, 0, out.preamble);
  // Phases and segments by the time each begins (a phase first at a tie).
  std::vector<std::pair<int64_t, std::vector<uint32_t>>> timed;
  int64_t t = 0;
  for (const plan::TimerPhase& ph : fitter.phases()) {
    // W0[23:0] holds the ticks (a timed move's clocks), 0 meaning 1: a longer phase
    // would run short on the card.
    if (ph.ticks > kPhaseTicksMax)
      return fail(fmt::format("phase {}: {} ticks do not fit the PHASE word's 24-bit field", out.phases, ph.ticks));
    std::vector<uint32_t> w;
    encode_phase(wire_phase(ph), w);
    timed.push_back({2 * t, std::move(w)});
    t += phase_half_clocks(ph);
    out.phase_end_half_clocks.push_back(t);
    ++out.phases;
  }
  for (size_t i = 0; i < wire.segments.size(); ++i) {
    WireSegment chunked = wire.segments[i];
    chunked.length.reset();
    std::vector<uint32_t> cw, ew, w;
    encode_segment(chunked, cw);
    out.chunked_bytes += 4 * cw.size();
    encode_segment(wire.segments[i], ew, true);
    out.every_axis_bytes += 4 * ew.size();
    encode_segment(wire.segments[i], w);
    out.segment_bytes += 4 * w.size();
    timed.push_back({2 * out.fire_half_clocks[first_move[i]] + 1, std::move(w)});
    ++out.segments;
  }
  std::stable_sort(timed.begin(), timed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [when, w] : timed) {
    out.bytes += 4 * w.size();
    if (out.start_after == 0 && (w[0] >> 28) != 6) out.start_after = out.commands.size() + 1;
    out.commands.push_back(std::move(w));
  }
  out.planned = std::move(*planned.value);
  out.wire = std::move(wire);
  return r;
}

}  // namespace cpstep::card

// SPDX-License-Identifier: MIT
#include "card/ptimer_job.h"

#include <algorithm>
#include <utility>

#include <fmt/format.h>

#include "card/protocol.h"
#include "plan/phases.h"

namespace cpstep::card {

namespace {

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
  if (machine.planner.arcs != plan::ArcMode::chords)
    return fail("a phase-timer card does not time a conic's moves yet: plan arcs as chords ([planner] arcs)");

  // The timer counts half clocks (rtl/cp_run.v, PTIMER): every time in them.
  plan::PhaseFormat fmt{6, 60, true, false, 0.0125};
  fmt.clock_hz = machine.card.clock_hz / 2;
  fmt.length_bits = 30;  // the segment word L: Q2.30 of the path unit
  plan::PhaseFitter fitter(fmt, machine.chunk_tolerance_cycles() / 2);
  std::vector<uint32_t> lengths;  // per timed batch (a card segment): its L
  std::string hook_error;
  plan::PlanOptions o;
  o.chunk_limits = chunk_limits(limits);  // (the chunks are not sent; to_wire checks them)
  o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                        std::span<const plan::PlanJerk> changes) {
    if (!hook_error.empty()) return;
    std::vector<double> half(ideal.begin(), ideal.end());
    for (double& t : half) t /= 2;
    std::vector<plan::PlanJerk> ch(changes.begin(), changes.end());
    for (plan::PlanJerk& c : ch) c.at /= 2;
    const plan::i128 l = plan::move_length(lengths_mm.front(), fmt) >> 30;
    if (!(l > 0 && l < (plan::i128(1) << 32))) {
      hook_error = fmt::format("card segment {}: its length per move, {} mm, does not fit the 32-bit L word",
                               lengths.size(), lengths_mm.front());
      return;
    }
    for (double x : lengths_mm)
      if ((plan::move_length(x, fmt) >> 30) != l) {
        hook_error = fmt::format("card segment {}: its moves are not of one length", lengths.size());
        return;
      }
    lengths.push_back(uint32_t(l));
    if (!fitter.push(half, lengths_mm, rest_at < 0 ? rest_at : rest_at / 2, ch)) hook_error = fitter.error();
  };
  auto planned = plan::plan_job(job, machine, o);
  r.warnings = planned.warnings;
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  if (!hook_error.empty()) return fail(hook_error);
  if (!fitter.finish()) return fail(fitter.error());
  auto wired = to_wire(*planned, file, limits);
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
    if (planned->card[c].segment.pause) return fail("a phase-timer card does not take pauses (dwells, M0) yet");
    if (c >= lengths.size()) return fail(fmt::format("card segment {} has no length per move", c));
    s.length = lengths[c];
    first_move.push_back(moves);
    moves += uint64_t(s.u) << s.k;
    for (size_t a = 0; a < out.end.size() && a < s.v.size(); ++a)
      out.end[a] += (s.dir_positive[a] ? 1 : -1) * int64_t(uint64_t(s.v[a]) << s.k);
  }
  if (moves != out.fire_half_clocks.size())
    return fail(fmt::format("{} moves on the wire, {} timed", moves, out.fire_half_clocks.size()));
  if (wire.segments.empty()) return fail("no motion");
  wire.segments.back().end = true;

  encode_preamble(machine, 0, out.preamble);
  // Phases and segments by the time each begins (a phase first at a tie).
  std::vector<std::pair<int64_t, std::vector<uint32_t>>> timed;
  int64_t t = 0;
  for (const plan::TimerPhase& ph : fitter.phases()) {
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

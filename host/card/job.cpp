// SPDX-License-Identifier: MIT
#include "card/job.h"

#include <fmt/format.h>

#include <bit>
#include <optional>
#include <span>
#include <numeric>
#include <stdexcept>

namespace cpstep::card {

CardLimits limits(const CardCaps& c) {
  CardLimits l;
  l.umax = c.umax;
  l.kmax = c.kmax;
  l.w = c.w;
  l.chunk_queue = c.chunk_queue();
  l.segment_queue = c.segment_queue();
  return l;
}

plan::ChunkLimits chunk_limits(const CardLimits&) {
  plan::ChunkLimits l;
  l.max_count = 0xFFFF;
  l.add_min = INT16_MIN;
  l.add_max = INT16_MAX;
  l.add2_min = INT16_MIN;
  l.add2_max = INT16_MAX;
  l.enable_add2 = true;
  l.monotone = true;
  return l;
}

bool in_card_form(const plan::Chunk& c) {
  auto int16 = [](int64_t x) { return x >= INT16_MIN && x <= INT16_MAX; };
  if (c.count < 1 || c.count > 0xFFFF || !int16(c.add) || !int16(c.add2)) return false;
  if (c.count < 3) return true;
  const int64_t last = int64_t(c.add) + int64_t(c.count - 2) * c.add2;
  return int16(last) && !(c.add > 0 && last < 0) && !(c.add < 0 && last > 0);
}

namespace {

plan::Diagnostic error(const std::string& file, const plan::SourceLoc& loc, std::string message) {
  return {file, loc, std::move(message)};
}

// Takes `moves` moves off the front of a chunk list, splitting a chunk where
// the boundary falls inside it (exact: the rest starts at its own next delay,
// interval + n add + add2 n(n-1)/2, with add + n add2: an increment of the chunk,
// so within int16 by in_card_form(); a rest of one move needs neither add).
std::vector<WireChunk> take_moves(std::vector<plan::Chunk>& chunks, size_t& next, uint64_t moves) {
  std::vector<WireChunk> out;
  while (moves > 0) {
    plan::Chunk& c = chunks[next];
    const uint32_t n = uint32_t(std::min<uint64_t>(moves, c.count));
    // (add2 matters from a chunk's third move on, add from its second)
    out.push_back({c.interval, uint16_t(n), int16_t(n > 1 ? c.add : 0), int16_t(n > 2 ? c.add2 : 0)});
    moves -= n;
    if (n == c.count) {
      ++next;
    } else {
      const int64_t nn = n;
      c.interval = uint32_t(int64_t(c.interval) + nn * c.add + int64_t(c.add2) * nn * (nn - 1) / 2);
      c.add = int32_t(int64_t(c.add) + nn * c.add2);
      c.count -= n;
      if (c.count <= 2) c.add2 = 0;
      if (c.count == 1) c.add = 0;
    }
  }
  return out;
}

// Moves covered by at most `limit` chunks from chunks[next] on.
uint64_t moves_in_chunks(const std::vector<plan::Chunk>& chunks, size_t next, size_t limit) {
  uint64_t moves = 0;
  for (size_t c = next; c < chunks.size() && c < next + limit; ++c) moves += chunks[c].count;
  return moves;
}

// The torch's level while a card segment runs: its step segment's (none known: off).
bool torch_of(const plan::PlannedJob& job, const plan::CardSegment& seg) {
  return seg.step_segment < job.step_segments.size() && job.step_segments[seg.step_segment].torch;
}

}  // namespace

std::optional<plan::Diagnostic> to_wire_segment(const plan::PlannedJob& job, size_t s,
                                                std::span<const plan::Chunk> chunks_in, const plan::ConicWalk* conic,
                                                const std::string& file, const CardLimits& card,
                                                std::vector<WireSegment>& out) {
  return to_wire_segment(job.card[s].segment, torch_of(job, job.card[s].segment), chunks_in, conic, file, card, out);
}

std::optional<plan::Diagnostic> to_wire_segment(const plan::CardSegment& seg, bool torch,
                                                std::span<const plan::Chunk> chunks_in, const plan::ConicWalk* conic,
                                                const std::string& file, const CardLimits& card,
                                                std::vector<WireSegment>& out) {
  std::vector<plan::Chunk> chunks(chunks_in.begin(), chunks_in.end());
  for (const plan::Chunk& c : chunks) {
    if (!in_card_form(c)) {
      return error(file, seg.loc, fmt::format("chunk (interval {}, count {}, add {}, "
                                                    "add2 {}) is outside the card's chunk form "
                                                    "(count 1..65535; add, add2 and every "
                                                    "increment add + j*add2 within 16 bits "
                                                    "and of one sign)",
                                                    c.interval, c.count, c.add, c.add2));
    }
  }
  if (conic) {
    // A CONIC: its plane's walk can restart at any node (a new segment with the
    // walker's words there), so a planar one is cut where the chunk queue or
    // UMAX says; one whose other axes step (a helix) has patterns over its whole
    // T (k = 0) and is not cut (the planner makes its pieces fit).
    const plan::ConicWalk& walk = *conic;
    bool planar = true;
    for (int a = 0; a < plan::kAxes; ++a) planar = planar && seg.v[a] == 0;
    plan::ConicWalk rest = walk;
    size_t next_chunk = 0;
    for (uint64_t done = 0; done < seg.moves;) {
      uint64_t n = std::min<uint64_t>(seg.moves - done, card.umax);
      n = std::min(n, moves_in_chunks(chunks, next_chunk, card.chunk_queue));
      if (!planar && n < seg.moves) {
        return error(file, seg.loc, fmt::format("a helix piece of {} moves needs more than the card's "
                                                      "{} timing chunks or {} moves",
                                                      seg.moves, card.chunk_queue, card.umax));
      }
      const plan::ConicWalk piece = n < rest.moves.size() ? rest.head(n) : rest;
      if (n < rest.moves.size()) rest = rest.tail(n);
      WireSegment w;
      w.u = uint32_t(n);
      for (int a = 0; a < plan::kAxes; ++a) {
        w.dir_positive.push_back(seg.delta[a] >= 0);
        w.v.push_back(seg.v[a]);
      }
      w.torch = torch;
      w.chunks = take_moves(chunks, next_chunk, n);
      w.conic = WireSegment::Conic{piece.cw, unsigned(piece.axis_u), unsigned(piece.axis_v), piece.words(),
                                   piece.cont};
      out.push_back(std::move(w));
      done += n;
    }
    return std::nullopt;
  }
  // The patterns repeat every L = lcm(u_i) moves; pieces of whole periods.
  const uint64_t T = seg.moves;
  uint64_t period = 1;
  for (int a = 0; a < plan::kAxes; ++a) period = std::lcm(period, uint64_t(seg.u[a]));
  uint64_t piece = T;
  if (T > card.umax) {
    if (period > card.umax) {
      return error(file, seg.loc, fmt::format("segment of {} moves is longer than the "
                                                    "card's {} and its patterns repeat only "
                                                    "every {} moves",
                                                    T, card.umax, period));
    }
    piece = card.umax / period * period;
  }
  size_t next_chunk = 0;
  for (uint64_t done = 0; done < T;) {
    uint64_t n = std::min(piece, T - done);
    // The card takes a segment only when all its chunks fit its chunk queue
    // at once: cut where the next chunk_queue chunks end, at whole periods.
    const uint64_t fit = moves_in_chunks(chunks, next_chunk, card.chunk_queue);
    if (fit < n) {
      n = fit / period * period;
      if (n == 0) {
        return error(file, seg.loc, fmt::format("segment of {} moves needs more than the "
                                                      "card's {} timing chunks within one pattern "
                                                      "period of {} moves, so it cannot be cut into "
                                                      "segments the card accepts",
                                                      T, card.chunk_queue, period));
      }
    }
    // Whole periods: axis a makes v_a steps every u_a moves.
    std::array<uint64_t, plan::kAxes> d{};
    uint64_t g = n;  // (a pause steps no axis: k from its moves alone)
    for (int a = 0; a < plan::kAxes; ++a) {
      d[a] = uint64_t(seg.v[a]) * (n / seg.u[a]);
      g = std::gcd(g, d[a]);
    }
    const unsigned k = std::min<unsigned>(card.kmax, unsigned(std::countr_zero(g)));
    WireSegment w;
    w.k = k;
    w.u = uint32_t(n >> k);
    for (int a = 0; a < plan::kAxes; ++a) {
      w.dir_positive.push_back(seg.delta[a] >= 0);
      w.v.push_back(uint32_t(d[a] >> k));
    }
    w.torch = torch;
    w.chunks = take_moves(chunks, next_chunk, n);
    out.push_back(std::move(w));
    done += n;
  }
  return std::nullopt;
}

plan::Result<WireJob> to_wire(const plan::PlannedJob& job, const std::string& file,
                              const CardLimits& card) {
  plan::Result<WireJob> r;
  WireJob& out = r.value.emplace();
  for (size_t s = 0; s < job.card.size(); ++s) {
    const size_t before = out.segments.size();
    if (auto e = to_wire_segment(job, s, job.card[s].chunks, job.card[s].conic.get(), file, card, out.segments)) {
      r.errors.push_back(std::move(*e));
      r.value.reset();
      return r;
    }
    out.source.insert(out.source.end(), out.segments.size() - before, s);
  }
  if (!out.segments.empty()) out.segments.back().end = true;
  std::vector<size_t> chunks;
  for (size_t i = 0; i < out.segments.size() && i <= card.segment_queue; ++i) chunks.push_back(out.segments[i].chunks.size());
  out.start_after = start_after(chunks, card);
  return r;
}

WirePhase wire_phase(const plan::TimerPhase& ph) {
  WirePhase w;
  w.kind = unsigned(ph.reload || ph.adjust) << 3 | unsigned(ph.rest) << 2 | unsigned(ph.timed) << 1 |
           unsigned(ph.reload);
  w.ticks = uint32_t(ph.ticks);
  w.u = int32_t(ph.jerk);
  w.r_top = uint64_t(ph.r_top);
  w.s = ph.s;
  w.h = ph.a;
  return w;
}

size_t start_after(std::span<const size_t> chunks, const CardLimits& card) {
  // START once the first segments are queued, before they could fill the card.
  size_t n = 0, queued = 0;
  while (n < chunks.size() && n < card.segment_queue && queued + chunks[n] <= card.chunk_queue) queued += chunks[n++];
  return std::max<size_t>(n, 1);
}

void encode_inputs(const plan::Machine& m, std::vector<uint32_t>& words) {
  // The inputs (a card that has them): the filter, each axis's limit switches (those
  // not wired disabled), the probe's level (docs/CORE.md "Inputs").
  if (!m.card.inputs) return;
  encode_config(0, ConfigField::input_filter, m.inputs.filter_cycles, words);
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = m.axes[a];
    if (!ax.present) continue;
    const auto bits = [](plan::SwitchLevel l, uint32_t high, uint32_t enabled) {
      return (l == plan::SwitchLevel::none ? 0 : enabled) | (l == plan::SwitchLevel::active_low ? 0 : high);
    };
    encode_config(a, ConfigField::limits,
                  bits(ax.limit_min, limit_bits::min_active_high, limit_bits::min_enabled) |
                      bits(ax.limit_max, limit_bits::max_active_high, limit_bits::max_enabled),
                  words);
  }
  encode_config(0, ConfigField::probe, uint32_t(m.inputs.probe_active_high), words);
}

std::vector<uint32_t> encode_job(const plan::Machine& m, const WireJob& job) {
  std::vector<uint32_t> words;
  encode_preamble(m, job.seek, words);
  for (size_t s = 0; s < job.segments.size(); ++s) {
    if (s == job.start_after) encode_control(true, false, false, words);
    encode_segment(job.segments[s], words);
  }
  if (job.start_after >= job.segments.size()) encode_control(true, false, false, words);
  return words;
}

void encode_preamble(const plan::Machine& m, uint32_t seek, std::vector<uint32_t>& words) {
  // Drivers on first: the motors hold while the card is configured and filled.
  encode_drivers(true, words);
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = m.axes[a];
    if (!ax.present) continue;
    encode_config(a, ConfigField::step_high, ax.pulse.step_high, words);
    encode_config(a, ConfigField::step_low, ax.pulse.step_low, words);
    encode_config(a, ConfigField::dir_setup, ax.pulse.dir_setup, words);
    encode_config(a, ConfigField::dir_hold, ax.pulse.dir_hold, words);
    encode_config(a, ConfigField::polarity,
                  uint32_t(ax.step_active_high) | uint32_t(ax.dir_positive_high) << 1, words);
  }
  encode_inputs(m, words);
  if (seek != seek_mode::off) {
    if (!m.card.inputs) throw std::invalid_argument("encode_job: a seek needs a card with inputs");
    encode_config(0, ConfigField::seek, seek, words);
  }
  // The feed ramp (a card that has it; docs/CORE.md "Feed hold and override").
  if (m.card.feed) {
    encode_config(0, ConfigField::feed_tick, m.feed.ramp.tick, words);
  }
}

}  // namespace cpstep::card

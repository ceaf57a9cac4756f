// SPDX-License-Identifier: MIT
#include "run/card_job.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "card/protocol.h"
#include "plan/steptime.h"

namespace cpstep::run {

namespace {

// The cycles from a wire segment's start to its `moves`-th move (all of its
// moves: its duration).
uint64_t chunk_cycles_until(const std::vector<card::WireChunk>& chunks, uint64_t moves) {
  // Move j of a chunk (0-based) comes interval + j add + add2 j (j - 1) / 2
  // cycles after the one before: n moves take n interval + add n(n-1)/2 +
  // add2 n(n-1)(n-2)/6.
  int64_t t = 0;
  for (const card::WireChunk& c : chunks) {
    if (moves == 0) break;
    const auto n = int64_t(std::min<uint64_t>(moves, c.count));
    t += n * int64_t(c.interval) + int64_t(c.add) * (n * (n - 1) / 2) + int64_t(c.add2) * (n * (n - 1) * (n - 2) / 6);
    moves -= uint64_t(n);
  }
  return uint64_t(t);
}

}  // namespace

uint64_t CardJob::conic_segments() const {
  if (streamed) return streamed_conics;
  uint64_t n = 0;
  for (const card::WireSegment& w : wire.segments) n += w.conic.has_value();
  return n;
}

uint64_t CardJob::wire_chunks() const {
  if (streamed) return streamed_chunks;
  uint64_t n = 0;
  for (const card::WireSegment& s : wire.segments) n += s.chunks.size();
  return n;
}

plan::CardFacts card_facts(const card::CardCaps& caps) {
  return {card::card_name(caps), double(caps.clock_hz), caps.w, caps.kmax, caps.tw, caps.umax, caps.ciw, caps.inputs, caps.feed};
}

plan::Result<plan::Machine> load_card_machine(const std::filesystem::path& machine_file,
                                              const card::CardCaps& caps) {
  auto machine = plan::load_machine(machine_file);
  if (machine.ok()) machine.errors = plan::bind_card(*machine.value, card_facts(caps));
  if (!machine.errors.empty()) machine.value.reset();
  return machine;
}

plan::Result<plan::Job> read_card_gcode(const std::filesystem::path& gcode, const plan::Machine& machine,
                                        const plan::PerAxis<int64_t>& start) {
  plan::PerAxis<double> start_mm{};
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = machine.axes[a];
    if (start[a] == 0) continue;
    if (!ax.present) {
      plan::Result<plan::Job> r;
      r.errors.push_back({machine.file, {},
                          fmt::format("the card's axis {} is at {} steps, but the machine has no such axis",
                                      plan::kAxisLetters[a], start[a])});
      return r;
    }
    start_mm[a] = double(start[a]) / ax.steps_per_mm;
  }
  return plan::load_gcode(gcode, plan::gcode_options(machine, start_mm));
}

plan::Result<CardJob> prepare_job(const std::filesystem::path& gcode, const std::filesystem::path& machine_file,
                                  const card::CardCaps& caps, const plan::PerAxis<int64_t>& start, bool streamed) {
  plan::Result<CardJob> r;
  auto machine = load_card_machine(machine_file, caps);
  r.warnings = machine.warnings;
  if (!machine.ok()) {
    r.errors = machine.errors;
    return r;
  }
  auto job = read_card_gcode(gcode, *machine, start);
  r.warnings.insert(r.warnings.end(), job.warnings.begin(), job.warnings.end());
  if (!job.ok()) {
    r.errors = job.errors;
    return r;
  }
  auto planned = plan_card_job(*job, *machine, caps, start, streamed);
  r.warnings.insert(r.warnings.end(), planned.warnings.begin(), planned.warnings.end());
  r.warnings = plan::summarize_repeats(std::move(r.warnings));  // e.g. "feed lowered" once, with a count
  r.errors = std::move(planned.errors);
  if (planned.value) {
    r.value = std::move(planned.value);
    r.value->warnings = r.warnings;
  }
  return r;
}

namespace {

// A streamed job's wire segments as the planner makes its card segments: each
// converted, measured (its words, its chunks' cycles and moves) and kept
// without its chunks but the first (the torch's timing needs it).
// A streamed job's wire segments as the planner makes its card segments: each
// converted, checked and measured (its words, the cycles and moves of its
// chunks, its torch level), then dropped.
struct WireSink {
  card::CardLimits limits;
  std::string file;
  std::vector<uint64_t> words;       // per wire segment: its SEGMENT command's words
  std::vector<uint64_t> end_cycle;   // per wire segment: its end, cycles from START
  std::vector<uint64_t> end_moves;   // per wire segment: moves from START to its end
  std::vector<size_t> first_chunks;  // chunks of the first segment_queue + 1 (start_after)
  std::vector<CardJob::TorchChange> torch;
  uint64_t chunks = 0, cycle = 0, moves = 0, segments = 0, conics = 0;
  bool level = false;
  plan::SourceLoc last_loc;
  std::vector<card::WireSegment> made;
  std::vector<uint32_t> scratch;

  std::optional<plan::Diagnostic> take(const plan::PlannedJob& pj, size_t s) {
    made.clear();
    if (auto e = card::to_wire_segment(pj, s, pj.card[s].chunks, pj.card[s].conic.get(), file, limits, made))
      return e;
    for (const card::WireSegment& w : made) {
      scratch.clear();
      card::encode_segment(w, scratch);
      words.push_back(scratch.size());
      cycle += chunk_cycles_until(w.chunks, UINT64_MAX);
      moves += uint64_t(w.u) << w.k;
      end_cycle.push_back(cycle);
      end_moves.push_back(moves);
      chunks += w.chunks.size();
      conics += w.conic.has_value();
      if (first_chunks.size() <= limits.segment_queue) first_chunks.push_back(w.chunks.size());
      if (w.torch != level) {
        torch.push_back({size_t(segments), w.torch, w.chunks.empty() ? 1u : w.chunks.front().interval,
                         pj.card[s].segment.loc});
        level = w.torch;
      }
      ++segments;
      last_loc = pj.card[s].segment.loc;
    }
    return std::nullopt;
  }
};
}  // namespace

plan::Result<CardJob> plan_card_job(const plan::Job& job, const plan::Machine& machine, const card::CardCaps& caps,
                                    const plan::PerAxis<int64_t>& start, bool streamed) {
  plan::Result<CardJob> r;
  plan::PlanOptions options;
  options.chunk_limits = card::chunk_limits();  // add2 as the machine's planner.chunk_add2 says
  WireSink sink{card::limits(caps), job.file};
  if (streamed) {
    options.on_segment = [&sink](const plan::PlannedJob& pj, size_t s) { return sink.take(pj, s); };
    options.keep_chunks = false;
  }
  auto planned = plan::plan_job(job, machine, options);
  r.warnings = planned.warnings;
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  plan::Result<card::WireJob> wire;
  if (streamed) {
    wire.value.emplace().start_after = card::start_after(sink.first_chunks, sink.limits);
  } else {
    wire = card::to_wire(*planned, job.file, card::limits(caps));
  }
  if (!wire.ok()) {
    r.errors = wire.errors;
    return r;
  }

  CardJob& cj = r.value.emplace();
  cj.job_file = job.file;
  cj.machine = machine;
  cj.caps = caps;
  cj.planned = std::move(*planned.value);
  cj.wire = std::move(*wire.value);
  cj.streamed = streamed;
  if (streamed) {
    std::vector<uint32_t> preamble;
    card::encode_preamble(cj.machine, cj.wire.seek, preamble);
    uint64_t w = preamble.size();
    for (size_t i = 0; i < sink.segments; ++i) {
      if (i == cj.wire.start_after) ++w;  // START
      w += sink.words[i];
      cj.segment_end_word.push_back(w);
    }
    if (cj.wire.start_after >= sink.segments) ++w;
    cj.segment_end_cycle = std::move(sink.end_cycle);
    cj.segment_end_moves = std::move(sink.end_moves);
    cj.streamed_words = w;
    cj.streamed_chunks = sink.chunks;
    cj.streamed_segments = sink.segments;
    cj.streamed_conics = sink.conics;
    cj.torch_changes = std::move(sink.torch);
    cj.last_segment_loc = sink.last_loc;
  } else {
    cj.words = card::encode_job(cj.machine, cj.wire);
  }

  plan::PerAxis<int64_t> pos = start;
  if (!cj.planned.step_segments.empty()) pos = cj.planned.step_segments.front().start;
  cj.start = pos;
  uint64_t moves = 0;
  for (const plan::PlannedCardSegment& c : cj.planned.card) {
    // The pins show neither a pause's moves nor a checkpoint for it.
    if (c.segment.pause) continue;
    moves += c.segment.moves;
    for (int a = 0; a < plan::kAxes; ++a) pos[a] += c.segment.delta[a];
    cj.checkpoints.push_back({moves, pos, c.segment.loc});
  }
  // Where each SEGMENT command ends in the stream, and when it ends.
  uint64_t end_cycle = 0, end_moves = 0;
  size_t seg = 0;
  for (size_t w = 0; !streamed && w < cj.words.size();) {
    const size_t len = card::command_words(cj.words[w], plan::kAxes);
    w += len;
    if (len == 1) continue;
    const card::WireSegment& s = cj.wire.segments.at(seg++);
    end_cycle += chunk_cycles_until(s.chunks, UINT64_MAX);
    end_moves += uint64_t(s.u) << s.k;
    cj.segment_end_word.push_back(w);
    cj.segment_end_cycle.push_back(end_cycle);
    cj.segment_end_moves.push_back(end_moves);
  }
  cj.warnings = r.warnings;
  return r;
}

MoveClock::MoveClock(const CardJob& job) : job_(job) {
  ideal_.reserve(kBlock);
  chunk_.reserve(kBlock);
}

bool MoveClock::next() {
  if (at_ + 1 < ideal_.size()) {
    ++at_;
    ++moves_;
    return true;
  }
  if (!fill()) return false;
  at_ = 0;
  ++moves_;
  return true;
}

bool MoveClock::fill() {
  const std::vector<plan::PlannedCardSegment>& card = job_.planned.card;
  ideal_.clear();
  chunk_.clear();
  while (card_ < card.size()) {
    const plan::PlannedCardSegment& c = card[card_];
    // A streamed job's segment made again (its chunks and walk) as the clock enters it.
    if (job_.streamed && into_ == 0 && rebuilt_for_ != card_) {
      rebuilt_ = plan::rebuild_card_segment(job_.planned, card_, job_.machine);
      rebuilt_for_ = card_;
    }
    const std::vector<plan::Chunk>& chunks = job_.streamed ? rebuilt_.chunks : c.chunks;
    const plan::ConicWalk* conic = job_.streamed ? rebuilt_.conic.get() : c.conic.get();
    if (into_ == 0 && (card_ == 0 || card[card_ - 1].segment.step_segment != c.segment.step_segment)) {
      // A step segment's parts are consecutive; each move is timed against its total
      // (as plan::ideal_times does).
      total_ = 0;
      for (size_t e = card_; e < card.size() && card[e].segment.step_segment == c.segment.step_segment; ++e)
        total_ += card[e].segment.moves;
    }
    const uint64_t left = c.segment.moves - into_;
    const uint64_t n = std::min(left, kBlock);
    if (n == 0) {
      ++card_;
      into_ = 0;
      chunk_index_ = 0;
      chunk_move_ = 0;
      continue;
    }
    // The chunk times of the block's moves (the card's sum, move by move).
    std::vector<int64_t> times;
    for (uint64_t i = 0; i < n; ++i) {
      while (chunk_index_ < chunks.size() && chunk_move_ >= chunks[chunk_index_].count) {
        ++chunk_index_;
        chunk_move_ = 0;
      }
      if (chunk_index_ >= chunks.size()) break;  // chunks short of the moves: a bad plan, times stop
      const plan::Chunk& ch = chunks[chunk_index_];
      const int64_t j = chunk_move_++;
      last_event_ += int64_t(ch.interval) + j * ch.add + ch.add2 * j * (j - 1) / 2;
      times.push_back(last_event_);
    }
    if (!c.segment.pause) {
      if (conic) {
        const auto b = conic->ideal.begin() + std::ptrdiff_t(into_);
        ideal_.assign(b, b + std::ptrdiff_t(std::min<uint64_t>(n, conic->ideal.size() - into_)));
      } else {
        ideal_ = plan::ideal_move_times(job_.planned.feeds[c.segment.step_segment], total_,
                                        c.segment.first_move + into_, n, job_.clock_hz());
      }
      chunk_ = std::move(times);
    }
    into_ += n;
    if (!c.segment.pause) {
      const size_t m = std::min(ideal_.size(), chunk_.size());
      ideal_.resize(m);
      chunk_.resize(m);
      if (m > 0) return true;
    }
  }
  return false;
}

WordSource::WordSource(const CardJob& job, std::vector<uint32_t> prefix)
    : job_(job), buf_(std::move(prefix)), prefix_(buf_.size()) {
  total_ = prefix_ + job.word_count();
  if (!job.streamed) {
    buf_.insert(buf_.end(), job.words.begin(), job.words.end());
    preamble_ = start_ = true;
    card_ = job.planned.card.size();
  }
}

std::span<const uint32_t> WordSource::window(size_t at_least) {
  while (buf_.size() - at_ < at_least && make_more()) {
  }
  return std::span<const uint32_t>(buf_).subspan(at_);
}

void WordSource::consume(size_t n) {
  at_ += n;
  consumed_ += n;
  // Drop what was sent once it is most of the buffer.
  if (at_ > 4096 && at_ * 2 > buf_.size()) {
    buf_.erase(buf_.begin(), buf_.begin() + std::ptrdiff_t(at_));
    at_ = 0;
  }
}

bool WordSource::make_more() {
  if (!preamble_) {
    card::encode_preamble(job_.machine, job_.wire.seek, buf_);
    preamble_ = true;
    return true;
  }
  const uint64_t segments = job_.wire_segments();
  if (card_ >= job_.planned.card.size()) {
    if (start_) return false;
    card::encode_control(true, false, false, buf_);  // a job of fewer segments than the queues hold
    start_ = true;
    return true;
  }
  const plan::RebuiltCardSegment rb = plan::rebuild_card_segment(job_.planned, card_, job_.machine);
  made_.clear();
  if (auto e = card::to_wire_segment(job_.planned, card_, rb.chunks, rb.conic.get(), job_.job_file,
                                     card::limits(job_.caps), made_))
    throw std::logic_error("WordSource: a card segment the plan took is refused: " + e->str());
  ++card_;
  for (card::WireSegment& w : made_) {
    if (wire_ == job_.wire.start_after) {
      card::encode_control(true, false, false, buf_);
      start_ = true;
    }
    w.end = wire_ + 1 == segments;
    card::encode_segment(w, buf_);
    ++wire_;
  }
  if (card_ >= job_.planned.card.size() && job_.wire.start_after >= segments && !start_) {
    card::encode_control(true, false, false, buf_);
    start_ = true;
  }
  return true;
}

std::vector<double> ideal_cycles(const CardJob& job) {
  std::vector<double> out;
  out.reserve(job.moves());
  for (MoveClock c(job); c.next();) out.push_back(c.ideal());
  return out;
}

std::vector<int64_t> chunk_cycles(const CardJob& job) {
  std::vector<int64_t> out;
  out.reserve(job.moves());
  for (MoveClock c(job); c.next();) out.push_back(c.chunk());
  return out;
}

double buffered_seconds(const CardJob& job, uint64_t segments_done, uint64_t moves_done, uint64_t words_handed) {
  const auto& ends = job.segment_end_word;
  const auto sent = uint64_t(std::upper_bound(ends.begin(), ends.end(), words_handed) - ends.begin());
  if (sent <= segments_done) return 0;
  // The card's next move: the first not made of the segment it runs.
  const uint64_t start = segments_done ? job.segment_end_cycle[segments_done - 1] : 0;
  const uint64_t before = segments_done ? job.segment_end_moves[segments_done - 1] : 0;
  const uint64_t into = moves_done > before ? moves_done - before : 0;
  // A streamed job keeps no chunks: the segment the card runs counts as done (less
  // motion than it holds, never more).
  const uint64_t next = job.streamed ? job.segment_end_cycle[segments_done]
                                     : start + chunk_cycles_until(job.wire.segments[segments_done].chunks, into + 1);
  const uint64_t end = job.segment_end_cycle[sent - 1];
  return end > next ? double(end - next) / job.clock_hz() : 0;
}

bool write_words(const std::filesystem::path& path, const std::vector<uint32_t>& words) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return false;
  for (uint32_t w : words) {
    const char bytes[4] = {char(w & 0xFF), char(w >> 8 & 0xFF), char(w >> 16 & 0xFF),
                           char(w >> 24 & 0xFF)};
    out.write(bytes, 4);
  }
  out.close();
  return bool(out);
}

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
#include "run/card_job.h"

#include <algorithm>
#include <deque>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "card/protocol.h"
#include "card/ptimer_job.h"
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

// A streamed job planned from its blocks, or from its G-code file (defined below).
plan::Result<CardJob> plan_streamed(std::shared_ptr<const plan::Job> job, const plan::Machine& machine,
                                    const card::CardCaps& caps, const plan::PerAxis<int64_t>& start);
plan::Result<CardJob> plan_streamed_file(const std::filesystem::path& file, const plan::GcodeOptions& options,
                                         const plan::Machine& machine, const card::CardCaps& caps,
                                         const plan::PerAxis<int64_t>& start);

}  // namespace

uint64_t CardJob::conic_segments() const {
  if (streamed) return streamed_conics;
  uint64_t n = 0;
  for (const card::WireSegment& w : wire.segments) n += w.conic.has_value();
  return n;
}

uint64_t CardJob::wire_chunks() const {
  if (streamed) return streamed_chunks;
  if (caps.ptimer) return 0;  // its segments carry no chunks (the plan's are not sent)
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

namespace {

// The G-code options for a machine on a card at `start` (absolute steps).
plan::Result<plan::GcodeOptions> card_gcode_options(const plan::Machine& machine, const plan::PerAxis<int64_t>& start) {
  plan::Result<plan::GcodeOptions> r;
  plan::PerAxis<double> start_mm{};
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = machine.axes[a];
    if (start[a] == 0) continue;
    if (!ax.present) {
      r.errors.push_back({machine.file, {},
                          fmt::format("the card's axis {} is at {} steps, but the machine has no such axis",
                                      plan::kAxisLetters[a], start[a])});
      return r;
    }
    start_mm[a] = double(start[a]) / ax.steps_per_mm;
  }
  r.value = plan::gcode_options(machine, start_mm);
  return r;
}

}  // namespace

plan::Result<plan::Job> read_card_gcode(const std::filesystem::path& gcode, const plan::Machine& machine,
                                        const plan::PerAxis<int64_t>& start) {
  auto options = card_gcode_options(machine, start);
  if (!options.ok()) {
    plan::Result<plan::Job> r;
    r.errors = options.errors;
    return r;
  }
  return plan::load_gcode(gcode, *options);
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
  plan::Result<CardJob> planned;
  if (streamed) {
    // Streamed: the G-code file read again, a piece at a time, each time the
    // plan is made again (PlanCursor), its blocks planned as they are needed;
    // each piece checked against the reading the job was planned from, so that
    // a file changed under a running job stops it rather than sends another
    // plan. Its G1 chains are fitted with arcs as they are read where the
    // machine file asks (plan::ArcFitter). A program with probe moves keeps its blocks.
    auto options = card_gcode_options(*machine, start);
    if (!options.ok()) {
      r.errors = options.errors;
      return r;
    }
    if (!std::ifstream(gcode, std::ios::binary)) {
      r.errors.push_back({gcode.string(), {}, "cannot open file"});
      return r;
    }
    // (A phase-timer card's job is planned whole: card::plan_phase_timer_job.)
    if (!plan::file_has_probe_words(gcode) && !caps.ptimer)
      planned = plan_streamed_file(gcode, *options, *machine, caps, start);
  }
  if (!planned.ok() && planned.errors.empty()) {
    auto job = read_card_gcode(gcode, *machine, start);
    r.warnings.insert(r.warnings.end(), job.warnings.begin(), job.warnings.end());
    if (!job.ok()) {
      r.errors = job.errors;
      return r;
    }
    // A streamed job keeps its blocks (it plans them again as it runs): moved, not copied.
    planned = streamed && !caps.ptimer
                  ? plan_streamed(std::make_shared<const plan::Job>(std::move(*job.value)), *machine, caps, start)
                  : plan_card_job(*job, *machine, caps, start);
  }
  r.warnings.insert(r.warnings.end(), planned.warnings.begin(), planned.warnings.end());
  r.warnings = plan::summarize_repeats(std::move(r.warnings));  // e.g. "feed lowered" once, with a count
  r.errors = std::move(planned.errors);
  if (planned.value) {
    r.value = std::move(planned.value);
    r.value->warnings = r.warnings;
  }
  return r;
}

// A streamed job's blocks in order: its own, or read from its G-code's text
// (with its G1 chains fitted as they are read, where the machine file asks).
class BlockSource {
 public:
  // With `record`: the job's G-code file read for the first time, its mark taken there.
  explicit BlockSource(const CardJob& job, plan::GcodeFileMark* record = nullptr) : job_(job) {
    if (record) reader_.emplace(std::filesystem::path(job.job_file), job.gcode_options, record);
    else if (job.gcode_file) reader_.emplace(job.gcode_file, job.gcode_options);
    else if (!job.blocks) throw std::logic_error("a streamed job with neither blocks nor a G-code file");
    if (const auto tol = plan::arc_fit_tolerances(job.machine); reader_ && tol.any()) fitter_.emplace(tol);
  }
  std::optional<plan::MotionBlock> next() {
    if (!reader_) {
      if (at_ < job_.blocks->blocks.size()) return job_.blocks->blocks[at_++];
      return std::nullopt;
    }
    if (!fitter_) return reader_->next();
    for (;;) {
      if (auto b = fitter_->next()) return b;
      if (read_all_) return std::nullopt;
      if (auto b = reader_->next()) {
        fitter_->push(*b);
      } else {
        fitter_->finish();
        read_all_ = true;
      }
    }
  }
  // The G-code reader's result once next() gave none (null: the blocks were the job's).
  // A file read again that changed since the job was planned holds that error.
  const plan::Result<plan::Job>* read_result() const { return reader_ ? &reader_->result() : nullptr; }
  // What the fitting of G1 chains made so far (null: the blocks are not fitted here).
  const plan::ArcFitStats* fit_stats() const { return fitter_ ? &fitter_->stats() : nullptr; }

 private:
  const CardJob& job_;
  std::optional<plan::GcodeBlockReader> reader_;
  std::optional<plan::ArcFitter> fitter_;
  bool read_all_ = false;
  size_t at_ = 0;
};

namespace {

// A streamed job's wire segments as the planner makes its card segments: each
// converted, checked and measured (its words, the cycles and moves of its
// chunks, its torch level), then dropped.
struct WireSink {
  WireSink(card::CardLimits l, std::string f) : limits(l), file(std::move(f)) {}
  card::CardLimits limits;
  std::string file;
  uint64_t words = 0;                // the SEGMENT commands' words
  std::vector<size_t> first_chunks;  // chunks of the first segment_queue + 1 (start_after)
  std::vector<CardJob::TorchChange> torch;
  uint64_t chunks = 0, cycle = 0, moves = 0, segments = 0, conics = 0;
  bool level = false;
  plan::SourceLoc last_loc;
  std::vector<card::WireSegment> made;
  std::vector<uint32_t> scratch;

  std::optional<plan::Diagnostic> take(const plan::PlannedCardSegment& c, bool torch_on) {
    made.clear();
    if (auto e = card::to_wire_segment(c.segment, torch_on, c.chunks, c.conic.get(), file, limits, made)) return e;
    for (const card::WireSegment& w : made) {
      scratch.clear();
      card::encode_segment(w, scratch);
      words += scratch.size();
      const uint64_t before = cycle;
      cycle += chunk_cycles_until(w.chunks, UINT64_MAX);
      moves += uint64_t(w.u) << w.k;
      chunks += w.chunks.size();
      conics += w.conic.has_value();
      if (first_chunks.size() <= limits.segment_queue) first_chunks.push_back(w.chunks.size());
      if (w.torch != level) {
        torch.push_back({size_t(segments), w.torch, before, w.chunks.empty() ? 1u : w.chunks.front().interval,
                         c.segment.loc});
        level = w.torch;
      }
      ++segments;
      last_loc = c.segment.loc;
    }
    return std::nullopt;
  }
};

// The torch level of a card segment: its step segment's.
bool torch_of(const PlanCursor& cursor, const plan::PlannedCardSegment& c) {
  return cursor.step(c.segment.step_segment).segment.torch;
}

// A streamed job: planned as its blocks go through a plan::PlanStream, each
// card segment converted and measured by the sink, nothing of the plan kept
// but its statistics and its source (the blocks, or the G-code's text).
plan::Result<CardJob> plan_streamed_from(CardJob cj, const card::CardCaps& caps, const plan::PerAxis<int64_t>& start,
                                         const plan::ArcFitStats& fit,
                                         std::shared_ptr<plan::GcodeFileMark> mark = nullptr) {
  plan::Result<CardJob> r;
  const plan::Machine& machine = cj.machine;
  if (!(machine.card.clock_hz > 0)) {
    r.errors.push_back({machine.file, {}, "no card clock: the machine file gives no [card] clock_hz and no "
                                          "card was asked (plan::bind_card())"});
    return r;
  }
  WireSink sink(card::limits(caps), cj.job_file);
  plan::PlanStream stream(machine, cj.job_file, cj.plan_options);
  BlockSource source(cj, mark.get());
  std::optional<plan::Diagnostic> refused;
  std::deque<plan::StreamedStep> steps;  // from the last card segment's step segment on
  bool first_step = true;
  plan::PerAxis<int64_t> plan_start = start, pos = start;
  const auto drain = [&] {
    for (;;) {
      while (auto st = stream.next_step()) {
        if (first_step) plan_start = pos = st->segment.start;
        first_step = false;
        cj.has_nurbs = cj.has_nurbs || st->segment.kind == plan::MotionKind::nurbs;
        steps.push_back(std::move(*st));
      }
      auto c = stream.next_card();
      if (!c) return;
      if (refused) continue;
      while (steps.size() > 1 && steps.front().index < c->segment.step_segment) steps.pop_front();
      const bool torch = !steps.empty() && steps.front().index == c->segment.step_segment && steps.front().segment.torch;
      refused = sink.take(*c, torch);
      if (!c->segment.pause) {
        ++cj.checkpoint_count;
        for (int a = 0; a < plan::kAxes; ++a) pos[a] += c->segment.delta[a];
      }
    }
  };
  for (size_t b = 0;; ++b) {
    auto block = source.next();
    if (!block) break;
    stream.push(*block, b);
    drain();
  }
  stream.finish();
  drain();
  // The G-code's own errors first (a program read whole is refused before it is planned).
  if (const plan::Result<plan::Job>* read = source.read_result()) {
    r.warnings = read->warnings;
    if (!read->ok()) {
      r.errors = read->errors;
      return r;
    }
  }
  const std::vector<plan::Diagnostic> w = stream.warnings();
  r.warnings.insert(r.warnings.end(), w.begin(), w.end());
  if (refused && (stream.errors().empty() || !stream.refused_before_the_card_loop())) {
    r.errors.push_back(std::move(*refused));
    return r;
  }
  if (!stream.errors().empty()) {
    r.errors = stream.errors();
    return r;
  }
  cj.planned.stats = stream.stats();
  cj.planned.stats.fit = source.fit_stats() ? *source.fit_stats() : fit;
  // A NURBS cut into arcs (a card that walks them): the run is still measured against it.
  cj.has_nurbs = cj.has_nurbs || cj.planned.stats.fit.curves > 0;
  cj.planned.chunk_limits = stream.chunk_limits();
  // Where the plan starts (its first step segment's start, else the card's
  // position) and where its last card segment ends.
  cj.start = plan_start;
  cj.final_position = pos;
  cj.wire.start_after = card::start_after(sink.first_chunks, sink.limits);
  std::vector<uint32_t> preamble;
  card::encode_preamble(cj.machine, cj.wire.seek, preamble);
  cj.streamed_words = preamble.size() + sink.words + 1;  // and START
  cj.streamed_chunks = sink.chunks;
  cj.streamed_segments = sink.segments;
  cj.streamed_conics = sink.conics;
  cj.torch_changes = std::move(sink.torch);
  cj.last_segment_loc = sink.last_loc;
  cj.end_cycle = sink.cycle;
  cj.gcode_file = std::move(mark);
  r.value = std::move(cj);
  return r;
}

// A streamed job's skeleton: what every consumer of it shares.
CardJob streamed_job(std::string file, const plan::Machine& machine, const card::CardCaps& caps) {
  CardJob cj;
  cj.job_file = std::move(file);
  cj.machine = machine;
  cj.caps = caps;
  cj.streamed = true;
  cj.plan_options.chunk_limits = card::chunk_limits();  // add2 as the machine's planner.chunk_add2 says
  return cj;
}

plan::Result<CardJob> plan_streamed(std::shared_ptr<const plan::Job> job, const plan::Machine& machine,
                                    const card::CardCaps& caps, const plan::PerAxis<int64_t>& start) {
  CardJob cj = streamed_job(job->file, machine, caps);
  plan::ArcFitStats fit;
  const plan::ArcFitTolerances tol = plan::arc_fit_tolerances(machine);
  cj.blocks = tol.any() ? std::make_shared<const plan::Job>(plan::fit_arcs(*job, tol, &fit))
                        : std::move(job);
  return plan_streamed_from(std::move(cj), caps, start, fit);
}

plan::Result<CardJob> plan_streamed_file(const std::filesystem::path& file, const plan::GcodeOptions& options,
                                         const plan::Machine& machine, const card::CardCaps& caps,
                                         const plan::PerAxis<int64_t>& start) {
  CardJob cj = streamed_job(file.string(), machine, caps);
  cj.gcode_options = options;
  return plan_streamed_from(std::move(cj), caps, start, {}, std::make_shared<plan::GcodeFileMark>());
}

// The job's checkpoints, start and end, from its plan (not streamed).
void set_checkpoints(CardJob& cj, const plan::PerAxis<int64_t>& start) {
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
  cj.checkpoint_count = cj.checkpoints.size();
  cj.final_position = cj.checkpoints.empty() ? cj.start : cj.checkpoints.back().position;
  for (const plan::StepSegment& st : cj.planned.step_segments)
    cj.has_nurbs = cj.has_nurbs || st.kind == plan::MotionKind::nurbs;
  cj.has_nurbs = cj.has_nurbs || cj.planned.stats.fit.curves > 0;   // a NURBS as arcs
}

// A job for a phase-timer card (card::plan_phase_timer_job), planned whole: arcs as
// conics where the machine file asks (each move measured by the walker's length
// rule), or, when the card cannot walk them so (an arc's moves faster than its
// walker gives them, a length the rule cannot measure), the whole job's arcs as
// chords with a warning that says why. The card's timer starts with START, and move
// n fires 2 * fire_half_clocks[n] + card::kPhaseTimerStartCycles clocks after it
// (at scale 1).
plan::Result<CardJob> plan_phase_timer_card_job(const plan::Job& job, const plan::Machine& machine,
                                                const card::CardCaps& caps, const plan::PerAxis<int64_t>& start) {
  plan::Result<CardJob> r;
  plan::Machine m = machine;
  auto pt = card::plan_phase_timer_job(job, m, card::limits(caps), job.file);
  if (!pt.ok() && m.planner.arcs == plan::ArcMode::conic && m.card.conic_width > 0) {
    plan::Machine chords = m;
    chords.planner.arcs = plan::ArcMode::chords;
    auto again = card::plan_phase_timer_job(job, chords, card::limits(caps), job.file);
    if (again.ok()) {
      const plan::Diagnostic& why = pt.errors.front();
      r.warnings.push_back({why.file, why.loc, "arcs planned as chords: " + why.message});
      m = chords;
      pt = std::move(again);
    }
  }
  r.warnings.insert(r.warnings.end(), pt.warnings.begin(), pt.warnings.end());
  if (!pt.ok()) {
    r.errors = pt.errors;
    return r;
  }
  card::PhaseTimerJob& p = *pt.value;
  CardJob& cj = r.value.emplace();
  cj.job_file = job.file;
  cj.machine = m;
  cj.caps = caps;
  cj.planned = std::move(p.planned);
  cj.wire = std::move(p.wire);
  cj.phases = p.phases;
  const auto cycle = [](int64_t half_clocks) { return 2 * half_clocks + card::kPhaseTimerStartCycles; };
  cj.fire_cycles.reserve(p.fire_half_clocks.size());
  for (int64_t h : p.fire_half_clocks) cj.fire_cycles.push_back(cycle(h));
  cj.words = std::move(p.preamble);
  cj.preamble_words = cj.words.size();
  size_t phase = 0;
  uint64_t end_moves = 0;
  for (size_t i = 0; i < p.commands.size(); ++i) {
    const std::vector<uint32_t>& c = p.commands[i];
    cj.words.insert(cj.words.end(), c.begin(), c.end());
    if ((c[0] >> 28) == 0x6) {
      cj.phase_end_word.push_back(cj.words.size());
      cj.phase_end_cycle.push_back(uint64_t(cycle(p.phase_end_half_clocks.at(phase++))));
    } else {
      const card::WireSegment& s = cj.wire.segments.at(cj.segment_end_word.size());
      end_moves += uint64_t(s.u) << s.k;
      cj.segment_end_word.push_back(cj.words.size());
      cj.segment_end_cycle.push_back(uint64_t(cj.fire_cycles.at(end_moves - 1)));
      cj.segment_end_moves.push_back(end_moves);
    }
    if (i + 1 == p.start_after) card::encode_control(true, false, false, cj.words);
  }
  set_checkpoints(cj, start);
  cj.warnings = r.warnings;
  return r;
}

}  // namespace

plan::Result<CardJob> plan_card_job(const plan::Job& job, const plan::Machine& machine, const card::CardCaps& caps,
                                    const plan::PerAxis<int64_t>& start, bool streamed) {
  if (caps.ptimer) return plan_phase_timer_card_job(job, machine, caps, start);
  if (streamed) {
    auto r = plan_streamed(std::make_shared<const plan::Job>(job), machine, caps, start);
    if (r.value) r.value->warnings = r.warnings;
    return r;
  }
  plan::Result<CardJob> r;
  plan::PlanOptions options;
  options.chunk_limits = card::chunk_limits();  // add2 as the machine's planner.chunk_add2 says
  auto planned = plan::plan_job(job, machine, options);
  r.warnings = planned.warnings;
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  plan::Result<card::WireJob> wire = card::to_wire(*planned, job.file, card::limits(caps));
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
  cj.words = card::encode_job(cj.machine, cj.wire);
  cj.plan_options = options;
  set_checkpoints(cj, start);
  // Where each SEGMENT command ends in the stream, and when it ends.
  uint64_t end_cycle = 0, end_moves = 0;
  size_t seg = 0;
  for (size_t w = 0; w < cj.words.size();) {
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

PlanCursor::PlanCursor(const CardJob& job)
    : job_(job), stream_(job.machine, job.job_file, job.plan_options), source_(std::make_unique<BlockSource>(job)) {}

PlanCursor::~PlanCursor() = default;

bool PlanCursor::pull() {
  if (!finished_) {
    if (auto b = source_->next()) {
      stream_.push(*b, block_++);
      return true;
    }
  }
  if (finished_) return false;
  stream_.finish();
  finished_ = true;
  return true;
}

const plan::PlannedCardSegment* PlanCursor::next_card() {
  for (;;) {
    while (auto st = stream_.next_step()) steps_.push_back(std::move(*st));
    if (auto c = stream_.next_card()) {
      card_ = std::move(*c);
      ++card_index_;
      // The step segments before this one's are done with.
      while (!steps_.empty() && steps_.front().index < card_->segment.step_segment) steps_.pop_front();
      return &*card_;
    }
    if (!pull()) {
      refused();
      return nullptr;
    }
  }
}

const plan::StreamedStep& PlanCursor::step(size_t s) const {
  if (steps_.empty() || s < steps_.front().index || s >= steps_.front().index + steps_.size())
    throw std::logic_error(fmt::format("PlanCursor: step segment {} is not held", s));
  return steps_[s - steps_.front().index];
}

bool PlanCursor::next_step(plan::StreamedStep& out) {
  for (;;) {
    if (auto st = stream_.next_step()) {
      out = std::move(*st);
      return true;
    }
    bool cards = false;
    while (stream_.next_card()) cards = true;  // not wanted here
    if (cards) continue;
    if (!pull()) {
      refused();
      return false;
    }
  }
}

void PlanCursor::refused() const {
  // The G-code's file read again may differ from the one planned (changed since).
  if (const plan::Result<plan::Job>* read = source_->read_result(); read && !read->ok())
    throw JobFileChanged(read->errors.front().str());
  if (!stream_.errors().empty())
    throw std::logic_error("PlanCursor: the plan made again is refused: " + stream_.errors().front().str());
}

CheckpointCursor::CheckpointCursor(const CardJob& job) : job_(job) {
  if (job.streamed) {
    plan_.emplace(job);
    cp_.position = job.start;
  }
}

const Checkpoint* CheckpointCursor::next() {
  if (!job_.streamed) {
    if (index_ >= job_.checkpoints.size()) return nullptr;
    return &job_.checkpoints[index_++];
  }
  // The pins show neither a pause's moves nor a checkpoint for it.
  for (const plan::PlannedCardSegment* c; (c = plan_->next_card()) != nullptr;) {
    if (c->segment.pause) continue;
    ++index_;
    cp_.moves += c->segment.moves;
    for (int a = 0; a < plan::kAxes; ++a) cp_.position[a] += c->segment.delta[a];
    cp_.loc = c->segment.loc;
    return &cp_;
  }
  return nullptr;
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
  ideal_.clear();
  chunk_.clear();
  if (job_.streamed && !cursor_) {
    cursor_.emplace(job_);
    streamed_card_ = cursor_->next_card();
  }
  const std::vector<plan::PlannedCardSegment>& card = job_.planned.card;
  for (;;) {
    // The card segment the block is from (a streamed job's made again as the clock enters it).
    const plan::PlannedCardSegment* cp = job_.streamed ? streamed_card_ : card_ < card.size() ? &card[card_] : nullptr;
    if (!cp) return false;
    const plan::PlannedCardSegment& c = *cp;
    const std::vector<plan::Chunk>& chunks = c.chunks;
    const plan::ConicWalk* conic = c.conic.get();
    if (!job_.streamed && into_ == 0 &&
        (card_ == 0 || card[card_ - 1].segment.step_segment != c.segment.step_segment)) {
      // A step segment's parts are consecutive; each move is timed against its total
      // (as plan::ideal_times does).
      total_ = 0;
      for (size_t e = card_; e < card.size() && card[e].segment.step_segment == c.segment.step_segment; ++e)
        total_ += card[e].segment.moves;
    }
    if (job_.streamed) total_ = c.step_moves;  // the moves of its step segment, all of its parts
    const uint64_t left = c.segment.moves - into_;
    const uint64_t n = std::min(left, kBlock);
    if (n == 0) {
      ++card_;
      if (job_.streamed) streamed_card_ = cursor_->next_card();
      into_ = 0;
      chunk_index_ = 0;
      chunk_move_ = 0;
      continue;
    }
    // The chunk times of the block's moves (the card's sum, move by move; a
    // phase-timer card's fire times).
    std::vector<int64_t> times;
    for (uint64_t i = 0; i < n && !job_.fire_cycles.empty(); ++i) {
      if (timed_ >= job_.fire_cycles.size()) break;  // a bad plan: times stop
      times.push_back(job_.fire_cycles[timed_++]);
    }
    for (uint64_t i = 0; i < n && job_.fire_cycles.empty(); ++i) {
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
        const plan::PlannedSegment& feed = job_.streamed ? cursor_->step(c.segment.step_segment).feed
                                                         : job_.planned.feeds[c.segment.step_segment];
        ideal_ = plan::ideal_move_times(feed, total_, c.segment.first_move + into_, n, job_.clock_hz());
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
}

WordSource::WordSource(const CardJob& job, std::vector<uint32_t> prefix)
    : job_(job), buf_(std::move(prefix)), prefix_(buf_.size()) {
  total_ = prefix_ + job.word_count();
  if (!job.streamed) {
    buf_.insert(buf_.end(), job.words.begin(), job.words.end());
    preamble_ = start_ = cards_done_ = true;
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
  if (!cursor_ && !cards_done_) cursor_.emplace(job_);
  const plan::PlannedCardSegment* c = cards_done_ ? nullptr : cursor_->next_card();
  if (!c) {
    cards_done_ = true;
    if (start_) return false;
    card::encode_control(true, false, false, buf_);  // a job of fewer segments than the queues hold
    start_ = true;
    return true;
  }
  made_.clear();
  if (auto e = card::to_wire_segment(c->segment, torch_of(*cursor_, *c), c->chunks, c->conic.get(), job_.job_file,
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
    end_cycle_ += chunk_cycles_until(w.chunks, UINT64_MAX);
    end_moves_ += uint64_t(w.u) << w.k;
    ends_.push_back({consumed_ + (buf_.size() - at_) - prefix_, end_cycle_, end_moves_});
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

double WordSource::buffered_seconds(uint64_t segments_done, uint64_t moves_done, uint64_t words_handed) {
  if (!job_.streamed) return run::buffered_seconds(job_, segments_done, moves_done, words_handed);
  // The ends of the segments before the one the card runs are done with (its
  // own start is the end of the one before it).
  if (segments_done < ends_first_) return 0;  // an older reply than one asked before: nothing known
  while (!ends_.empty() && ends_first_ + 1 < segments_done) {
    ends_.pop_front();
    ++ends_first_;
  }
  const auto handed = std::upper_bound(ends_.begin(), ends_.end(), words_handed,
                                       [](uint64_t w, const SegmentEnd& e) { return w < e.word; });
  const uint64_t sent = ends_first_ + uint64_t(handed - ends_.begin());
  if (sent <= segments_done) return 0;
  // A streamed job keeps no chunks: the segment the card runs counts as done
  // (less motion than it holds, never more).
  const uint64_t next = ends_[segments_done - ends_first_].cycle;
  const uint64_t end = ends_[sent - 1 - ends_first_].cycle;
  return end > next ? double(end - next) / job_.clock_hz() : 0;
}

double buffered_seconds(const CardJob& job, uint64_t segments_done, uint64_t moves_done, uint64_t words_handed) {
  if (job.streamed) throw std::logic_error("buffered_seconds: a streamed job keeps no segment ends (WordSource does)");
  const auto& ends = job.segment_end_word;
  const auto sent = uint64_t(std::upper_bound(ends.begin(), ends.end(), words_handed) - ends.begin());
  if (sent <= segments_done) return 0;
  // The card's next move: the first not made of the segment it runs.
  const uint64_t start = segments_done ? job.segment_end_cycle[segments_done - 1] : 0;
  const uint64_t before = segments_done ? job.segment_end_moves[segments_done - 1] : 0;
  const uint64_t into = moves_done > before ? moves_done - before : 0;
  uint64_t next = start + chunk_cycles_until(job.wire.segments[segments_done].chunks, into + 1);
  uint64_t end = job.segment_end_cycle[sent - 1];
  if (!job.fire_cycles.empty()) {
    // A phase-timer card: its next move's fire time, and it holds motion only as far
    // as the phases handed time it too.
    next = uint64_t(job.fire_cycles[std::min<uint64_t>(moves_done, job.fire_cycles.size() - 1)]);
    const auto& pe = job.phase_end_word;
    const auto timed = size_t(std::upper_bound(pe.begin(), pe.end(), words_handed) - pe.begin());
    end = std::min(end, timed ? job.phase_end_cycle[timed - 1] : 0);
  }
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

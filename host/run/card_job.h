// SPDX-License-Identifier: MIT
// A G-code job made ready for the card: planned with the card's chunk form,
// converted to wire segments and encoded as command words, with what a run
// needs to check the card against the plan (ideal move times, the position
// after every card segment).
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "card/job.h"
#include "plan/common.h"
#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/pipeline.h"

namespace cpstep::run {

// Where the card must be after a planned card segment.
struct Checkpoint {
  uint64_t moves = 0;                    // move events from START to its last move
  plan::PerAxis<int64_t> position{};     // absolute steps after it
  plan::SourceLoc loc;                   // the G-code block it came from
};

struct CardJob {
  std::string job_file;
  plan::Machine machine;
  plan::PlannedJob planned;
  card::WireJob wire;
  std::vector<uint32_t> words;           // the command stream: CONFIG, segments, START
  std::vector<Checkpoint> checkpoints;   // one per planned card segment
  plan::PerAxis<int64_t> start{};        // absolute steps the job was planned from (the card's position)
  // Per wire segment (the SEGMENT commands of `words`, in order): the word
  // index just past its last word, its end in cycles from START, and the card's
  // moves from START to its end (pause moves included, as the card counts).
  // Empty for a streamed job (WordSource keeps those it made that the card holds).
  std::vector<uint64_t> segment_end_word;
  std::vector<uint64_t> segment_end_cycle;
  std::vector<uint64_t> segment_end_moves;
  // A phase-timer card's job (caps.ptimer; docs/CORE.md "Phase-timer builds",
  // card::plan_phase_timer_job): `words` are the preamble, the PHASE and SEGMENT
  // commands in the order the card needs them, START after the first segment; its
  // segments carry no chunks. Each move's cycle from START as the card fires it (in
  // place of the chunks' times: MoveClock::chunk()), and each PHASE command's end
  // word and the cycle its phase ends (the motion the card holds needs both).
  std::vector<int64_t> fire_cycles;
  size_t preamble_words = 0;  // the words before the first PHASE (drivers, axes, inputs, feed)
  std::vector<uint64_t> phase_end_word;
  std::vector<uint64_t> phase_end_cycle;
  uint64_t phases = 0;
  std::vector<plan::Diagnostic> warnings;  // the planner's (also in the Result)
  // Streamed (prepare_job(..., streamed)): none of the plan is kept. `planned`
  // holds its statistics, `words`, `wire.segments` and `checkpoints` are empty;
  // a PlanCursor makes the plan again from the job's blocks or its G-code's text,
  // with the chunk limits it was made with, as a consumer reaches it (WordSource
  // the command words, segment by segment, as they are sent). What the run needs
  // of it whole comes with the job: the words' and wire segments' counts, the
  // CONIC ones, the torch's changes, the checkpoints' count and last position
  // (docs/SIM.md "Memory").
  bool streamed = false;
  uint64_t streamed_words = 0, streamed_chunks = 0, streamed_segments = 0, streamed_conics = 0;
  // The blocks the plan was made from (after planner.fit_arcs_mm).
  std::shared_ptr<const plan::Job> blocks;
  // Or the G-code file (its mark: size and a hash per piece, taken as it was
  // planned) and how it is read, when the job's blocks are those of the file as
  // read (their G1 chains fitted as they are read where planner.fit_arcs_mm asks;
  // no probing): read again as it is planned again, a file written over since
  // stops the cursor (JobFileChanged).
  std::shared_ptr<const plan::GcodeFileMark> gcode_file;
  plan::GcodeOptions gcode_options;
  plan::PlanOptions plan_options;
  uint64_t checkpoint_count = 0;            // checkpoints.size()
  plan::PerAxis<int64_t> final_position{};  // checkpoints.back().position (start when there is none)
  bool has_nurbs = false;                   // a step segment of a G5.x curve
  struct TorchChange {
    size_t segment = 0;           // the wire segment that brings the new level
    bool on = false;
    uint64_t end_before = 0;      // the end of the wire segment before it, cycles from START
    uint32_t first_interval = 0;  // its first move's delay (its first chunk's interval)
    plan::SourceLoc loc;          // its G-code block
  };
  std::vector<TorchChange> torch_changes;  // streamed only
  plan::SourceLoc last_segment_loc;        // streamed: the last wire segment's block
  uint64_t end_cycle = 0;                  // streamed: the last wire segment's end, cycles from START
  [[nodiscard]] uint64_t word_count() const { return streamed ? streamed_words : words.size(); }
  [[nodiscard]] uint64_t wire_segments() const { return streamed ? streamed_segments : wire.segments.size(); }
  [[nodiscard]] uint64_t conic_segments() const;
  std::string feed_ramp_note;              // how the feed ramp was fitted (run::fit_feed_ramp)

  [[nodiscard]] uint64_t moves() const { return planned.stats.moves; }
  // Every move the card makes and counts: those that step and the pause moves.
  [[nodiscard]] uint64_t card_moves() const { return planned.stats.moves + planned.stats.pause_moves; }
  [[nodiscard]] uint64_t wire_chunks() const;  // the chunks sent (none to a phase-timer card)
  card::CardCaps caps;                   // the card it is planned for
  [[nodiscard]] double clock_hz() const { return machine.card.clock_hz; }
};

// A streamed job's G-code file written over since the job was planned from it
// (what() names the file, the line and the bytes): the plan cannot be made again.
struct JobFileChanged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A streamed job's plan made again, in order (plan::PlanStream over the job's
// blocks): its card segments with their chunks and walks, each with its step
// segment and feed, or its step segments alone; in bounded memory. A job that
// is not streamed is read from its plan.
class BlockSource;  // a streamed job's blocks (card_job.cpp)

class PlanCursor {
 public:
  explicit PlanCursor(const CardJob& job);
  ~PlanCursor();
  PlanCursor(const PlanCursor&) = delete;
  PlanCursor& operator=(const PlanCursor&) = delete;
  // The next card segment, or null past the last; valid until the next call.
  const plan::PlannedCardSegment* next_card();
  // Step segment s with its feed: that of the card segment next_card() gave
  // last, or one made after it.
  [[nodiscard]] const plan::StreamedStep& step(size_t s) const;
  // The next step segment with its feed, in order (for a consumer that reads
  // step segments, not card segments); false past the last.
  bool next_step(plan::StreamedStep& out);

 private:
  bool pull();  // one more block into the plan (or its end); false when there is no more
  void refused() const;  // throws when the plan made again stopped on an error

  const CardJob& job_;
  plan::PlanStream stream_;
  std::unique_ptr<BlockSource> source_;
  size_t block_ = 0;
  bool finished_ = false;
  std::deque<plan::StreamedStep> steps_;  // made; from the current card segment's own on
  std::optional<plan::PlannedCardSegment> card_;
  size_t card_index_ = 0;
};

// The job's checkpoints in order (CardJob::checkpoints; a streamed job's made
// again as PlanCursor reaches them, from CardJob::start).
class CheckpointCursor {
 public:
  explicit CheckpointCursor(const CardJob& job);
  // The next checkpoint, or null past the last; valid until the next call.
  const Checkpoint* next();

 private:
  const CardJob& job_;
  std::optional<PlanCursor> plan_;
  size_t index_ = 0;
  Checkpoint cp_;
};

// Every move of a job that steps, one at a time in execution order, with its
// planned times in card cycles from START: the planner's ideal time and the time
// its chunks realize (never later; within the chunk tolerance). A pause's moves
// show no pin: they are passed over, but they time the next move's first
// interval. Memory is bounded by a block of moves (kBlock), whatever the job's
// length: what a run measured as it goes (RunMeter) steps through.
class MoveClock {
 public:
  explicit MoveClock(const CardJob& job);
  // Moves to the next move; false past the last.
  bool next();
  [[nodiscard]] double ideal() const { return ideal_[at_]; }
  [[nodiscard]] int64_t chunk() const { return chunk_[at_]; }
  // Moves made so far (the current move's number, 1-based).
  [[nodiscard]] uint64_t moves() const { return moves_; }

  static constexpr uint64_t kBlock = 4096;

 private:
  bool fill();  // the next block of the current card segment (or of the ones after it)

  const CardJob& job_;
  size_t card_ = 0;          // the card segment the block is from
  uint64_t into_ = 0;        // its moves already in blocks
  uint64_t total_ = 0;       // the moves of its step segment (all of its parts)
  size_t chunk_index_ = 0;   // the chunk of the card segment the next move is in
  uint32_t chunk_move_ = 0;  // that move's index in its chunk
  int64_t last_event_ = 0;   // the chunk time of the move before
  uint64_t timed_ = 0;       // moves given their times so far (a phase-timer job's fire_cycles)
  std::vector<double> ideal_;
  std::vector<int64_t> chunk_;
  size_t at_ = 0;
  uint64_t moves_ = 0;
  // A streamed job's plan, made again as the clock enters each card segment.
  std::optional<PlanCursor> cursor_;
  const plan::PlannedCardSegment* streamed_card_ = nullptr;
};

// The command words of a job as they are sent, behind `prefix` (the watchdog's
// CONFIG, ...): a whole job's words, or a streamed job's made again card segment
// by card segment (PlanCursor, card::to_wire_segment) into a
// window: the same words as encode_job() of the whole job, in bounded memory.
class WordSource {
 public:
  explicit WordSource(const CardJob& job, std::vector<uint32_t> prefix = {});
  // The words not yet consumed, whole commands: at least `at_least` of them
  // unless the job's last comes first.
  std::span<const uint32_t> window(size_t at_least);
  void consume(size_t n);
  [[nodiscard]] uint64_t total() const { return total_; }
  [[nodiscard]] uint64_t consumed() const { return consumed_; }
  [[nodiscard]] bool exhausted() const { return consumed_ == total_; }
  [[nodiscard]] size_t prefix_words() const { return prefix_; }
  [[nodiscard]] const CardJob& job() const { return job_; }
  // The seconds of motion the card holds, at least (run::buffered_seconds(),
  // with words_handed counted from the job's first word, after the prefix): a
  // streamed job's from the ends of the wire segments this source made, kept
  // from the one the card runs on (calls in the order of the card's replies:
  // segments_done never goes back), so bounded by what the card holds; the
  // segment the card runs counts as done.
  double buffered_seconds(uint64_t segments_done, uint64_t moves_done, uint64_t words_handed);

 private:
  bool make_more();  // the next card segment's words; false at the end

  const CardJob& job_;
  std::vector<uint32_t> buf_;
  size_t at_ = 0;             // first unconsumed word in buf_
  size_t prefix_ = 0;
  uint64_t total_ = 0, consumed_ = 0;
  bool preamble_ = false;     // the preamble made
  bool start_ = false;        // START made
  size_t card_ = 0, wire_ = 0;
  std::vector<card::WireSegment> made_;
  std::optional<PlanCursor> cursor_;  // a streamed job's plan, made again
  bool cards_done_ = false;
  // A streamed job's wire segments made, from segment ends_first_ on: the word
  // just past each one's last (from the job's first word), its end in cycles
  // from START and the moves from START to its end.
  struct SegmentEnd {
    uint64_t word = 0, cycle = 0, moves = 0;
  };
  std::deque<SegmentEnd> ends_;
  uint64_t ends_first_ = 0;
  uint64_t end_cycle_ = 0, end_moves_ = 0;
};

// Every move's ideal and chunk time at once (MoveClock run to the end): for
// tests and for `cpstep check`, which holds a whole trace anyway.
std::vector<double> ideal_cycles(const CardJob& job);
std::vector<int64_t> chunk_cycles(const CardJob& job);

// The seconds of motion the card still holds, at least, while it runs the job
// (card::CardClient::BufferedTime): from its next move (`moves_done` of the
// job's moves are made, `segments_done` of its segments) to the end of the last
// segment whose words are among the first `words_handed` of `job.words`, in
// planned time. A card that stretches moves only holds more. Not for a streamed
// job (WordSource::buffered_seconds).
double buffered_seconds(const CardJob& job, uint64_t segments_done, uint64_t moves_done, uint64_t words_handed);

// The planner's view of a card's capabilities.
plan::CardFacts card_facts(const card::CardCaps& caps);

// Loads the machine and binds it to the card (plan::bind_card(): its clock, W,
// KMAX, pulse timing in its cycles), loads the G-code, plans the job in the card's
// chunk form (card::chunk_limits(): add2 unless the machine's planner.chunk_add2
// is false) and encodes it for that card (its UMAX, KMAX, chunk queue). The card's
// position counters read `start` (absolute steps; a freshly reset card: all 0):
// the first move starts there, and the checkpoints are absolute positions from
// it. Every error refuses the job; warnings travel with the result.
plan::Result<CardJob> prepare_job(const std::filesystem::path& gcode, const std::filesystem::path& machine,
                                  const card::CardCaps& caps = card::default_caps(),
                                  const plan::PerAxis<int64_t>& start = {}, bool streamed = false);

// The steps prepare_job() takes, for callers that change the G-code's blocks
// between reading and planning (run/resume.h):
// the machine file loaded and bound to the card;
plan::Result<plan::Machine> load_card_machine(const std::filesystem::path& machine, const card::CardCaps& caps);
// the G-code read for that machine from a card at `start` (absolute steps);
plan::Result<plan::Job> read_card_gcode(const std::filesystem::path& gcode, const plan::Machine& machine,
                                        const plan::PerAxis<int64_t>& start = {});
// a job's blocks planned and encoded for the card (`start`: where the card is
// when the job has no motion). The warnings are the planner's.
plan::Result<CardJob> plan_card_job(const plan::Job& job, const plan::Machine& machine, const card::CardCaps& caps,
                                    const plan::PerAxis<int64_t>& start = {}, bool streamed = false);

// The command stream as little-endian 32-bit words (the `file` transport and
// `cpstep plan -o`). Returns false when the file cannot be written.
bool write_words(const std::filesystem::path& path, const std::vector<uint32_t>& words);

}  // namespace cpstep::run

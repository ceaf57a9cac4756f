// SPDX-License-Identifier: MIT
// A G-code job made ready for the card: planned with the card's chunk form,
// converted to wire segments and encoded as command words, with what a run
// needs to check the card against the plan (ideal move times, the position
// after every card segment).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "card/job.h"
#include "plan/common.h"
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
  std::vector<double> ideal_cycles;      // per move: the planner's ideal time from START
  std::vector<int64_t> chunk_cycles;     // per move: the time its chunks realize
  std::vector<Checkpoint> checkpoints;   // one per planned card segment
  plan::PerAxis<int64_t> start{};        // absolute steps the job was planned from (the card's position)
  // Per wire segment (the SEGMENT commands of `words`, in order): the word
  // index just past its last word, its end in cycles from START, and the card's
  // moves from START to its end (pause moves included, as the card counts).
  std::vector<uint64_t> segment_end_word;
  std::vector<uint64_t> segment_end_cycle;
  std::vector<uint64_t> segment_end_moves;
  std::vector<plan::Diagnostic> warnings;  // the planner's (also in the Result)
  std::string feed_ramp_note;              // how the feed ramp was fitted (run::fit_feed_ramp)

  [[nodiscard]] uint64_t moves() const { return planned.stats.moves; }
  // Every move the card makes and counts: those that step and the pause moves.
  [[nodiscard]] uint64_t card_moves() const { return planned.stats.moves + planned.stats.pause_moves; }
  [[nodiscard]] uint64_t wire_chunks() const;
  card::CardCaps caps;                   // the card it is planned for
  [[nodiscard]] double clock_hz() const { return machine.card.clock_hz; }
};

// The seconds of motion the card still holds, at least, while it runs the job
// (card::CardClient::BufferedTime): from its next move (`moves_done` of the
// job's moves are made, `segments_done` of its segments) to the end of the last
// segment whose words are among the first `words_handed` of `job.words`, in
// planned time. A card that stretches moves only holds more.
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
                                  const plan::PerAxis<int64_t>& start = {});

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
                                    const plan::PerAxis<int64_t>& start = {});

// The command stream as little-endian 32-bit words (the `file` transport and
// `cpstep plan -o`). Returns false when the file cannot be written.
bool write_words(const std::filesystem::path& path, const std::vector<uint32_t>& words);

}  // namespace cpstep::run

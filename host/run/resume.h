// SPDX-License-Identifier: MIT
// A cut job's contours, and runs of some of them (docs/PLASMA.md "Resume"):
// `cpstep run --state` records how many contours the card completed and where
// it stopped, `--stop-after-contours K` ends a run after the K-th, and
// `--resume STATE` runs those after the completed ones, beginning with a rapid
// from where the machine stopped to the next contour's pierce point.
//
// A contour is a maximal run of G-code blocks with the torch on (the spindle,
// M3/M4 until M5, or digital output P0, M62-M65): one pierce and the cut it
// starts. The job is read by the G-code interpreter as a whole, from where its
// first run began, and its blocks (every modal state resolved) are cut; no
// G-code text is spliced.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "plan/gcode.h"
#include "run/card_job.h"
#include "run/run_state.h"
#include "run/sim_run.h"

namespace cpstep::run {

struct Contour {
  size_t first_block = 0, last_block = 0;  // in Job::blocks, both included
  int m5_line = 0;  // the line that switches the torch off after it: M5 (or M63/M65, M2/M30); else its last block's
};

// Whether the torch is on while the block runs.
bool torch_on(const plan::MotionBlock& b);

// The job's contours in order; `text` is its G-code (the M5 lines are found there).
std::vector<Contour> find_contours(const plan::Job& job, std::string_view text);

// Per contour of a planned job, in order: the card's moves from START (pause
// moves included, as the card counts them) when the contour's last move is made.
std::vector<uint64_t> contour_end_moves(const CardJob& job);

// Why a state cannot go on with a job of these bytes ("" when it can): their
// FNV-1a 64 is not the state's.
std::string job_changed(const RunState& state, std::string_view job_bytes, const std::string& state_file);

// The contours completed once the card has made `moves_done` moves.
size_t contours_done(const std::vector<uint64_t>& ends, uint64_t moves_done);

// Which contours a run covers.
struct ContourSelection {
  size_t done = 0;         // contours completed before (0 unless resumed)
  size_t stop_after = 0;   // end after the last block of this contour of the job; 0: at the job's end
  // Resumed: where the machine stands (machine mm). The run begins with a rapid
  // (G0, every axis at once) from there to contour done + 1's first block.
  std::optional<plan::PerAxis<double>> from_mm;
};

// The blocks the selection runs: the job's own from its start (not resumed), or
// the rapid and then contour done + 1's blocks on (resumed); in both up to the
// last block of contour stop_after, or to the job's end.
plan::Job select_contours(const plan::Job& job, const std::vector<Contour>& contours, const ContourSelection& s);

// A run planned by contours.
struct ContourPlan {
  CardJob job;                          // planned from `start`
  plan::PerAxis<int64_t> start{};       // machine steps the run begins at
  plan::PerAxis<int64_t> job_start{};   // machine steps the job's first run began at (it is read from there)
  std::string job_hash;                 // fnv1a64_hex of the job's bytes
  std::vector<Contour> contours;        // the job's
  size_t first = 0;                     // contours completed before the run
  size_t last = 0;                      // the run ends after this contour (contours.size(): the job's end)
  std::vector<uint64_t> ends;           // contour_end_moves(job): contours first + 1 .. last
  bool resumed = false;
  plan::PerAxis<double> pierce_mm{};    // resumed: contour first + 1's pierce point
  plan::SourceLoc pierce_loc;           // resumed: the block the rapid stands for (the G0 to it)
};

struct ContourOptions {
  std::filesystem::path gcode, machine;
  const RunState* resume = nullptr;     // continue the run this state records
  std::string state_file;               // where `resume` was read (named in errors)
  size_t stop_after = 0;                // end after this contour of the job; 0: at the job's end
};

// Reads the job (resumed: from the state's job_start, refused when its bytes
// changed, its contours are fewer than the state's completed ones, or the
// machine's steps per mm are not the state's) and plans the selected contours
// from `start` (machine steps; resumed: the state's position) for the card.
// When nothing is left to run, it plans nothing and `nothing_left` says why.
plan::Result<ContourPlan> plan_contours(const ContourOptions& o, const card::CardCaps& caps,
                                        const plan::PerAxis<int64_t>& start, std::string& nothing_left);

// The state after a run of the plan (run.position in machine steps).
RunState state_after(const ContourPlan& plan, const CardRun& run, const std::string& job_file,
                     const std::string& machine_file);

// The simulated card starts every run at 0: the job as that card counts it
// when 0 stands for the job's start (checkpoints moved by -start, start 0), and
// the run's positions moved back to machine steps.
CardJob counted_from_zero(const CardJob& job);
void add_origin(CardRun& run, const plan::PerAxis<int64_t>& origin);

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
// `cpstep run --state FILE`, `--resume FILE` and `--stop-after-contours K`
// (docs/PLASMA.md "Resume"): the state read before anything is sent, the run
// planned by contours (run/resume.h), the state written after the run.
#pragma once

#include <optional>
#include <string>

#include "cli/run_command.h"
#include "run/resume.h"

namespace cpstep::cli {

class ContourRun {
 public:
  explicit ContourRun(const RunOptions& o) : o_(o) {}

  // Whether any of the three options is given (else the run is as without them).
  [[nodiscard]] bool active() const;
  // Reads --resume's state and checks it against the job's bytes, before any
  // card is touched. nullopt to go on, else the exit code: 2 with the error
  // printed, 0 when the state says the job finished (said on stdout).
  std::optional<int> open();
  // A real card must stand where the state says the machine stopped; prints
  // why not.
  [[nodiscard]] bool card_matches(const plan::PerAxis<int64_t>& card_position) const;
  // Plans the selected contours from the card's position (the simulated card:
  // 0, the plan then starts at the state's position and is run counted from
  // there). No value, no errors: nothing is left to resume (said on stdout).
  plan::Result<run::CardJob> plan(const card::CardCaps& caps, const plan::PerAxis<int64_t>& card_position);
  [[nodiscard]] bool nothing_left() const { return !nothing_left_.empty(); }
  // run::run_on_sim, on a card counted from the plan's start when it is not 0;
  // the run's positions are machine steps.
  [[nodiscard]] run::CardRun run_sim(const run::CardJob& job, const run::SimRunOptions& options) const;
  // Prints the contours' lines and writes --state; returns rc, or 1 when the
  // state cannot be written.
  int finish(const run::CardRun& run, int rc) const;

 private:
  const RunOptions& o_;
  std::optional<run::RunState> state_;
  std::optional<run::ContourPlan> plan_;
  std::string nothing_left_;
};

}  // namespace cpstep::cli

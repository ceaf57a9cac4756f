// SPDX-License-Identifier: MIT
#include "cli/run_contours.h"
#include "run/measure.h"

#include <fmt/format.h>

#include <cstdio>

namespace cpstep::cli {

namespace {

std::string mm_text(const plan::PerAxis<double>& p, const plan::Machine& m) {
  std::string s;
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present) s += fmt::format("{}{}={:.4f}", s.empty() ? "" : " ", plan::kAxisLetters[a], p[a]);
  return s + " mm";
}

}  // namespace

bool ContourRun::active() const { return !o_.state.empty() || !o_.resume.empty() || o_.stop_after_contours > 0; }

std::optional<int> ContourRun::open() {
  if (o_.resume.empty()) return std::nullopt;
  auto s = run::read_state(o_.resume);
  if (!s.ok()) {
    for (const plan::Diagnostic& e : s.errors) fmt::print(stderr, "cpstep run: --resume {}\n", e.str());
    return 2;
  }
  state_ = std::move(*s.value);
  const auto bytes = run::read_bytes(o_.job);
  if (const std::string why = bytes ? run::job_changed(*state_, *bytes, o_.resume) : ""; !why.empty()) {
    fmt::print(stderr, "cpstep run: {}: {}\n", o_.job, why);
    return 2;
  }
  if (bytes && state_->ended == run::RunEnd::finished) {
    nothing_left_ = fmt::format("{} says the run finished the job", o_.resume);
    fmt::print("cpstep run: nothing to resume: {}\n", nothing_left_);
    return 0;
  }
  return std::nullopt;  // an unreadable job is refused where it is planned
}

bool ContourRun::card_matches(const plan::PerAxis<int64_t>& card) const {
  if (!state_ || card == state_->position) return true;
  const auto steps = [this](const plan::PerAxis<int64_t>& p) {
    std::string s;
    for (int a = 0; a < plan::kAxes; ++a)
      if (state_->axes[a] || p[a] != 0) s += fmt::format("{}{}={}", s.empty() ? "" : " ", plan::kAxisLetters[a], p[a]);
    return s;
  };
  fmt::print(stderr,
             "cpstep run: --resume {}: the card is at {} steps, but the state says the machine stopped at {}; "
             "nothing was sent (the card must stand where the interrupted run left it)\n",
             o_.resume, steps(card), steps(state_->position));
  return false;
}

plan::Result<run::CardJob> ContourRun::plan(const card::CardCaps& caps, const plan::PerAxis<int64_t>& card) {
  run::ContourOptions co;
  co.gcode = o_.job;
  co.machine = o_.machine;
  co.resume = state_ ? &*state_ : nullptr;
  co.state_file = o_.resume;
  co.stop_after = o_.stop_after_contours;
  auto p = run::plan_contours(co, caps, card, nothing_left_);
  plan::Result<run::CardJob> r;
  r.warnings = std::move(p.warnings);
  r.errors = std::move(p.errors);
  if (!nothing_left_.empty()) fmt::print("cpstep run: nothing to resume: {}\n", nothing_left_);
  if (!p.value) return r;
  plan_ = std::move(*p.value);
  r.value = plan_->job;
  return r;
}

run::CardRun ContourRun::run_sim(const run::CardJob& job, const run::SimRunOptions& options) const {
  if (job.start == plan::PerAxis<int64_t>{}) return run::run_on_sim(job, options);
  if (options.meter) options.meter->set_origin(job.start);
  run::CardRun r = run::run_on_sim(run::counted_from_zero(job), options);
  run::add_origin(r, job.start);
  return r;
}

int ContourRun::finish(const run::CardRun& r, int rc) const {
  if (!plan_) return rc;
  const run::ContourPlan& p = *plan_;
  const plan::Machine& m = p.job.machine;
  const run::RunState s = run::state_after(p, r, o_.job, o_.machine);
  const size_t total = p.contours.size();
  if (p.resumed)
    fmt::print("resumed    from {}: {} of {} contours done; a rapid from {} to contour {}'s pierce point {} "
               "(line {})\n",
               o_.resume, p.first, total, mm_text(state_->position_mm(), m), p.first + 1, mm_text(p.pierce_mm, m),
               p.pierce_loc.line);
  fmt::print("contours   {} of {} done ({} in this run)", s.contours_completed, total, s.contours_completed - p.first);
  if (s.contours_completed > 0) fmt::print("; contour {}'s M5 at line {}", s.contours_completed, s.last_m5_line);
  if (s.ended == run::RunEnd::stopped)
    fmt::print("; stopped after contour {} (--stop-after-contours)", p.last);
  fmt::print("\n");
  if (o_.state.empty()) return rc;
  if (const std::string why = run::write_state(o_.state, s); !why.empty()) {
    std::fflush(stdout);
    fmt::print(stderr, "cpstep run: --state: {}\n", why);
    return 1;
  }
  fmt::print("state      {} (ended: {}{})\n", o_.state, run::run_end_name(s.ended),
             s.ended == run::RunEnd::finished ? "" : fmt::format("; --resume {} continues the job", o_.state));
  return rc;
}

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
// Feed hold and resume at the fastest point of every example job (issue 12, docs/CORE.md
// "Feed hold and override"): each job planned for the hx8k card (which has feed hold)
// with seed002's limits, run on the fast engine once as planned to find, from its
// pins, the time its path speed peaks; then again with HOLD at that time and RESUME
// after the hold has come to a stand. The second run must end where the plan ends
// (every checkpoint, the pins equal to the counters), stand still between the hold's
// ramp and the resume, and keep every axis's velocity, acceleration and jerk measured
// from its STEP pins within the machine's limits (run::measure_run, the same windows
// as the run report's).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "card/caps.h"
#include "run/card_job.h"
#include "run/feed.h"
#include "run/feed_ramp.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

const std::string kSource = CPSTEP_SOURCE_DIR;

class FeedJobs : public ::testing::TestWithParam<const char*> {};

TEST_P(FeedJobs, HoldAtTheFastestPointKeepsEveryLimitAndThePath) {
  const card::CardCaps caps = *card::board_caps("hx8k");
  auto prepared = run::prepare_job(kSource + "/examples/jobs/" + GetParam(),
                                   kSource + "/examples/machines/seed002.toml", caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  run::CardJob& job = *prepared.value;
  ASSERT_TRUE(job.machine.card.feed);
  // As cpstep run does: the ramp fitted to the job's fastest point.
  const run::JobFeedRamp fit = run::fit_feed_ramp(job);
  ASSERT_TRUE(fit.fitted) << fit.note;
  EXPECT_GE(fit.slower, 1.0);
  EXPECT_LE(fit.ramp.rate_per_s(), fit.cruise.rate_per_s * fit.cruise.span);
  run::SimRunOptions o;
  o.board = "hx8k";
  const run::CardRun plain = run::run_on_sim(job, o);
  ASSERT_TRUE(plain.ok()) << plain.faults.front().message;
  run::RunMeter meter(job);
  run::replay(plain, meter);
  meter.finish(plain);
  const run::KinematicSeries ks = meter.series();
  ASSERT_FALSE(ks.path_v.empty());
  const size_t fastest = run::fastest_point(job, ks);
  EXPECT_DOUBLE_EQ(ks.t[fastest], fit.fastest_s);
  const double t_hold = ks.t[fastest], v_peak = ks.path_v[fastest];
  // The hold ramps down in hold_s (docs/CORE.md): stand for as long again, then resume.
  const double ramp_s = job.machine.feed.ramp.hold_s();
  ASSERT_GT(ramp_s, 0);
  const double t_resume = t_hold + ramp_s + 0.5;
  o.feed = run::parse_feed_events(fmt::format("{}:hold,{}:resume", t_hold, t_resume));
  const run::CardRun held = run::run_on_sim(job, o);
  ASSERT_TRUE(held.ok()) << held.faults.front().name << ": " << held.faults.front().message;
  EXPECT_TRUE(held.feed_scaled);
  EXPECT_EQ(held.moves_done, plain.moves_done);
  EXPECT_EQ(held.position, plain.position);
  EXPECT_EQ(held.checked_segments, job.checkpoints.size());
  const double tau = job.machine.feed.ramp.tau_s;
  // A hold covers 2 tau of planned time on its way to the stand: a job that ends
  // sooner than that after the hold ends during it (no RESUME is sent after the end).
  const double left_s = double(plain.cycles - plain.start_cycle) / job.clock_hz() - t_hold;
  if (held.feed.size() == 1) {
    EXPECT_LT(left_s, 2.2 * tau) << "the job ended while holding, so it was near its end";
  } else {
    ASSERT_EQ(held.feed.size(), 2u);
    EXPECT_GT(left_s, 1.8 * tau);
    // It stood: no move event from the end of the hold's ramp (taken + hold_s) to the
    // resume; and it took longer by at least that time.
    const double hz = job.clock_hz();
    const double stood_from = held.start_cycle + (held.feed[0].taken_s + ramp_s) * hz;
    const double stood_to = held.start_cycle + held.feed[1].taken_s * hz;
    const auto in_hold = std::count_if(held.move_cycles.begin(), held.move_cycles.end(), [&](uint64_t c) {
      return double(c) > stood_from && double(c) < stood_to;
    });
    EXPECT_EQ(in_hold, 0) << "moves while held";
    EXPECT_GT(held.cycles, plain.cycles + uint64_t((stood_to - stood_from)));
  }
  const run::RunMeasure hm = run::measure_run(job, held);
  for (int a = 0; a < plan::kAxes; ++a) {
    const run::AxisMeasure& ax = hm.axes[a];
    if (!ax.present || ax.pulses == 0) continue;
    EXPECT_TRUE(ax.within_limits) << GetParam() << " axis " << plan::kAxisLetters[a] << ": v " << ax.peak.v
                                  << " a " << ax.peak.a << " j " << ax.peak.j << " (held at " << t_hold
                                  << " s, path speed " << v_peak << " mm/s)";
  }
  RecordProperty("hold_at_s", fmt::format("{:.4f}", t_hold));
  RecordProperty("path_speed_mm_s", fmt::format("{:.2f}", v_peak));
}

INSTANTIATE_TEST_SUITE_P(Examples, FeedJobs,
                         ::testing::Values("tab.ngc", "bracket.ngc", "plasma.ngc", "tight_arcs.ngc", "naca0025.ngc",
                                           "dense.ngc"),
                         [](const auto& p) {
                           std::string n = p.param;
                           return n.substr(0, n.find('.'));
                         });

}  // namespace
}  // namespace cpstep::tb

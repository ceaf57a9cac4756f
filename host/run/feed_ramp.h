// SPDX-License-Identifier: MIT
// The feed ramp fitted to a job (docs/CORE.md "Feed hold and override"). The card's
// scale s changes each axis's realized motion to a = a_p s^2 + v_p ds/dt and
// j = j_p s^3 + 3 a_p s ds/dt + v_p d2s/dt2 (v_p, a_p, j_p the plan's, at the planned
// time the warped clock has reached), so a ramp derived at cruise alone
// (plan::feed_limits) can break the limits where the plan itself accelerates, e.g.
// around a curve. The host runs the job once on the fast engine (the card's golden
// model: the pins the card will make), measures each axis's v, a, j from those pins,
// and at the job's fastest point (fastest_point) plays a HOLD and a RESUME through
// those sums with the card's ramp (s = (1 + t/tau) e^(-t/tau) down, its mirror up): the
// cruise ramp's tau times the smallest m >= 1 (bisection) that keeps every axis within
// 95 % of its acceleration and jerk limits (or within what the plan reaches there,
// when more).
#pragma once

#include <string>

#include "plan/feed.h"
#include "run/card_job.h"
#include "run/measure.h"

namespace cpstep::run {

struct JobFeedRamp {
  bool fitted = false;          // false: the card has no feed, or the dry run failed (the machine's ramp stays)
  double fastest_s = 0;         // the fastest point, seconds from START
  double speed_mm_s = 0;        // the path speed there
  plan::FeedLimits cruise;      // the machine's (plan::feed_limits)
  double slower = 1;            // m: the fitted tau over the cruise one
  plan::FeedRamp ramp;          // what the card gets (CONFIG field 9)
  std::string note;             // why it is slower than at cruise, or why it was not fitted
};

// The job's fastest point in the series of a run of it (an index of ks.t): the
// fastest sample where the machine cruises, i.e. where the plan asks at most half of
// any axis's acceleration and jerk limits for as long as a hold at the cruise ramp
// takes, and half as long again; without one, the sample within 1 % of the top path
// speed that asks the least. (A hold where the plan itself accelerates at its limits
// adds to them: docs/CORE.md "Feed hold and override".)
size_t fastest_point(const CardJob& job, const KinematicSeries& ks);

// Fits the ramp to `job` (a card with feed) and writes it into job.machine.feed.ramp and
// the job's CONFIG word of field 9. Runs the job on the fast engine once.
JobFeedRamp fit_feed_ramp(CardJob& job);

}  // namespace cpstep::run

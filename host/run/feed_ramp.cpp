// SPDX-License-Identifier: MIT
#include "run/feed_ramp.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "card/caps.h"
#include "card/protocol.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::run {

namespace {

// Rewrites the job's CONFIG word of field 9 (among the setup words before the first
// segment) with the ramp's tick.
void patch_ramp_words(CardJob& job, const plan::FeedRamp& ramp) {
  for (uint32_t& w : job.words) {
    const uint32_t op = w >> 28;
    if (op != 0x2 && op != 0x3) break;  // CONFIG and CONTROL lead; a segment ends the setup
    if (op == 0x2 && (w >> 20 & 0xF) == uint32_t(card::ConfigField::feed_tick)) w = (w & ~0xFFFFu) | ramp.tick;
  }
}

}  // namespace

size_t fastest_point(const CardJob& job, const KinematicSeries& ks) {
  if (ks.path_v.empty()) return 0;
  // Each sample's share of the limits the plan uses (the largest over the axes).
  std::vector<double> share(ks.t.size(), 0.0);
  for (size_t k = 0; k < ks.t.size(); ++k)
    for (int x = 0; x < plan::kAxes; ++x) {
      const plan::AxisConfig& ax = job.machine.axes[x];
      if (!ax.present || ks.v[x].empty()) continue;
      share[k] = std::max({share[k], std::abs(ks.a[x][k]) / ax.max_accel, std::abs(ks.j[x][k]) / ax.max_jerk});
    }
  // The window a hold at the cruise ramp takes to come within 1 % of a stand (6.6 tau),
  // half as long again.
  const plan::FeedLimits c = plan::feed_limits(job.machine);
  const std::optional<plan::FeedRamp> r = plan::feed_ramp(job.clock_hz(), c.rate_per_s, c.accel_per_s2, c.span);
  const double span = 1.5 * 6.6 * (r ? r->tau_s : 0.1);
  const double dt = ks.t.size() > 1 ? ks.t[1] - ks.t[0] : 1e-3;
  const size_t ahead = std::max<size_t>(1, size_t(span / dt));
  size_t best = 0, calmest = 0;
  double best_v = -1, calmest_share = std::numeric_limits<double>::infinity();
  const double top = *std::max_element(ks.path_v.begin(), ks.path_v.end());
  for (size_t k = 0; k < ks.t.size(); ++k) {
    double w = 0;
    for (size_t i = k; i < std::min(ks.t.size(), k + ahead); ++i) w = std::max(w, share[i]);
    if (w <= 0.5 && ks.path_v[k] > best_v) {
      best_v = ks.path_v[k];
      best = k;
    }
    if (ks.path_v[k] >= 0.99 * top && w < calmest_share) {
      calmest_share = w;
      calmest = k;
    }
  }
  return best_v > 0 ? best : calmest;
}

JobFeedRamp fit_feed_ramp(CardJob& job) {
  JobFeedRamp out;
  if (!job.machine.card.feed) return out;
  out.cruise = plan::feed_limits(job.machine);
  SimRunOptions o;
  o.engine = Engine::model;
  // The simulated card starts at 0: the job as if planned from there.
  CardJob dry_job = job;
  for (Checkpoint& cp : dry_job.checkpoints)
    for (int x = 0; x < plan::kAxes; ++x) cp.position[x] -= job.start[x];
  for (int x = 0; x < plan::kAxes; ++x) dry_job.final_position[x] -= job.start[x];
  dry_job.start = {};  // a streamed job's checkpoints are made from it
  RunMeter meter(job, false);  // the series alone
  o.meter = &meter;
  o.record_pins = false;
  const CardRun dry = run_on_sim(dry_job, o);
  if (!dry.ok()) {
    out.note = "the dry run on the fast engine failed: the machine's ramp stays";
    job.feed_ramp_note = out.note;
    return out;
  }
  meter.finish(dry);
  const KinematicSeries ks = meter.series();
  if (ks.path_v.empty()) return out;
  const size_t fastest = fastest_point(job, ks);
  out.fastest_s = ks.t[fastest];
  out.speed_mm_s = ks.path_v[fastest];
  const std::optional<plan::FeedRamp> cruise =
      plan::feed_ramp(job.clock_hz(), out.cruise.rate_per_s, out.cruise.accel_per_s2, out.cruise.span);
  if (!cruise) {
    out.note = "no ramp the card's tick field holds fits the machine's limits";
    job.feed_ramp_note = out.note;
    return out;
  }
  // The dry run's measured per-axis v, a, j, warped by a HOLD at the fastest point and
  // a RESUME after it with the card's ramp of time constant tau (continuous: s = (1 + x)
  // e^-x, x = t / tau, down; 1 - that, up).
  const double dt = ks.t.size() > 1 ? ks.t[1] - ks.t[0] : 1e-3;
  const auto at = [&](const std::vector<double>& y, double tau) {
    const double x = (tau - ks.t[0]) / dt;
    if (x <= 0) return y.front();
    const size_t k = size_t(x);
    if (k + 1 >= y.size()) return y.back();
    return y[k] + (y[k + 1] - y[k]) * (x - double(k));
  };
  // The worst share of a limit (acceleration or jerk, any axis) a ramp of time constant
  // tau reaches.
  const auto worst = [&](double tau) {
    double w = 0, planned = out.fastest_s;
    const double h = std::min(dt / 4, tau / 50);
    for (int leg = 0; leg < 2; ++leg) {
      for (double t = 0; t < 17 * tau; t += h) {
        const double x = t / tau, e = std::exp(-x);
        const double down = (1 + x) * e;
        const double s = leg == 0 ? down : 1 - down;
        const double sd = (leg == 0 ? -1 : 1) * x * e / tau;
        const double sdd = (leg == 0 ? -1 : 1) * (1 - x) * e / (tau * tau);
        for (int a = 0; a < plan::kAxes; ++a) {
          const plan::AxisConfig& ax = job.machine.axes[a];
          if (!ax.present || ks.v[a].empty()) continue;
          const double vp = at(ks.v[a], planned), ap = at(ks.a[a], planned), jp = at(ks.j[a], planned);
          const double ra = ap * s * s + vp * sd;
          const double rj = jp * s * s * s + 3 * ap * s * sd + vp * sdd;
          w = std::max({w, std::abs(ra) / ax.max_accel, std::abs(rj) / ax.max_jerk});
        }
        planned += s * h;
      }
    }
    return w;
  };
  // The plan alone over the hold's reach (s = 1): what the ramp adds to. The smallest m
  // (doubling, then bisecting) whose hold and resume stay within 95 % of every limit,
  // or within what the plan itself reaches there when that is more.
  double base = 0;
  for (size_t k = 0; k < ks.t.size(); ++k) {
    if (ks.t[k] < out.fastest_s || ks.t[k] > out.fastest_s + cruise->hold_s()) continue;
    for (int a = 0; a < plan::kAxes; ++a) {
      const plan::AxisConfig& ax = job.machine.axes[a];
      if (!ax.present || ks.v[a].empty()) continue;
      base = std::max({base, std::abs(ks.a[a][k]) / ax.max_accel, std::abs(ks.j[a][k]) / ax.max_jerk});
    }
  }
  const double bound = std::max(0.95, base);
  const double most = 65535.0 * double(1u << plan::kFeedShift) / job.clock_hz() / cruise->tau_s;
  double lo = 1, hi = 1;
  if (worst(cruise->tau_s) > bound) {
    while (hi < most && worst(cruise->tau_s * hi) > bound) {
      lo = hi;
      hi = std::min(most, 2 * hi);
    }
    if (worst(cruise->tau_s * hi) > bound) {
      out.note = fmt::format("the plan itself is at its limits near its fastest point ({:.3f} s): the slowest "
                             "ramp the tick field holds",
                             out.fastest_s);
      lo = hi;
    } else {
      for (int b = 0; b < 12; ++b) {
        const double m = 0.5 * (lo + hi);
        (worst(cruise->tau_s * m) <= bound ? hi : lo) = m;
      }
    }
  }
  out.slower = hi;
  const std::optional<plan::FeedRamp> fitted = plan::feed_ramp_tau(job.clock_hz(), cruise->tau_s * hi, out.cruise.span);
  if (!fitted) {
    out.note = "no ramp the card's tick field holds fits the job: the machine's ramp stays";
    job.feed_ramp_note = out.note;
    return out;
  }
  out.ramp = *fitted;
  out.fitted = true;
  if (out.note.empty() && hi > 1)
    out.note = fmt::format("{:.3g} times the cruise ramp's time: the plan's own acceleration and jerk at its fastest "
                           "point ({:.3f} s, {:.1f} mm/s) leave that much room",
                           hi, out.fastest_s, out.speed_mm_s);
  job.machine.feed.ramp = out.ramp;
  patch_ramp_words(job, out.ramp);
  job.feed_ramp_note = out.note;
  return out;
}

}  // namespace cpstep::run

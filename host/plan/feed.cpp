// SPDX-License-Identifier: MIT
#include "plan/feed.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "plan/machine.h"

namespace cpstep::plan {

namespace {
constexpr double kStageTicks = double(1u << kFeedShift);  // tau in ticks
}  // namespace

double FeedRamp::rate_per_s() const { return tau_s > 0 ? span / (std::exp(1.0) * tau_s) : 0; }
double FeedRamp::accel_per_s2() const { return tau_s > 0 ? span / (tau_s * tau_s) : 0; }

std::optional<FeedRamp> feed_ramp_tau(double clock_hz, double tau_s, double span) {
    if (!(clock_hz > 0) || !(tau_s > 0) || !(span > 0)) return std::nullopt;
    const double t = std::max(1.0, std::ceil(tau_s * clock_hz / kStageTicks));
    if (t > 65535) return std::nullopt;
    FeedRamp r;
    r.tick = static_cast<std::uint32_t>(t);
    r.tau_s = t * kStageTicks / clock_hz;
    r.span = span;
    return r;
}

std::optional<FeedRamp> feed_ramp(double clock_hz, double rate_per_s, double accel_per_s2, double span) {
    if (!(rate_per_s > 0) || !(accel_per_s2 > 0)) return std::nullopt;
    const double tau = std::max(span / (std::exp(1.0) * rate_per_s), std::sqrt(span / accel_per_s2));
    return feed_ramp_tau(clock_hz, tau, span);
}

FeedLimits feed_limits(const Machine& m) {
    FeedLimits l{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 std::max(1.0, m.feed.max_override)};
    for (const AxisConfig& ax : m.axes) {
        if (!ax.present || !(ax.max_velocity > 0)) continue;
        l.rate_per_s = std::min(l.rate_per_s, ax.max_accel / ax.max_velocity);
        l.accel_per_s2 = std::min(l.accel_per_s2, ax.max_jerk / ax.max_velocity);
    }
    return l;
}

}  // namespace cpstep::plan

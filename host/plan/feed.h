// SPDX-License-Identifier: MIT
// The card's feed ramp (docs/CORE.md "Feed hold and override"): the tick period T
// (CONFIG field 9) of the card's two first-order stages (each moves 2^-10 of its
// distance a tick), a critically damped ramp of time constant tau = 2^10 T / f. A
// change of the scale by D then runs at a rate of at most D / (e tau) and a rate of
// rate of at most D / tau^2, both from 0, monotonically onto the target.
#pragma once

#include <cstdint>
#include <optional>

namespace cpstep::plan {

struct Machine;

struct FeedRamp {
    std::uint32_t tick = 0;   // clocks a tick (field 9)
    double tau_s = 0;         // the stages' time constant, 2^10 tick / f
    double span = 1;          // D: the largest change of scale it was chosen for (the largest override)
    // What the card then does for a change of `span`, at most.
    [[nodiscard]] double rate_per_s() const;    // |ds/dt| <= D / (e tau)
    [[nodiscard]] double accel_per_s2() const;  // |d2s/dt2| <= D / tau^2
    // A hold from s = 1 to its stand (the last stage within 2^-20 of 0: (1 + x) e^-x
    // = 2^-20 at x = 16.9): 16.9 tau.
    [[nodiscard]] double hold_s() const { return 16.9 * tau_s; }
};

// The stages' shift: each moves 2^-kFeedShift of its distance a tick.
inline constexpr unsigned kFeedShift = 10;

// The slowest ramp's tick for a card clocked at clock_hz whose scale may change by up
// to `span` at most at `rate_per_s` and `accel_per_s2`: tau = max(span / (e rate),
// sqrt(span / accel)), the tick rounded up. nullopt when the tick exceeds 65535 clocks.
std::optional<FeedRamp> feed_ramp(double clock_hz, double rate_per_s, double accel_per_s2, double span);
// The ramp with its time constant at least tau_s (rounded up to a whole tick).
std::optional<FeedRamp> feed_ramp_tau(double clock_hz, double tau_s, double span);

// The limits a machine puts on s: an axis moving at v has acceleration v·ds/dt and
// jerk v·d2s/dt2 from the ramp where its plan cruises (docs/CORE.md), so with every
// axis at its max_velocity, the smallest max_accel / v and max_jerk / v over the
// axes; span: the largest override (feed.max_override, at least 1).
struct FeedLimits {
    double rate_per_s = 0, accel_per_s2 = 0, span = 1;
};
FeedLimits feed_limits(const Machine& m);

}  // namespace cpstep::plan

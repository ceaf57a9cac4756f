// SPDX-License-Identifier: MIT
// Seed 002's 7-phase jerk-limited feed profile over one path segment, in
// closed form per phase: jerk +J, 0, -J (accelerate), 0 (cruise), -J, 0, +J
// (decelerate). Acceleration is zero at both ends of every profile that
// make_profile() builds; a slice() of one (a segment's share of a profile over
// several segments) may start and end with any acceleration.
#pragma once

#include <array>
#include <optional>

namespace cpstep::plan {

// A speed change from va to vb that starts and ends at zero acceleration.
struct Ramp {
    double t_jerk = 0;    // each jerk phase
    double t_const = 0;   // the constant-acceleration phase (0 when A is not reached)
    double a_peak = 0;    // |acceleration| reached
    double duration = 0;
    double distance = 0;  // = (va + vb) / 2 * duration by the ramp's symmetry
};

// Closed form: A is reached when |vb - va| >= A^2 / J, else the peak is sqrt(J |vb - va|).
Ramp ramp(double va, double vb, double A, double J);

// Largest speed reachable from v_from (up or down, the ramp is symmetric)
// within distance L, capped at `cap`.
double reachable_speed(double v_from, double L, double A, double J, double cap);

struct Phase {
    double duration = 0;
    double jerk = 0;
    // State at the phase's start.
    double t0 = 0, s0 = 0, v0 = 0, a0 = 0;
};

struct KinState {
    double s = 0, v = 0, a = 0, j = 0;
};

struct Profile {
    std::array<Phase, 7> phases{};
    double length = 0;
    double v_entry = 0;
    double v_exit = 0;
    double v_peak = 0;    // cruise speed actually used (may be below the limit)
    double duration = 0;

    // Position, velocity, acceleration and jerk at time t in [0, duration].
    [[nodiscard]] KinState at(double t) const;
    // The time at which the path reaches s in [0, length] (monotone inverse).
    [[nodiscard]] double time_at(double s) const;
    // The part of this profile between times ta < tb, where the path stands at
    // sa, re-based to start at t = 0, s = 0, of length L: a profile that may
    // start and end with non-zero acceleration (a path-level profile cut at a
    // segment's ends). At most 7 phases, as a 7-phase profile has.
    [[nodiscard]] Profile slice(double ta, double tb, double sa, double L) const;
};

// The profile over length L from v0 to v1 with cruise limit vmax, acceleration
// limit A and jerk limit J. The peak speed is vmax when it fits, else the
// largest that fits (found by bisection over closed-form ramps). nullopt when
// v0 and v1 cannot be joined within L at all, or when no speed is allowed
// (vmax, v0 and v1 all zero) over a length L > 0.
std::optional<Profile> make_profile(double L, double v0, double v1, double vmax, double A, double J);

}  // namespace cpstep::plan

// Feed planning over a whole job: per-segment limits projected from the axes,
// junction speeds from the corner angle (junction deviation, as in Grbl), and
// backward/forward passes so that every exit speed is reachable by the next
// segment. Each segment then gets its 7-phase profile.
#pragma once

#include <vector>

#include "plan/machine.h"
#include "plan/profile.h"
#include "plan/segments.h"

namespace cpstep::plan {

struct SegmentLimits {
    double v = 0, a = 0, j = 0;  // along the path, mm/s, mm/s^2, mm/s^3
};

// The path limits of a move along `delta` (steps): the tightest of every
// moving axis's limit divided by that axis's share of the direction.
SegmentLimits project_limits(const PerAxis<std::int64_t>& delta, const Machine& m);

// Fastest path speed at which no axis exceeds the card's step rate, with the
// chunk tolerance as margin (a move may be that much early).
double card_speed_limit(const PerAxis<std::int64_t>& delta, const Machine& m);

// Speed at which a path bending with radius r (mm) keeps its centripetal
// acceleration v^2/r within a and its jerk v^3/r^2 within j: a polyline's
// radius at a junction is r = L / (2 sin(theta/2)) for chords of length L
// turning by theta (exact for the equal chords of an arc).
double curvature_speed(double r, double a, double j);
double polyline_radius(const PerAxis<double>& in, const PerAxis<double>& out, double chord);

// Grbl's junction-deviation speed for a corner between unit directions
// `in` and `out` (mm space), with acceleration a and deviation delta.
double junction_speed(const PerAxis<double>& in, const PerAxis<double>& out, double a,
                      double deviation);

struct PlannedSegment {
    double length = 0;     // mm
    double t_start = 0;    // s, absolute from the job start
    double duration = 0;   // s
    double cruise = 0;     // the speed limit used for the segment
    SegmentLimits limits;
    Profile profile;       // empty for dwells
};

// Profiles for every step segment (dwells become pauses of their length).
// Feeds above an axis's limit are lowered with a warning; moves beyond the
// card's step rate are refused or slowed according to planner.on_limit.
Result<std::vector<PlannedSegment>> plan_feeds(const std::vector<StepSegment>& segs,
                                               const Machine& m, const std::string& job_file);

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// Feed planning over a whole job: per-segment limits projected from the axes,
// junction speeds from the corner angle (junction deviation, as in Grbl), and
// backward/forward passes so that every exit speed is reachable by the next
// segment. Each segment then gets its 7-phase profile.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <string>
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
// The same for a segment timed over `length` mm of path (StepSegment::
// planned_length_mm): each axis moves |delta_j| / length of its mm per mm of
// path, which need not be a unit vector when length is the unrounded chord's.
SegmentLimits project_limits(const PerAxis<std::int64_t>& delta, double length, const Machine& m);

// Fastest path speed at which no axis exceeds the card's step rate, with the
// chunk tolerance as margin (a move may be that much early).
double card_speed_limit(const PerAxis<std::int64_t>& delta, const Machine& m);
double card_speed_limit(const PerAxis<std::int64_t>& delta, double length, const Machine& m);

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

// Fastest junction speed at which an axis whose direction reverses there (the
// path going on) keeps the card's DIR hold and setup without a stretched move.
// `u` is the axis's share of the outgoing path direction (mm per mm), `a` the
// outgoing segment's acceleration limit. The last step toward the turning
// point may come at the junction itself; the first step back comes once the
// axis has gone back half a step (the card's lattice rounds there), so its
// time is at least d / v_d with d = 1/2 step of path and v_d the speed after
// accelerating over d. Across a reversal the card needs step_high +
// max(max(hold,1) + max(setup,1), step_low) cycles from leading edge to
// leading edge (docs/PULSE.md), plus the chunk tolerance (a move may be
// that much early). 0 when even a start from rest at the junction is too fast
// over d at the acceleration limit.
double reversal_speed(double u, const AxisConfig& axis, double a, const Machine& m);

// What a path bending with radius r leaves of the limits: the cruise cap v
// (at most the given v, and the curvature speed with kCurvatureShare of the
// axes' normal limits a_normal, j_normal), and the tangential acceleration and
// jerk that, added to the centripetal v^2/r, its turning v^3/r^2 and the 3 v a_t / r
// that tangential acceleration causes across the path, stay within the axes'
// limits (docs/PLANNING.md, "Path-level planning").
struct CurvatureBudget {
    double v = 0, a = 0, j = 0;
};
inline constexpr double kCurvatureShare = 0.4;     // of a_normal, j_normal
inline constexpr double kTangentJerkShare = 0.1;   // of the jerk, always left to the tangent
inline constexpr double kSpanRatio = 0.02;         // caps within 2 % share one profile...
inline constexpr double kSpanLossS = 0.002;        // ...while it costs at most 2 ms against them
inline constexpr double kSpanMaxS = 2.0;           // ...and lasts at most 2 s at its caps
CurvatureBudget curvature_budget(double r, double v, const SegmentLimits& tangent, double a_normal,
                                 double j_normal);

// The unit direction of a segment in mm from its unrounded geometry (the
// step delta's when that is empty).
PerAxis<double> path_direction(const StepSegment& s, const Machine& m);

// A lower bound on the duration of any plan of these segments within the
// limits: each segment at most at its feed, its projected axis limit, the
// card's step rate and the curvature speed min(sqrt(A r), cbrt(J r^2)) of the
// larger radius at its ends (A, J: the largest axis limits); corners at their
// junction-deviation speed, stops at zero; jerk relaxed: speed changes with
// the projected acceleration only (v^2 by at most 2 A L). Dwells count whole.
// Segments [first, last) only: a part of a job may start and end at its
// junctions' speeds.
double time_lower_bound(const std::vector<StepSegment>& segs, const Machine& m, std::size_t first = 0,
                        std::size_t last = static_cast<std::size_t>(-1));

struct PlannedSegment {
    double length = 0;     // mm
    double radius = std::numeric_limits<double>::infinity();  // path radius used, mm
    double t_start = 0;    // s, absolute from the job start
    double duration = 0;   // s
    double cruise = 0;     // the speed limit used for the segment
    SegmentLimits limits;  // v: projected; a, j: the tangential budget the profile keeps
    Profile profile;       // empty for dwells
};

// A group covers at most this many spans (2, 4, ... are tried), and the spans
// after its first at most kGroupMaxS at their caps.
inline constexpr std::size_t kMaxGroupSpans = 64;
inline constexpr double kGroupMaxS = 2.0;

struct FeedOptions {
    // The lookahead window grows by spans covering this many times the stopping
    // distance from the window's highest cap at a time; infinity (with
    // max_lookahead_s infinite) plans the whole job in one window. The result
    // does not depend on it (only entries that no later span can change are
    // used, unless max_lookahead_s cuts the window), only the work and the
    // lookahead do.
    double window_stop_factor = 1.0;
    // The farthest the backward pass looks past the span being planned, in time
    // at the caps: a window that reaches this far without making the entries the
    // forward pass needs final makes them final as they stand (from rest at the
    // window's end: slower than the whole job's where that was faster, never
    // infeasible). Infinity: only entries that no later span can change are used.
    double max_lookahead_s = kDefaultMaxLookaheadS;
    static constexpr double kDefaultMaxLookaheadS = 10.0;
};
// A group's spans (and the last one's) lie within the default bound.
static_assert(kGroupMaxS + kSpanMaxS < FeedOptions::kDefaultMaxLookaheadS);

struct FeedStats {
    std::size_t spans = 0, groups = 0;
    std::size_t windows = 0;         // backward passes run
    std::size_t backward_steps = 0;  // span entries computed over all windows
    std::size_t max_lookahead_spans = 0;  // the farthest the backward pass looked past the span being planned
    double max_lookahead_mm = 0, max_lookahead_s = 0;  // the same in path length and in time at the caps
    std::size_t cut_windows = 0;     // windows that reached FeedOptions::max_lookahead_s
};

// Profiles for every step segment (dwells become pauses of their length).
// Feeds above an axis's limit are lowered with a warning; moves beyond the
// card's step rate are refused or slowed according to planner.on_limit.
// The job's segments pushed through a FeedPlanner.
Result<std::vector<PlannedSegment>> plan_feeds(const std::vector<StepSegment>& segs,
                                               const Machine& m, const std::string& job_file,
                                               const FeedOptions& options = {},
                                               FeedStats* stats = nullptr);

// The same plan made as the step segments arrive, one at a time (a job read as
// it is planned): next() hands out each segment's PlannedSegment, in order, as
// soon as nothing after it can change it, bit for bit what plan_feeds() gives.
// It holds the segments from the oldest not yet handed out to the lookahead's
// reach (FeedStats::max_lookahead_*), not the job. A segment's warnings come
// when it is pushed; after an error (a move beyond the card's step rate with
// planner.on_limit = "refuse", or an internal one) nothing more is handed out,
// but pushed segments are still checked, so errors() names every refused block.
// Repeated warnings of one block are given once (a block's segments are
// consecutive).
class FeedPlanner {
public:
    FeedPlanner(const Machine& m, std::string job_file, const FeedOptions& options = {});
    ~FeedPlanner();
    FeedPlanner(FeedPlanner&&) noexcept;
    FeedPlanner& operator=(FeedPlanner&&) noexcept;
    FeedPlanner(const FeedPlanner&) = delete;
    FeedPlanner& operator=(const FeedPlanner&) = delete;

    void push(const StepSegment& s);  // the job's next step segment
    void finish();                    // the job has no more
    std::optional<PlannedSegment> next();

    [[nodiscard]] std::size_t pushed() const;
    [[nodiscard]] std::size_t handed_out() const;
    [[nodiscard]] bool done() const;  // finished, every segment handed out, no error
    [[nodiscard]] const std::vector<Diagnostic>& warnings() const;
    [[nodiscard]] const std::vector<Diagnostic>& errors() const;
    [[nodiscard]] const FeedStats& stats() const;  // spans: once finished
    [[nodiscard]] std::size_t held() const;        // segments held now (in the window, or planned and not handed out)
    [[nodiscard]] std::size_t max_held() const;    // the most held after a push

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cpstep::plan

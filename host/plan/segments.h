// SPDX-License-Identifier: MIT
// Geometry to integer-step segments: arcs become chords within the machine's
// tolerance; every segment end is the absolute target rounded to whole steps,
// so rounding never accumulates.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "plan/gcode.h"
#include "plan/machine.h"

namespace cpstep::plan {

struct StepSegment {
    PerAxis<std::int64_t> start{};   // absolute steps
    PerAxis<std::int64_t> end{};
    MotionKind kind = MotionKind::linear;
    SourceLoc loc;                   // the G-code block it came from
    std::size_t block = 0;           // index into Job::blocks
    double feed = 0;                 // requested mm/s; 0 = as fast as the machine allows
    double dwell_s = 0;              // dwell segments: the pause, no motion
    bool spindle_on = false;
    // The card's torch output while it runs (docs/CORE.md "Torch"): the spindle on
    // (M3/M4) or digital output P0 on (M62-M65).
    bool torch = false;
    // The unrounded geometry (machine mm) the segment was rounded from: its
    // start and end points, and the smallest path radius at the polyline
    // points merged into it and, when both its ends are on a curve, at its
    // ends (infinity: straight; a line ending on a curve is capped at that
    // point only, by its junction). Arcs give their
    // radius from the centre; G1 polylines a circle fitted through
    // neighbouring points (path_radii()).
    PerAxis<double> from_mm{};
    PerAxis<double> to_mm{};
    double radius_mm = std::numeric_limits<double>::infinity();
    double radius_ends_max_mm = std::numeric_limits<double>::infinity();  // the larger of its two ends'
    double radius_start_mm = std::numeric_limits<double>::infinity();     // at its start point
    // A chord of an arc the card walks as a conic (plan_job, plan/conic_arc.h): its
    // moves are the conic's, not a card segment of its own.
    bool conic = false;

    [[nodiscard]] PerAxis<std::int64_t> delta() const;
    // Euclidean length of the quantized segment in mm (over the present axes).
    [[nodiscard]] double length_mm(const Machine& m) const;
    // The length the feed planner times the segment over: the unrounded
    // chord's (from_mm to to_mm), so that the planned speed is the speed along
    // the G-code's geometry and rounding to steps adds no speed ripple from one
    // chord to the next; the quantized length when the unrounded chord is
    // shorter than kMinUnroundedLengthRatio of it (a point rounded across a
    // step boundary). The axes' limits are projected with this length
    // (planner.h, project_limits), so no axis exceeds them either way.
    [[nodiscard]] double planned_length_mm(const Machine& m) const;
};

inline constexpr double kMinUnroundedLengthRatio = 0.5;

// round(mm * steps_per_mm), halves away from -infinity (floor(x + 0.5)).
std::int64_t mm_to_steps(double mm, double steps_per_mm);

// An arc's geometry in its plane (G17/G18/G19): u, v its two axes (the others
// move linearly), the centre, the end radii, the start angle and the sweep
// (positive, 2 pi for a full circle), in the arc's own direction (cw: the angle
// atan2(v, u) decreases).
struct ArcGeom {
    std::size_t u = 0, v = 1;
    double cx = 0, cy = 0, r0 = 0, r1 = 0, a0 = 0, sweep = 0;
    bool cw = false;
    // The point at fraction `frac` of the sweep (the radius interpolated).
    [[nodiscard]] PerAxis<double> at(const MotionBlock& b, double frac) const;
};
ArcGeom arc_geom(const MotionBlock& b);

// The chord end points of an arc block (the block's start excluded, its exact
// end included), each within `tolerance_mm` of the arc.
std::vector<PerAxis<double>> arc_chord_points(const MotionBlock& arc, double tolerance_mm);

// The chord end points of a nurbs block (its start excluded, its exact end
// included), each chord within `tolerance_mm` of the curve (Nurbs::
// chord_parameters). `radii`, when given, receives the curve's true radius of
// curvature (from C' and C'') at the start and at every point, each the
// smaller of the point's and the adjacent chords' middles' (docs/CURVES.md).
std::vector<PerAxis<double>> nurbs_chord_points(const MotionBlock& b, double tolerance_mm,
                                                std::vector<double>* radii = nullptr);

// A polyline turning by more than this (rad) at a point has a corner there
// (junction deviation, acceleration zero); less is a smooth junction.
inline constexpr double kSmoothTurnRad = 0.3;
// The noise assumed on G-code coordinates (mm) when fitting a radius.
inline constexpr double kGeometryNoiseMm = 1e-4;

// Radius of the path at every point of a polyline (machine mm). `arc_radius`
// gives, per point, the radius of an arc the point lies inside or ends
// (infinity: none); other points of a smooth run get the circle through the
// point and neighbours on each side, widened until the point stands at least
// 10 noise widths off their chord, counted conservatively (the noise added to
// the standoff). Corners (turn > kSmoothTurnRad) and the ends get infinity.
std::vector<double> path_radii(const std::vector<PerAxis<double>>& pts,
                               const std::vector<double>& arc_radius);

// All blocks of a job as step segments. Moves outside an axis's travel, or
// along an axis the machine does not have, refuse the job with file:line:col.
// The job's blocks pushed through a StepSegmenter.
Result<std::vector<StepSegment>> make_step_segments(const Job& job, const Machine& machine);

// The same step segments made as the blocks arrive, one at a time (a job read
// as it is planned): next() hands out each segment, in order, once its radii
// are known (path_radii() reads up to 65 points past a segment's end, and a
// segment's end radius depends on the segment after it), bit for bit what
// make_step_segments() gives. It holds the points from 65 before the oldest
// segment not yet handed out to the newest, not the job (a block's own chords
// are made whole: at most kMaxArcChords or Nurbs::kMaxChords). After an error
// nothing more is handed out; later blocks are still checked.
class StepSegmenter {
public:
    StepSegmenter(const Machine& m, std::string job_file);
    ~StepSegmenter();
    StepSegmenter(StepSegmenter&&) noexcept;
    StepSegmenter& operator=(StepSegmenter&&) noexcept;
    StepSegmenter(const StepSegmenter&) = delete;
    StepSegmenter& operator=(const StepSegmenter&) = delete;

    // The job's next block; `index` is its place among the job's blocks (StepSegment::block).
    void push(const MotionBlock& block, std::size_t index);
    void finish();  // the job has no more
    std::optional<StepSegment> next();

    [[nodiscard]] std::size_t handed_out() const;
    [[nodiscard]] bool done() const;  // finished, every segment handed out, no error
    [[nodiscard]] const std::vector<Diagnostic>& errors() const;
    [[nodiscard]] std::size_t held_points() const;      // polyline points held now
    [[nodiscard]] std::size_t max_held_points() const;  // the most held after a push

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cpstep::plan

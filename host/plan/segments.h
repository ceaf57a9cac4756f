// Geometry to integer-step segments: arcs become chords within the machine's
// tolerance; every segment end is the absolute target rounded to whole steps,
// so rounding never accumulates.
#pragma once

#include <cstdint>
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

    [[nodiscard]] PerAxis<std::int64_t> delta() const;
    // Euclidean length of the quantized segment in mm (over the present axes).
    [[nodiscard]] double length_mm(const Machine& m) const;
};

// round(mm * steps_per_mm), halves away from -infinity (floor(x + 0.5)).
std::int64_t mm_to_steps(double mm, double steps_per_mm);

// The chord end points of an arc block (the block's start excluded, its exact
// end included), each within `tolerance_mm` of the arc.
std::vector<PerAxis<double>> arc_chord_points(const MotionBlock& arc, double tolerance_mm);

// All blocks of a job as step segments. Moves outside an axis's travel, or
// along an axis the machine does not have, refuse the job with file:line:col.
Result<std::vector<StepSegment>> make_step_segments(const Job& job, const Machine& machine);

}  // namespace cpstep::plan

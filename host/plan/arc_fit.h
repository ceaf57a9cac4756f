// SPDX-License-Identifier: MIT
// Arcs fitted to chains of short G1 lines (planner.fit_arcs_mm; docs/PLANNING.md
// "Arcs fitted to line chains"): what CAM output and sampled curves give as many
// tiny lines becomes a few G2/G3 arcs, each one CONIC segment on a card with the
// conic walker, within a tolerance the machine file states (as LinuxCNC's G64 P Q
// merges nearly collinear lines within Q).
#pragma once

#include <cstddef>

#include "plan/gcode.h"

namespace cpstep::plan {

struct ArcFitStats {
    std::size_t arcs = 0;             // arcs made
    std::size_t lines_in_arcs = 0;    // the G1 blocks they replace
    std::size_t merged = 0;           // runs of collinear lines made one line
    std::size_t lines_in_merged = 0;  // the G1 blocks those replace
    double max_deviation_mm = 0;      // the farthest input vertex from its arc or line
};

// The job with runs of consecutive G1 blocks replaced:
// - by one G2/G3 in the XY plane, when the run has at least 3 lines, turns one
//   way by less than 1.9 pi in all, and a circle through its first and last
//   points has every vertex within tol_mm and every line within tol_mm (the
//   vertices' distance plus the line's sagitta);
// - by one G1, when at least 2 lines lie within tol_mm of the line from their
//   first point to their last and go the same way along it;
// whichever replaces more lines. A run's lines share their feed, spindle, tool
// and every coordinate but X and Y. The first and last points are kept exactly;
// the new block carries the run's first block's source location.
// tol_mm <= 0 returns the job unchanged.
Job fit_arcs(const Job& job, double tol_mm, ArcFitStats* stats = nullptr);

}  // namespace cpstep::plan

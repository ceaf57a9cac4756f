// SPDX-License-Identifier: MIT
// Arcs fitted to chains of short G1 lines (planner.fit_arcs_mm; docs/PLANNING.md
// "Arcs fitted to line chains"): what CAM output and sampled curves give as many
// tiny lines becomes a few G2/G3 arcs, each one CONIC segment on a card with the
// conic walker, within a tolerance the machine file states (as LinuxCNC's G64 P Q
// merges nearly collinear lines within Q).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>

#include "plan/gcode.h"
#include "plan/machine.h"

namespace cpstep::plan {

struct ArcFitStats {
    std::size_t arcs = 0;             // arcs made
    std::size_t lines_in_arcs = 0;    // the G1 blocks they replace
    std::size_t merged = 0;           // runs of collinear lines made one line
    std::size_t lines_in_merged = 0;  // the G1 blocks those replace
    double max_deviation_mm = 0;      // the farthest input vertex from its arc or line
    // NURBS blocks cut into arcs (and lines where no arc fits) instead of chords:
    std::size_t curves = 0;           // the curves
    std::size_t curve_arcs = 0;       // the arcs they became
    std::size_t curve_lines = 0;      // and the lines
    double curve_max_deviation_mm = 0;  // the bound of how far they lie from their curves
};

// What is fitted, and within what: G1 chains within `lines_mm`, NURBS blocks
// within `curves_mm` (0: not fitted).
struct ArcFitTolerances {
    double lines_mm = 0;
    double curves_mm = 0;
    [[nodiscard]] bool any() const { return lines_mm > 0 || curves_mm > 0; }
};
// What the machine file and its card ask: G1 chains within planner.fit_arcs_mm;
// each NURBS as arcs within planner.arc_tolerance_mm (the tolerance its chords
// would have) where the card walks arcs (planner.arcs = "conic" and a conic walker).
ArcFitTolerances arc_fit_tolerances(const Machine& m);

// The job with runs of consecutive G1 blocks replaced:
// - by one G2/G3 in the XY plane, when the run has at least 3 lines, turns one
//   way by less than 1.9 pi in all, and a circle through its first and last
//   points has every vertex within tol_mm and every line within tol_mm (the
//   vertices' distance plus the line's sagitta);
// - by one G1, when at least 2 lines lie within tol_mm of the line from their
//   first point to their last and go the same way along it;
// whichever replaces more lines (within the lines' tolerance, tol_mm below). A
// NURBS block (G5, G5.1, G5.2) is cut into chords within kCurveChordShare times
// the curves' tolerance of the curve, and runs of those are fitted as above within
// the rest of it, so every arc and line made lies within that tolerance of the
// curve; the curve becomes those blocks when any arc fits and they are fewer than
// its chords within the tolerance, and stays a NURBS otherwise.
// A run's lines share their feed, spindle, tool
// and every coordinate but X and Y. The first and last points are kept exactly;
// the new block carries the run's first block's source location.
// A fitted block replaces at most kArcFitMaxLines lines (a longer run that fits
// becomes several blocks), which bounds what ArcFitter holds.
// tol_mm <= 0 returns the job unchanged. (ArcFitter fed the whole job.) With a
// double, lines and curves within the same tolerance.
Job fit_arcs(const Job& job, ArcFitTolerances tol, ArcFitStats* stats = nullptr);
Job fit_arcs(const Job& job, double tol_mm, ArcFitStats* stats = nullptr);

inline constexpr std::size_t kArcFitMaxLines = 4096;
// The share of fit_arcs' tolerance a NURBS's chords take (the arcs the rest).
inline constexpr double kCurveChordShare = 0.25;

// fit_arcs() as the blocks arrive: push() them in order, finish() after the
// last, next() hands out the fitted job's blocks in order, each as soon as
// nothing after it can change it (the lines a fit was tried on, doubling from
// the run's first line, past the first length that failed, or the run's end).
// It holds the current run's lines from the first not yet handed out, at most
// kArcFitMaxLines + 1 of them, and what it has made but not handed out.
// The same blocks as fit_arcs() over the whole job, bit for bit.
class ArcFitter {
public:
    // whole_runs: decide only at each run's end, the whole run held (as fit_arcs
    // did before it streamed; the reference the tests compare the stream with).
    explicit ArcFitter(ArcFitTolerances tol, bool whole_runs = false);
    explicit ArcFitter(double tol_mm, bool whole_runs = false);   // lines and curves within tol_mm
    ~ArcFitter();
    ArcFitter(ArcFitter&&) noexcept;
    ArcFitter& operator=(ArcFitter&&) noexcept;
    ArcFitter(const ArcFitter&) = delete;
    ArcFitter& operator=(const ArcFitter&) = delete;

    void push(const MotionBlock& block);
    void finish();  // no more blocks
    std::optional<MotionBlock> next();
    [[nodiscard]] const ArcFitStats& stats() const;  // of what has been fitted so far
    [[nodiscard]] std::size_t held() const;          // lines of the run and blocks made, held

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// `cpstep run --plots DIR`: path.png, speed.png, accel.png and jerk.png drawn by
// gnuplot from what the card's pins did, with the plan beside it. The data
// files and the gnuplot script stay in DIR so a figure can be redrawn by hand.
#pragma once

#include <filesystem>
#include <string>

#include "run/card_job.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::run {

// The gnuplot executable found on PATH, or "" when there is none.
std::string find_gnuplot();

// Writes the plots into `dir` (created if needed). Returns "" on success, else
// what went wrong (no gnuplot on PATH, a file that cannot be written, gnuplot
// failing: its messages are in DIR/gnuplot.log).
// `meter` has measured the run (RunMeter::finish).
std::string write_plots(const std::filesystem::path& dir, const CardJob& job, const RunMeter& meter,
                        const RunMeasure& measure);

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
// The JSON report of `cpstep run --report` (docs/HOST.md defines every field).
#pragma once

#include <nlohmann/json.hpp>

#include "run/card_job.h"
#include "run/measure.h"
#include "run/sim_run.h"

namespace cpstep::run {

nlohmann::json make_report(const CardJob& job, const CardRun& run, const RunMeasure& m);

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
// What the CAM writes: G-code for cpstep's planner (G0/G1/G2/G3 with I J, M3, the
// pierce as G4 P<seconds>, M5 after each cut) and an SVG preview (the sheet, its
// margins and invalid regions, the parts as cut, leads, pierce points numbered in
// cut order, dashed rapids).
#pragma once

#include <string>
#include <vector>

#include "cam/plan.h"
#include "cam/sheet.h"

namespace cpstep::cam {

struct GcodeInfo {
  std::vector<std::string> header;   // comment lines
  double feed_mm_min = 1000;
  std::vector<std::string> part_names;  // per placed part, for comments
};

std::string write_gcode(const CutPlan& plan, const GcodeInfo& info);
std::string write_svg(const CutPlan& plan, const Sheet& sheet);

}  // namespace cpstep::cam

// SPDX-License-Identifier: MIT
// The sheet file (SHEET.toml, docs/PLASMA.md): the sheet and its margins and invalid
// regions, the start point, the layout (a regular array or irregular nesting), the
// leads and the cut chart (thickness -> kerf, pierce delays, feed). Refusals are
// `file:line:col: message`. Layout: each placed part is an (x, y, θ) of its master.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cam/contour.h"
#include "cam/geom.h"
#include "cam/plan.h"

namespace cpstep::cam {

struct ChartRow {
  double thickness = 0, kerf = 0, pierce_s = 0, pierce_edge_s = 0, feed_mm_min = 0;
};

enum class Corner { bottom_left, bottom_right, top_left, top_right };
enum class StartPoint { corner, first_part_centre };

struct Sheet {
  double width = 0, height = 0;
  double margin_left = 0, margin_right = 0, margin_top = 0, margin_bottom = 0;
  std::vector<Box> invalid;  // rectangles where nothing is placed
  Box usable() const;
  Box box() const { Box b; b.add({0, 0}); b.add({width, height}); return b; }
};

struct Layout {
  std::string mode = "array";     // array | nest
  int count = 0;                  // parts of each drawing; 0: as many as fit (array)
  double spacing_x = 0, spacing_y = 0;  // SX, SY between bounding boxes (negative: they overlap)
  std::string rotate = "none";    // array: none | alternate-x | alternate-y | checker (180° turns)
  std::string order = "x-zigzag"; // array traversal: x-oneway | x-zigzag | y-oneway | y-zigzag | nearest
  Corner corner = Corner::bottom_left;  // where the layout and the traversal start
  StartPoint start = StartPoint::corner;
  double gap = 0;                 // nest: mm between kerf outlines
  std::vector<double> rotations{0};  // nest: degrees tried
};

struct SheetConfig {
  std::string file;
  Sheet sheet;
  Layout layout;
  std::string material;
  double thickness = 0;
  ChartRow chart;                 // the row chosen for the thickness
  double lead_in = 3, lead_out = 2, edge_distance = 10;
  double chain_tolerance = 0.01;
  double unitless_mm = 1;
};

struct SheetResult {
  std::optional<SheetConfig> config;
  std::vector<std::string> errors;
};
SheetResult load_sheet(const std::string& path);
SheetResult parse_sheet(const std::string& text, const std::string& path);

// The seed's checks: margins not negative, opposite margins together smaller than
// the sheet, invalid regions inside the sheet and none inside another. Errors.
std::vector<std::string> check_sheet(const Sheet& s);

struct Placed {
  int master = 0;
  double x = 0, y = 0, theta_deg = 0;  // the master's points p map to R(θ)·p + (x, y)
  Affine transform() const { return Affine::translate(x, y) * Affine::rotate_deg(theta_deg); }
};

struct LayoutResult {
  std::vector<Placed> placed;     // in cut order for a regular traversal
  bool regular = false;           // the order is the traversal's
  std::vector<std::string> errors, warnings;
  double use_percent = 0;         // parts' area over the usable area
};

// `masters`: normalized shapes (bounding box at the origin). `kerf` widens each outline.
LayoutResult layout_parts(const std::vector<Shape>& masters, const SheetConfig& cfg);
// Where the torch starts.
Vec2 start_point(const SheetConfig& cfg, const std::vector<Shape>& placed);

// The eight regular orders (and more) of a grid of cols x rows cells: the cells in
// cut order as (col, row), starting at `corner`.
std::vector<std::pair<int, int>> traversal(int cols, int rows, const std::string& order, Corner corner);

// Parts outside the usable area, on an invalid region or overlapping one another
// (their outlines widened by half the kerf): one error each.
std::vector<std::string> check_fit(const std::vector<Shape>& placed, const Sheet& sheet, double kerf,
                                   const std::vector<std::string>& names);

}  // namespace cpstep::cam

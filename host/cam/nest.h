// SPDX-License-Identifier: MIT
// Irregular nesting with libnest2d (its no-fit-polygon placer, first-fit
// selection), behind an interface free of libnest2d's types: libnest2d is
// header-only C++17 and is compiled in nest.cpp alone.
#pragma once

#include <utility>
#include <vector>

namespace cpstep::cam::nest {

struct Outline {
  std::vector<std::pair<double, double>> pts;  // mm, a closed outline (no repeated first point)
};

struct Rect {
  double x0, y0, x1, y1;  // mm
};

struct Request {
  std::vector<Outline> items;        // what is placed (the parts' outlines, kerf included)
  Rect bin{0, 0, 0, 0};              // the usable area of the sheet
  std::vector<Rect> forbidden;       // invalid regions: fixed in the bin
  double gap = 0;                    // mm between placed outlines
  std::vector<double> rotations{0};  // radians tried for every item
};

// Where each item goes: its outline rotated by `rot` about the origin, then moved
// by (x, y). bin < 0: it did not fit on the sheet; bin > 0: only on a further sheet.
struct Placement {
  int bin = -1;
  double x = 0, y = 0, rot = 0;
};

std::vector<Placement> run(const Request& r);

}  // namespace cpstep::cam::nest

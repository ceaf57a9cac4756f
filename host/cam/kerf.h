// SPDX-License-Identifier: MIT
// Kerf compensation: a closed contour of lines and circular arcs offset by half
// the kerf to its waste side, arcs kept as arcs: each segment moved along its
// normal (an arc's radius grows or shrinks), convex corners joined by an arc about
// the original corner, concave corners trimmed where the moved segments meet.
// Segments that vanish and arcs whose radius falls to zero are features narrower
// than the kerf: they are reported.
#pragma once

#include <string>
#include <vector>

#include "cam/geom.h"

namespace cpstep::cam {

struct OffsetResult {
  std::vector<Seg> segs;            // closed; empty when the contour collapses
  std::vector<std::string> notes;   // features narrower than the kerf, one line each
};

// `path`: closed, lines and circular arcs only, oriented so that the waste is on
// the left of travel (cam/contour.h orient_for_cut). Offsets to the left by d >= 0.
OffsetResult offset_left(const std::vector<Seg>& path, double d, double tol = 1e-4);

// Where two closed flattened outlines cross (nullopt: nowhere).
std::optional<Vec2> first_crossing(const std::vector<Vec2>& a, const std::vector<Vec2>& b);
// Where a closed flattened outline crosses itself (non-adjacent edges).
std::optional<Vec2> self_crossing(const std::vector<Vec2>& a);

}  // namespace cpstep::cam

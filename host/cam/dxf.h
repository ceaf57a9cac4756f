// SPDX-License-Identifier: MIT
// DXF drawings read with libdxflib (GPL-2.0-or-later: docs/LICENSING.md): LINE,
// ARC, CIRCLE, ELLIPSE, LWPOLYLINE/POLYLINE with bulges, SPLINE (sampled within a
// tolerance), INSERT with its block expanded (arrays too), in millimetres from
// $INSUNITS. Arcs stay arcs. Every refusal names the file, the entity's handle and
// the line it starts on.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "cam/geom.h"

namespace cpstep::cam {

struct Source {
  std::string type;    // LINE, ARC, ...
  std::string handle;  // hex as in the file ("" when the file has none)
  int line = 0;        // the line of the entity's "0 / TYPE" pair
  std::string where(const std::string& file) const;  // "file: LINE handle 1F (line 120)"
};

struct Drawing {
  std::string file;
  std::vector<Seg> segs;         // model space, millimetres
  std::vector<Source> sources;   // Seg::src indexes this
  double unit_mm = 1;            // one drawing unit in mm
  std::vector<std::string> warnings;
};

struct DxfOptions {
  double spline_tolerance_mm = 0.01;
  double unitless_mm = 1;        // $INSUNITS 0 or missing: one unit is this many mm
  // A SPLINE that needs more chords than this within spline_tolerance_mm is
  // refused (plan::Nurbs::chord_parameters: told from its estimate before any
  // chord is made when far over). The fuzz target lowers it to keep each input quick.
  std::size_t max_spline_chords = 1'000'000;  // plan::Nurbs::kMaxChords
  // The drawing's segments after its INSERTs are placed (arrays of arrays
  // multiply): an INSERT that would place more is refused before it is placed.
  std::size_t max_segments = 1'000'000;
};

struct DxfResult {
  Drawing drawing;
  std::vector<std::string> errors;  // any error refuses the drawing
  bool ok() const { return errors.empty(); }
};

DxfResult load_dxf(const std::string& path, const DxfOptions& options = {});
// The same for a drawing's text, named `path` in messages (the fuzz target's entry).
DxfResult parse_dxf(const std::string& text, const std::string& path, const DxfOptions& options = {});

// mm per drawing unit for a $INSUNITS code; 0 for codes that are not lengths.
double insunits_mm(int code);

}  // namespace cpstep::cam

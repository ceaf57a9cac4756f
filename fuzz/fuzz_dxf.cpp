// SPDX-License-Identifier: MIT
// Fuzz target: the DXF import (host/cam/dxf.h, parse_dxf: libdxflib and cpstep's
// reader around it) on arbitrary text. Invariants: a refused drawing has errors,
// each naming the file; an accepted one has geometry, every segment's points
// finite, every segment's source an entity of the drawing (or -1), and a finite
// positive unit.
#include <cmath>
#include <cstdint>
#include <string>

#include "cam/dxf.h"
#include "fuzz_util.h"

using namespace cpstep;

namespace {

bool finite(const cam::Vec2& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // At most 200 chords a spline (the default is 10^6): a spline the fuzzer
  // grows past that is refused quickly, from its estimate or at the cap, and
  // the refusal is what is checked (a spline of 10^6 chords is seconds under ASan).
  // Likewise at most 20,000 segments placed by INSERTs (the default is 10^6).
  cam::DxfOptions o;
  o.max_spline_chords = 200;
  o.max_segments = 20000;
  const cam::DxfResult r = cam::parse_dxf(text, "fuzz.dxf", o);
  if (!r.ok()) {
    for (const std::string& e : r.errors) FUZZ_CHECK(e.rfind("fuzz.dxf", 0) == 0, "error without the file: %s", e.c_str());
    return 0;
  }
  const cam::Drawing& d = r.drawing;
  FUZZ_CHECK(!d.segs.empty(), "accepted without geometry");
  FUZZ_CHECK(std::isfinite(d.unit_mm) && d.unit_mm > 0, "unit %g mm", d.unit_mm);
  for (const cam::Seg& s : d.segs) {
    FUZZ_CHECK(finite(s.a) && finite(s.b), "a segment with a point that is not finite");
    FUZZ_CHECK(s.src >= -1 && s.src < int(d.sources.size()), "source %d of %zu", s.src, d.sources.size());
  }
  return 0;
}

// SPDX-License-Identifier: MIT
// Fuzz target: the pin map (host/check/pin_map.h, parse_pin_map) on arbitrary
// TOML text. Invariants: a refused map has errors, sorted by line and column; an
// accepted one names a STEP and a DIR signal for every axis (non-empty), and its
// time unit and sample period, when given, are finite and > 0.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "check/pin_map.h"
#include "fuzz_util.h"

using namespace cpstep;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const plan::Result<check::PinMap> r = check::parse_pin_map(text, "fuzz.toml");
  if (!r.ok()) {
    FUZZ_CHECK(!r.errors.empty(), "refused without an error");
    for (size_t i = 1; i < r.errors.size(); ++i)
      FUZZ_CHECK(std::pair(r.errors[i - 1].loc.line, r.errors[i - 1].loc.col) <=
                     std::pair(r.errors[i].loc.line, r.errors[i].loc.col),
                 "errors out of order");
    return 0;
  }
  const check::PinMap& m = *r.value;
  FUZZ_CHECK(m.file == "fuzz.toml", "file");
  for (const check::AxisPins& a : m.axes) FUZZ_CHECK(!a.step.empty() && !a.dir.empty(), "an axis without names");
  if (m.unit_s) FUZZ_CHECK(std::isfinite(*m.unit_s) && *m.unit_s > 0, "unit %g s", *m.unit_s);
  if (m.sample_s) FUZZ_CHECK(std::isfinite(*m.sample_s) && *m.sample_s > 0, "sample period %g s", *m.sample_s);
  return 0;
}

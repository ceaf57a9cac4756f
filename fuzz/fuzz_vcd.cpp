// SPDX-License-Identifier: MIT
// Fuzz target: the VCD reader (host/check/vcd.h, parse_vcd) on arbitrary text, and
// parse_duration on the same text. Invariants: a refused trace has exactly one
// error (the first refuses it) inside the text; an accepted one has every
// variable's code in range and its name at the end of its path, each code's
// changes in time order, at or before end_time, with no bits above the width.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "check/vcd.h"
#include "fuzz_util.h"

using namespace cpstep;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (const auto d = check::parse_duration(text)) FUZZ_CHECK(std::isfinite(*d) && *d > 0, "duration %g", *d);

  int lines = 1;
  for (char c : text) lines += c == '\n';
  const plan::Result<check::VcdTrace> r = check::parse_vcd(text, "fuzz.vcd");
  if (!r.ok()) {
    FUZZ_CHECK(r.errors.size() == 1, "%zu errors", r.errors.size());
    FUZZ_CHECK(r.errors[0].loc.line >= 0 && r.errors[0].loc.line <= lines, "error at line %d of %d",
               r.errors[0].loc.line, lines);
    return 0;
  }
  const check::VcdTrace& t = *r.value;
  if (t.unit_s) FUZZ_CHECK(std::isfinite(*t.unit_s) && *t.unit_s > 0, "unit %g s", *t.unit_s);
  std::vector<unsigned> width(t.changes.size(), 0);
  for (const check::VcdVar& v : t.vars) {
    FUZZ_CHECK(v.code < t.changes.size(), "code %zu of %zu", v.code, t.changes.size());
    FUZZ_CHECK(v.width >= 1 && v.width <= 64, "width %u", v.width);
    FUZZ_CHECK(v.path.size() >= v.name.size() && v.path.ends_with(v.name), "path %s name %s", v.path.c_str(),
               v.name.c_str());
    FUZZ_CHECK(width[v.code] == 0 || width[v.code] == v.width, "code %zu with two widths", v.code);
    width[v.code] = v.width;
    bool found = false;
    for (const check::VcdVar* f : t.find(v.name)) found = found || f == &v;
    FUZZ_CHECK(found, "find(%s) misses it", v.name.c_str());
  }
  for (size_t c = 0; c < t.changes.size(); ++c) {
    uint64_t last = 0;
    for (const check::VcdChange& ch : t.changes[c]) {
      FUZZ_CHECK(ch.time >= last && ch.time <= t.end_time, "code %zu: change at %llu after %llu (end %llu)", c,
                 (unsigned long long)ch.time, (unsigned long long)last, (unsigned long long)t.end_time);
      last = ch.time;
      if (width[c] > 0 && width[c] < 64)
        FUZZ_CHECK(ch.bits >> width[c] == 0, "code %zu: bits 0x%llx above width %u", c,
                   (unsigned long long)ch.bits, width[c]);
    }
  }
  return 0;
}

// SPDX-License-Identifier: MIT
// Fuzz target: the G-code reader (host/plan/gcode.h, parse_gcode). The first byte
// picks the options (Z words refused or ignored, the axes present, the error cap);
// the rest is the program text. Invariants: a refused job has errors, at most
// max_errors of them plus the "more errors" line, every one at a line of the text;
// an accepted job's blocks are finite, in order, each starting where the one
// before ended, with non-negative feeds and dwells.
#include <cmath>
#include <cstdint>
#include <string_view>

#include "fuzz_util.h"
#include "plan/gcode.h"

using namespace cpstep;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  const uint8_t opt = in.u8();
  const std::string_view text = in.rest();

  plan::GcodeOptions o;
  o.z_words = (opt & 1) ? plan::MissingZ::ignore : plan::MissingZ::refuse;
  if (opt & 2) o.axes_present = plan::PerAxis<bool>{true, true, (opt & 4) != 0, (opt & 8) != 0};
  if (opt & 16) o.max_errors = 3;
  if (opt & 32) o.tool_lengths = {{1, 25.4}, {2, -3.0}};
  if (opt & 64) o.start_position = {1.5, -2.0, 10.0, 0.0};
  // Canned cycles expand into at most 20,000 holes x pecks a program (the default
  // is 10^6): the limits' code is the same, and a job of 10^6 holes is seconds of
  // allocation under ASan, not a finding.
  o.max_cycle_block = 2000;
  o.max_cycle_job = 20000;

  int lines = 1;
  for (char c : text) lines += c == '\n';

  const plan::Result<plan::Job> r = plan::parse_gcode(text, "fuzz.ngc", o);
  for (const auto& d : r.errors) FUZZ_CHECK(d.loc.line >= 0 && d.loc.line <= lines, "error at line %d of %d", d.loc.line, lines);
  for (const auto& d : r.warnings) FUZZ_CHECK(d.loc.line >= 0 && d.loc.line <= lines, "warning at line %d of %d", d.loc.line, lines);
  if (!r.ok()) {
    FUZZ_CHECK(!r.errors.empty(), "refused without an error");
    FUZZ_CHECK(r.errors.size() <= o.max_errors + 1, "%zu errors", r.errors.size());
    return 0;
  }
  const auto& blocks = r.value->blocks;
  int last_line = 0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const plan::MotionBlock& b = blocks[i];
    FUZZ_CHECK(b.loc.line >= 1 && b.loc.line <= lines, "block %zu at line %d", i, b.loc.line);
    FUZZ_CHECK(b.loc.line >= last_line, "block %zu at line %d after line %d", i, b.loc.line, last_line);
    last_line = b.loc.line;
    for (int a = 0; a < plan::kAxes; ++a) {
      FUZZ_CHECK(std::isfinite(b.start[a]) && std::isfinite(b.end[a]), "block %zu axis %d not finite", i, a);
      if (i > 0) FUZZ_CHECK(b.start[a] == blocks[i - 1].end[a], "block %zu axis %d starts at %g, not %g", i, a,
                            b.start[a], blocks[i - 1].end[a]);
    }
    FUZZ_CHECK(std::isfinite(b.feed) && b.feed >= 0, "block %zu feed %g", i, b.feed);
    FUZZ_CHECK(std::isfinite(b.dwell_s) && b.dwell_s >= 0, "block %zu dwell %g", i, b.dwell_s);
    FUZZ_CHECK(std::isfinite(b.center_x) && std::isfinite(b.center_y) && std::isfinite(b.center_z),
               "block %zu centre not finite", i);
    if (b.kind == plan::MotionKind::linear || b.kind == plan::MotionKind::arc_cw ||
        b.kind == plan::MotionKind::arc_ccw)
      FUZZ_CHECK(b.feed > 0, "block %zu: a feed move with feed %g", i, b.feed);
    if (b.kind == plan::MotionKind::arc_cw || b.kind == plan::MotionKind::arc_ccw) (void)plan::arc_frame(b);
  }
  return 0;
}

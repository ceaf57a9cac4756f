// SPDX-License-Identifier: MIT
// Fuzz target: the whole planner on a card with a conic walker (host/plan/pipeline.h,
// plan_job; host/plan/conic_arc.h; card::to_wire, encode_job). The first byte picks
// the machine and the card (arcs as conics or chords, equal or unequal steps/mm in
// XY, a pattern capacity of 1024 or 48, a chunk queue of 64 or 3, add2 on or off, G1
// chains fitted with arcs within 0.01 mm or not);
// the rest is the G-code. The machine's travel is ±20 mm at 80 steps/mm (Z 40), so
// no input plans more than a few thousand moves a block.
// Invariants: a refused job names a line of the text; an accepted one's card
// segments chain from the first step segment's start to the last motion's end, each
// conic's walk sums to its delta, its moves come no faster than the walker's pace
// and its plane is two distinct axes, the ideal times never go back; the wire form
// is accepted or refused with a line, its command words split into whole commands,
// and each CONIC's seven words, walked by the walker's own rule, reach their end on
// the segment's last move and on no other (what the card checks, CONIC_END); a CONIC
// sent as a continuation follows a CONIC on its axes, its way (CONIC_CONTINUE).
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "card/job.h"
#include "fuzz_util.h"
#include "model/cp_conic.h"
#include "model/cp_conic_serial.h"
#include "plan/pipeline.h"

using namespace cpstep;

namespace {

constexpr unsigned kCiw = 40;

plan::Machine machine(uint8_t opt) {
  const double sy = (opt & 2) ? 100 : 80;
  const std::string text = "[card]\nclock_hz = 40e6\n[planner]\narc_tolerance_mm = 0.01\n"
                           "on_limit = \"slow\"\n" +
                           std::string((opt & 1) ? "arcs = \"chords\"\n" : "") +
                           std::string((opt & 16) ? "chunk_add2 = false\n" : "") +
                           std::string((opt & 32) ? "fit_arcs_mm = 0.01\n" : "") +
                           "[axes.x]\nsteps_per_mm = 80\ntravel_min_mm = -20\ntravel_max_mm = 20\n"
                           "max_velocity_mm_s = 100\nmax_accel_mm_s2 = 2000\nmax_jerk_mm_s3 = 50000\n"
                           "driver = \"TMC2209\"\n"
                           "[axes.y]\nsteps_per_mm = " + std::to_string(sy) +
                           "\ntravel_min_mm = -20\ntravel_max_mm = 20\nmax_velocity_mm_s = 100\n"
                           "max_accel_mm_s2 = 2000\nmax_jerk_mm_s3 = 50000\ndriver = \"TMC2209\"\n"
                           "[axes.z]\nsteps_per_mm = 40\ntravel_min_mm = -20\ntravel_max_mm = 20\n"
                           "max_velocity_mm_s = 20\nmax_accel_mm_s2 = 500\nmax_jerk_mm_s3 = 10000\n"
                           "driver = \"TMC2209\"\n";
  auto r = plan::parse_machine(text, "fuzz.toml");
  FUZZ_CHECK(r.ok(), "the target's machine is refused: %s", plan::join(r.errors).c_str());
  plan::Machine m = *r;
  m.card.conic_width = kCiw;  // what bind_card() sets for a card with the walker (HX8K)
  m.card.max_moves = 1048575;
  m.card.pattern_capacity = (opt & 4) ? 48 : 1024;
  m.card.max_doubling = 8;
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  const uint8_t opt = in.u8();
  const std::string_view text = in.rest();
  if (text.size() > 4096) return 0;  // a few blocks are what the planner's paths need

  int lines = 1;
  for (char c : text) lines += c == '\n';
  const plan::Machine m = machine(opt);
  plan::GcodeOptions go = plan::gcode_options(m);
  go.max_cycle_block = 200;
  go.max_cycle_job = 2000;
  const plan::Result<plan::Job> job = plan::parse_gcode(text, "fuzz.ngc", go);
  if (!job.ok()) return 0;  // the reader's own target (fuzz_gcode) judges refusals
  plan::PlanOptions po;
  po.chunk_limits = card::chunk_limits();
  const plan::Result<plan::PlannedJob> r = plan::plan_job(*job, m, po);
  for (const auto& d : r.errors) FUZZ_CHECK(d.loc.line >= 0 && d.loc.line <= lines, "error at line %d", d.loc.line);
  if (!r.ok()) {
    FUZZ_CHECK(!r.errors.empty(), "refused without an error");
    return 0;
  }
  const plan::PlannedJob& pj = *r.value;
  if (pj.step_segments.empty()) return 0;

  // The card segments chain from the start to the last motion's end.
  plan::PerAxis<int64_t> pos = pj.step_segments.front().start, end = pos;
  for (const plan::StepSegment& s : pj.step_segments)
    if (s.kind != plan::MotionKind::dwell) end = s.end;
  uint64_t moves = 0;
  double last_conic = -1e300;
  for (const plan::PlannedCardSegment& c : pj.card) {
    if (c.conic) {
      const plan::ConicWalk& w = *c.conic;
      FUZZ_CHECK(w.axis_u != w.axis_v && w.axis_u >= 0 && w.axis_u < plan::kAxes && w.axis_v >= 0 &&
                     w.axis_v < plan::kAxes,
                 "conic plane %d, %d", w.axis_u, w.axis_v);
      FUZZ_CHECK(w.u0 == pos[w.axis_u] && w.v0 == pos[w.axis_v], "a conic starts off the card's position");
      FUZZ_CHECK(w.moves.size() == c.segment.moves && w.ideal.size() == c.segment.moves && c.segment.moves > 0,
                 "conic of %u moves with %zu walked", c.segment.moves, w.moves.size());
      int64_t du = 0, dv = 0;
      for (uint8_t mv : w.moves) du += plan::ConicWalk::dx_of(mv), dv += plan::ConicWalk::dy_of(mv);
      FUZZ_CHECK(du == c.segment.delta[w.axis_u] && dv == c.segment.delta[w.axis_v] && du == w.du && dv == w.dv,
                 "a conic's walk does not sum to its delta");
      const double gap = double(plan::conic_gap_cycles(kCiw));
      FUZZ_CHECK(w.ideal.front() - m.chunk_tolerance_cycles() - last_conic >= gap - 1e-6,
                 "a conic's first move too soon after the last conic");
      for (size_t j = 1; j < w.ideal.size(); ++j)
        FUZZ_CHECK(w.ideal[j] - w.ideal[j - 1] >= gap - 1e-6, "conic moves %zu, %zu closer than the walker's pace",
                   j - 1, j);
      last_conic = w.ideal.back();
    }
    if (!c.segment.pause) moves += c.segment.moves;
    for (int a = 0; a < plan::kAxes; ++a) pos[a] += c.segment.delta[a];
  }
  FUZZ_CHECK(pos == end, "the card segments end off the job's end");
  FUZZ_CHECK(moves == pj.stats.moves, "%llu moves in the card segments, %llu counted", (unsigned long long)moves,
             (unsigned long long)pj.stats.moves);
  const std::vector<double> t = plan::ideal_times(pj, m.card.clock_hz);
  FUZZ_CHECK(t.size() == moves, "%zu ideal times for %llu moves", t.size(), (unsigned long long)moves);
  for (size_t k = 1; k < t.size(); ++k) FUZZ_CHECK(t[k] >= t[k - 1] - 1e-6, "ideal time %zu goes back", k);

  // The wire.
  card::CardLimits lim;
  lim.w = m.card.pattern_capacity;
  lim.chunk_queue = (opt & 8) ? 3 : 64;
  const auto wire = card::to_wire(pj, "fuzz.ngc", lim);
  if (!wire.ok()) {
    FUZZ_CHECK(!wire.errors.empty(), "wire refused without an error");
    for (const auto& d : wire.errors) FUZZ_CHECK(d.loc.line >= 0 && d.loc.line <= lines, "wire error at line %d", d.loc.line);
    return 0;
  }
  const std::vector<uint32_t> words = card::encode_job(m, *wire);
  size_t w = 0;
  while (w < words.size()) w += card::command_words(words[w], plan::kAxes);
  FUZZ_CHECK(w == words.size(), "the command words end inside a command");
  const card::WireSegment* prev = nullptr;
  for (const card::WireSegment& s : wire->segments) {
    FUZZ_CHECK(s.chunks.size() <= lim.chunk_queue, "%zu chunks for a queue of %u", s.chunks.size(), lim.chunk_queue);
    // A continuation follows a CONIC on its axes, its way (what the card checks, CONIC_CONTINUE).
    if (s.conic && s.conic->cont)
      FUZZ_CHECK(prev && prev->conic && prev->conic->axis_u == s.conic->axis_u &&
                     prev->conic->axis_v == s.conic->axis_v && prev->conic->cw == s.conic->cw,
                 "a continuation that does not follow its CONIC");
    prev = &s;
    if (!s.conic) continue;
    FUZZ_CHECK(s.k == 0 && s.u >= 1 && s.u <= lim.umax, "CONIC of T = %u, k = %u", s.u, s.k);
    const auto& k = s.conic->words;
    const model::CpConic::Coeffs co{int16_t(k[0] & 0xFFFF), int16_t(k[0] >> 16), int16_t(k[1] & 0xFFFF), 0, 0, 0};
    model::CpConic::Node n{int32_t(k[2]), int32_t(k[3]), int32_t(k[4])};
    const auto s24 = [](uint32_t x) { return int32_t(x << 8) >> 8; };
    int64_t du = s24(k[5]), dv = s24(k[6]);
    for (uint32_t j = 0; j < s.u; ++j) {
      int dx = 0, dy = 0;
      model::CpConicSerial::rule(co, n, s.conic->cw, kCiw, dx, dy);
      n = model::CpConic::advance(co, n, dx, dy);
      du -= dx;
      dv -= dy;
      FUZZ_CHECK((du == 0 && dv == 0) == (j + 1 == s.u), "the walk's end mark at move %u of %u", j + 1, s.u);
    }
  }
  return 0;
}

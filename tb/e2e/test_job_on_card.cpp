// SPDX-License-Identifier: MIT
// G-code -> planner -> command words -> the Verilated core, and back from its pins:
// the job lands exactly on the planned steps, and every move event happens at
// the cycle the planned chunks say (timed from START), unless stretched.
#include <gtest/gtest.h>

#include <numeric>

#include "Vcp_core_hx8k.h"
#include "card/job.h"
#include "plan/gcode.h"
#include "plan/pipeline.h"
#include "sim/core_driver.h"
#include "cpstep/builds.h"
#include "sim/core_port.h"

namespace cpstep::tb {
namespace {

struct CoreRtl : sim::CorePortBase<Vcp_core_hx8k, 4> {};

plan::Machine machine(const char* name) {
  auto m = plan::load_machine(std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/" + name);
  EXPECT_TRUE(m.ok()) << plan::join(m.errors);
  // Bound to the core these tests drive: the HX8K's build (rtl/builds.json).
  plan::Machine bound = *m;
  const builds::Build& b = builds::hx8k;
  const auto errors = plan::bind_card(bound, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw});
  EXPECT_TRUE(errors.empty()) << plan::join(errors);
  return bound;
}

plan::PlannedJob plan_text(const std::string& gcode, const plan::Machine& m) {
  auto job = plan::parse_gcode(gcode, "inline.ngc");
  EXPECT_TRUE(job.ok()) << plan::join(job.errors);
  plan::PlanOptions opt;
  opt.chunk_limits = card::chunk_limits();
  opt.add2_from_machine = false;
  auto planned = plan::plan_job(*job, m, opt);
  EXPECT_TRUE(planned.ok()) << plan::join(planned.errors);
  return *planned;
}

TEST(WireJob, SegmentsAreWhatTheCardAccepts) {
  for (const char* mach : {"plotter.toml", "seed002.toml"}) {
    const plan::Machine m = machine(mach);
    const auto planned = plan_text("G21 G90\nG1 X10 Y3 F3000\nG2 X20 Y3 I5 J0\nG1 X0 Y0\n", m);
    const auto wire = card::to_wire(planned, "inline.ngc");
    ASSERT_TRUE(wire.ok()) << plan::join(wire.errors);
    plan::PerAxis<int64_t> pos{};
    for (const auto& s : wire->segments) {
      ASSERT_GE(s.u, 1u);
      ASSERT_LE(s.u, card::CardLimits{}.umax);
      uint64_t count = 0;
      for (const auto& c : s.chunks) count += c.count;
      EXPECT_EQ(count, uint64_t(s.u) << s.k);
      for (int a = 0; a < 4; ++a) {
        ASSERT_LE(s.v[a], s.u);
        pos[a] += (s.dir_positive[a] ? 1 : -1) * (int64_t(s.v[a]) << s.k);
      }
    }
    EXPECT_EQ(pos, planned.step_segments.back().end) << mach;
    EXPECT_TRUE(wire->segments.back().end);
  }
}

TEST(WireJob, LongSegmentSplitsExactlyAtWholePatternPeriods) {
  plan::PlannedJob job;
  plan::PlannedCardSegment s;
  s.segment.moves = 3'000'000;
  s.segment.delta = {3'000'000, -1'000'000, 0, 0};
  s.segment.u = {1, 3, 1, 1};
  s.segment.v = {1, 1, 0, 0};
  s.chunks = {{100, 65535, 0, 0}};
  uint64_t left = 3'000'000 - 65535;
  while (left > 0) {
    const uint32_t n = uint32_t(std::min<uint64_t>(left, 65535));
    s.chunks.push_back({7, n, 0, 0});
    left -= n;
  }
  job.card.push_back(s);
  const auto wire = card::to_wire(job, "long.ngc");
  ASSERT_TRUE(wire.ok()) << plan::join(wire.errors);
  ASSERT_GT(wire->segments.size(), 2u);
  int64_t x = 0, y = 0;
  std::vector<plan::Chunk> original = s.chunks, pieces;
  for (const auto& w : wire->segments) {
    ASSERT_LE(w.u, card::CardLimits{}.umax);
    EXPECT_EQ((uint64_t(w.u) << w.k) % 3, 0u) << "a piece ends inside a pattern period";
    x += int64_t(w.v[0]) << w.k;
    y -= int64_t(w.v[1]) << w.k;
    for (const auto& c : w.chunks) pieces.push_back({c.interval, c.count, c.add, c.add2});
  }
  EXPECT_EQ(x, 3'000'000);
  EXPECT_EQ(y, -1'000'000);
  EXPECT_EQ(plan::expand(pieces, 0), plan::expand(original, 0));
}

// A job of one card segment timed by one chunk per move (intervals 100, 101, ...).
plan::PlannedJob one_move_chunks(uint32_t moves, plan::PerAxis<int64_t> delta, plan::PerAxis<uint32_t> u,
                                 plan::PerAxis<uint32_t> v) {
  plan::PlannedJob job;
  plan::PlannedCardSegment s;
  s.segment.moves = moves;
  s.segment.delta = delta;
  s.segment.u = u;
  s.segment.v = v;
  s.segment.loc = {7, 1};
  for (uint32_t i = 0; i < moves; ++i) s.chunks.push_back({100 + i, 1, 0, 0});
  job.card.push_back(s);
  return job;
}

// 200 one-move chunks on a segment whose patterns repeat every 5 moves (x
// steps 4 of 5, y 1 of 5): the card's chunk queue holds 64, so the pieces have
// at most 64 chunks, end at multiples of 5 moves and keep every move time.
TEST(WireJob, SegmentWithMoreChunksThanTheQueueSplitsAtWholePeriods) {
  const plan::PlannedJob job = one_move_chunks(200, {160, 40, 0, 0}, {5, 5, 1, 1}, {4, 1, 0, 0});
  const auto wire = card::to_wire(job, "many.ngc");
  ASSERT_TRUE(wire.ok()) << plan::join(wire.errors);
  const unsigned queue = card::CardLimits{}.chunk_queue;
  ASSERT_GE(wire->segments.size(), 200u / queue + 1);
  int64_t x = 0, y = 0;
  std::vector<plan::Chunk> pieces;
  for (const auto& w : wire->segments) {
    EXPECT_LE(w.chunks.size(), queue);
    EXPECT_EQ((uint64_t(w.u) << w.k) % 5, 0u) << "a piece ends inside a pattern period";
    x += int64_t(w.v[0]) << w.k;
    y += int64_t(w.v[1]) << w.k;
    for (const auto& c : w.chunks) pieces.push_back({c.interval, c.count, c.add, c.add2});
  }
  EXPECT_EQ(x, 160);
  EXPECT_EQ(y, 40);
  EXPECT_EQ(plan::expand(pieces, 0), plan::expand(job.card[0].chunks, 0));
}

// A cut inside a chunk with add2: 63 one-move chunks, then {10000, 110, -10, -1}
// (delays 10000 - 10j - j(j-1)/2, increments -10 - j), then 2 one-move chunks, on
// a pattern of period 5. The first piece holds 64 chunks = 63 + 110 moves, cut to
// 170 (whole periods): 107 moves of the add2 chunk; the rest starts at delay 107,
// 10000 - 1070 - 107·106/2 = 3259, with add -10 - 107 = -117, add2 -1, 3 moves.
TEST(WireJob, CutInsideAnAdd2ChunkKeepsEveryMoveTime) {
  plan::PlannedJob job = one_move_chunks(63, {140, 35, 0, 0}, {5, 5, 1, 1}, {4, 1, 0, 0});
  plan::PlannedCardSegment& s = job.card[0];
  s.segment.moves = 175;
  s.chunks.push_back({10000, 110, -10, -1});
  s.chunks.push_back({50, 1, 0, 0});
  s.chunks.push_back({50, 1, 0, 0});
  const auto wire = card::to_wire(job, "add2.ngc");
  ASSERT_TRUE(wire.ok()) << plan::join(wire.errors);
  ASSERT_EQ(wire->segments.size(), 2u);
  EXPECT_EQ(uint64_t(wire->segments[0].u) << wire->segments[0].k, 170u);
  ASSERT_EQ(wire->segments[0].chunks.size(), 64u);
  EXPECT_TRUE(wire->segments[0].chunks.back() == (card::WireChunk{10000, 107, -10, -1}));
  ASSERT_EQ(wire->segments[1].chunks.size(), 3u);
  const card::WireChunk& rest = wire->segments[1].chunks.front();
  EXPECT_TRUE(rest == (card::WireChunk{3259, 3, -117, -1}))
      << rest.interval << " " << rest.count << " " << rest.add << " " << rest.add2;
  std::vector<plan::Chunk> pieces;
  for (const auto& w : wire->segments)
    for (const auto& c : w.chunks) pieces.push_back({c.interval, c.count, c.add, c.add2});
  EXPECT_EQ(plan::expand(pieces, 0), plan::expand(job.card[0].chunks, 0));
}

// Chunks outside the card's form are refused before anything is sent: increments
// 5, 2, -1 change sign; increments 32000, 32500, 33000 leave 16 bits.
TEST(WireJob, ChunkOutsideTheCardsAdd2RuleIsAnError) {
  for (const plan::Chunk bad : {plan::Chunk{10000, 4, 5, -3}, plan::Chunk{100, 4, 32000, 500}}) {
    plan::PlannedJob job = one_move_chunks(1, {4, 0, 0, 0}, {1, 1, 1, 1}, {1, 0, 0, 0});
    job.card[0].segment.moves = 4;
    job.card[0].chunks = {bad};
    const auto wire = card::to_wire(job, "bad.ngc");
    ASSERT_FALSE(wire.ok());
    EXPECT_NE(plan::join(wire.errors).find("is outside the card's chunk form"), std::string::npos)
        << plan::join(wire.errors);
  }
  EXPECT_TRUE(card::in_card_form({100, 4, 4, -2}));  // increments 4, 2, 0
  EXPECT_TRUE(card::in_card_form({100, 2, 5, -32768}));  // one increment
  EXPECT_FALSE(card::in_card_form({100, 4, 5, -3}));
}

// The same with a pattern that repeats only every 199 moves: no cut fits.
TEST(WireJob, SegmentThatCannotBeCutIsAnError) {
  const plan::PlannedJob job = one_move_chunks(199, {199, 3, 0, 0}, {1, 199, 1, 1}, {1, 3, 0, 0});
  const auto wire = card::to_wire(job, "many.ngc");
  ASSERT_FALSE(wire.ok());
  EXPECT_EQ(plan::join(wire.errors).rfind("many.ngc:7:1: segment of 199 moves needs more than the card's 64 "
                                          "timing chunks",
                                          0),
            0u)
      << plan::join(wire.errors);
}

TEST(JobOnCard, LandsOnThePlannedStepsAtThePlannedCycles) {
  const plan::Machine m = machine("plotter.toml");
  const auto planned = plan_text("G21 G90\nG1 X2 Y0.5 F3000\nG1 X3 Y2\nG3 X2 Y3 I-1 J0\nG1 X0 Y0\n", m);
  const auto wire = card::to_wire(planned, "inline.ngc");
  ASSERT_TRUE(wire.ok()) << plan::join(wire.errors);
  std::vector<plan::Chunk> all;
  for (const auto& pc : planned.card) all.insert(all.end(), pc.chunks.begin(), pc.chunks.end());
  size_t with_add2 = 0;  // the card's chunk form has add2: the job uses it
  for (const auto& s : wire->segments)
    for (const auto& c : s.chunks) with_add2 += c.add2 != 0;
  EXPECT_GT(with_add2, 0u);
  const std::vector<int64_t> expected = plan::expand(all, 0);

  sim::RtlDut<CoreRtl> dut;
  std::vector<uint64_t> events;
  uint32_t prev = 0;
  int64_t start_cycle = -1;
  sim::CoreDriver<sim::RtlDut<CoreRtl>> drv(
      dut, [&](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut& o) {
        if (in.cmd_valid && o.cmd_ready && in.cmd_data >> 28 == 3 && (in.cmd_data & 1))
          start_cycle = int64_t(c);
        if (o.step & ~prev) events.push_back(c);
        prev = o.step;
      });
  drv.reset();
  drv.send(card::encode_job(m, *wire));
  drv.run_until_stopped(200'000'000);
  ASSERT_FALSE(drv.last().fault) << "error code " << drv.last().err_code;
  for (int a = 0; a < 4; ++a) EXPECT_EQ(drv.last().position[a], planned.step_segments.back().end[a]);
  ASSERT_EQ(events.size(), expected.size());
  const uint32_t stretches = drv.read(card::Register::stretch_count);
  EXPECT_EQ(stretches, 0u);
  // START is taken in cycle s; move i fires at s + t_i and its pins rise one cycle later.
  for (size_t i = 0; i < events.size(); ++i)
    ASSERT_EQ(int64_t(events[i]), start_cycle + expected[i] + 1) << "move " << i;
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// Every board of rtl/builds.json, end to end: its Verilated card is asked what it
// is through its SPI pins (the capability registers must say what the table says;
// the fast engine's too),
// a G-code job is planned for what it said and run through its pins, checked
// against the plan after every card segment; and a job planned for another card
// is refused before anything moves.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>

#include "card/caps.h"
#include "cpstep/builds.h"
#include "run/card_job.h"
#include "run/sim_run.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

const std::string kMachine = std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/seed002.toml";

class Boards : public ::testing::TestWithParam<const builds::Build*> {};

std::vector<const builds::Build*> boards() {
  std::vector<const builds::Build*> v;
  for (const builds::Build* b : builds::kAll)
    if (b->board) v.push_back(b);
  return v;
}

// The card's registers, read through its pins, against the table's row: N, W,
// UMAX, KMAX, queues, TW, PW, the command buffer, the protocol, the clock, the id.
TEST_P(Boards, TheCardReportsItsBuild) {
  const builds::Build& b = *GetParam();
  const card::CardCaps caps = run::connect_sim(b.name, run::Engine::rtl);
  EXPECT_EQ(run::connect_sim(b.name, run::Engine::model), caps);
  EXPECT_EQ(caps.id, card::kCardId);
  EXPECT_EQ(caps.n, b.n);
  EXPECT_EQ(caps.w, b.w);
  EXPECT_EQ(caps.umax, b.umax);
  EXPECT_EQ(caps.kmax, b.kmax);
  EXPECT_EQ(caps.chunk_queue(), 1u << b.caw);
  EXPECT_EQ(caps.segment_queue(), 1u << b.saw);
  EXPECT_EQ(caps.tw, b.tw);
  EXPECT_EQ(caps.pw, 32u);
  EXPECT_EQ(caps.command_buffer_words(), 1u << b.cbuf_aw);
  EXPECT_EQ(caps.protocol, card::kProtocolVersion);
  EXPECT_EQ(caps.clock_hz, b.clock_hz);
  EXPECT_EQ(caps.build_id, b.build_id);
  EXPECT_EQ(card::build_of(caps), &b);
  EXPECT_EQ(caps.ptimer, b.ptimer != 0);
  EXPECT_EQ(caps, *card::board_caps(b.name));
  EXPECT_EQ(card::unusable(caps, 4), "");
}

// A job planned for what the card said runs on it through its pins: every card
// segment ends where the plan says, the counters match, nothing is late.
TEST_P(Boards, AGcodeJobRunsOnTheCard) {
  const builds::Build& b = *GetParam();
  const card::CardCaps caps = run::connect_sim(b.name);
  auto prepared = run::prepare_job(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc", kMachine, caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  EXPECT_EQ(job.clock_hz(), double(b.clock_hz));
  EXPECT_EQ(job.machine.card.pattern_capacity, b.w);
  run::SimRunOptions o;
  o.board = std::string(b.name);
  o.engine = run::Engine::lockstep;  // the Verilated card, and the fast engine compared with it every cycle
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.moves_done, job.moves());
  EXPECT_EQ(r.checked_segments, job.checkpoints.size());
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  EXPECT_EQ(r.stretch_count, 0u);
}

// A line whose reduced pattern is longer than the iCEBreaker's W = 256 (the
// issue's case): planned for the card it is split into patterns that fit, and
// runs; planned for the HX8K's W = 1024 it would not fit, and the iCEBreaker's
// card refuses that job at connect, before a single word of it is sent.
TEST(BoardsLongPattern, PlannedForTheCardItRunsPlannedForAnotherItIsRefusedUnsent) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "boards";
  fs::create_directories(dir);
  const fs::path file = dir / "long_pattern.ngc";
  // 80 steps/mm: X 7.01 mm = 561 steps, Y 3.43 mm = 274.4 -> 274 steps; gcd 1: a 561-move pattern.
  std::ofstream(file) << "G21 G90\nG1 X7.0125 Y3.425 F1200\nM2\n";
  const card::CardCaps ice = run::connect_sim("icebreaker");
  auto for_ice = run::prepare_job(file, kMachine, ice);
  ASSERT_TRUE(for_ice.ok()) << plan::join(for_ice.errors);
  for (const card::WireSegment& s : for_ice.value->wire.segments) {
    uint32_t g = s.u;
    for (uint32_t v : s.v) g = std::gcd(g, v);
    EXPECT_LE(s.u / g, ice.w) << "a wire segment's pattern is longer than the card's W";
  }
  const run::CardRun ok = run::run_on_sim(*for_ice.value, {});
  ASSERT_TRUE(ok.ok()) << ok.faults.front().message;
  EXPECT_EQ(ok.position, for_ice.value->checkpoints.back().position);

  auto for_hx8k = run::prepare_job(file, kMachine, *card::board_caps("hx8k"));
  ASSERT_TRUE(for_hx8k.ok()) << plan::join(for_hx8k.errors);
  bool longer = false;
  for (const card::WireSegment& s : for_hx8k.value->wire.segments) {
    uint32_t g = s.u;
    for (uint32_t v : s.v) g = std::gcd(g, v);
    longer = longer || s.u / g > ice.w;
  }
  ASSERT_TRUE(longer) << "the job should need a pattern longer than 256 on the HX8K's card";
  run::SimRunOptions o;
  o.board = "icebreaker";
  const run::CardRun refused = run::run_on_sim(*for_hx8k.value, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.faults.front().name, "LINK");
  EXPECT_NE(refused.faults.front().message.find("planned for hx8k"), std::string::npos)
      << refused.faults.front().message;
  EXPECT_NE(refused.faults.front().message.find("nothing was sent"), std::string::npos);
  EXPECT_EQ(refused.moves_done, 0u);
  EXPECT_EQ(refused.segments_done, 0u);
  // The only words the card took are the READs of its capability registers.
  EXPECT_EQ(refused.link.stats.words, card::kCapsRegisters.size()) << "job words reached the card";
  for (int a = 0; a < 4; ++a) EXPECT_EQ(refused.position[a], 0);
}

// The machine file's [card] keys are checked against the card, at their line.
TEST(BoardsMachineKeys, AStatedClockOtherThanTheCardsIsRefusedAtItsLine) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "boards";
  fs::create_directories(dir);
  const fs::path machine = dir / "stated_clock.toml";
  std::ifstream in(kMachine);
  std::ofstream out(machine);
  out << "[card]\nclock_hz = 48_000_000\n" << in.rdbuf();
  out.close();
  auto r = run::prepare_job(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc", machine,
                            *card::board_caps("icebreaker"));
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].loc.line, 2);
  EXPECT_NE(r.errors[0].message.find("runs at 16500000 Hz"), std::string::npos) << r.errors[0].message;
  // The same key with the card's clock is accepted.
  std::ifstream in2(kMachine);
  std::ofstream out2(machine);
  out2 << "[card]\nclock_hz = 16_500_000\n" << in2.rdbuf();
  out2.close();
  EXPECT_TRUE(run::prepare_job(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc", machine,
                               *card::board_caps("icebreaker"))
                  .ok());
}

INSTANTIATE_TEST_SUITE_P(All, Boards, ::testing::ValuesIn(boards()),
                         [](const auto& p) { return std::string(p.param->name); });

}  // namespace
}  // namespace cpstep::tb

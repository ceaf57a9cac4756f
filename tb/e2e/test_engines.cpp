// SPDX-License-Identifier: MIT
// The simulated card's two engines (docs/SIM.md "Engines"): the fast engine
// (the golden model advanced event to event) and the Verilated card give the
// same run. Example jobs run on each alone, with the STEP/DIR VCDs compared line
// by line — every edge, its time and value — and the final position, counters,
// faults, move events and link statistics compared whole; a link that damages
// frames in flight (resends, lost results) on both; and the lockstep engine's
// own check, which names the first cycle and signal where the engines differ.
// The lockstep runs themselves (every output compared every cycle, the skipped
// spans included) are corpus_lockstep.* and the card link tests (test_card_link).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "card/caps.h"
#include "card/link.h"
#include "run/card_job.h"
#include "run/sim_run.h"
#include "sim/card_configs.h"
#include "sim/spi_master.h"
#include "sim/twin_card.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

const std::string kSource = CPSTEP_SOURCE_DIR;

// The first line where two VCD files differ, described: the time it is at (the
// last `#` line before it) and both lines; "" when they are the same.
std::string vcd_difference(const fs::path& a, const fs::path& b) {
  std::ifstream fa(a), fb(b);
  std::string la, lb, time = "the header";
  for (size_t line = 1;; ++line) {
    const bool ga = bool(std::getline(fa, la)), gb = bool(std::getline(fb, lb));
    if (!ga && !gb) return "";
    if (ga != gb || la != lb)
      return fmt::format("line {} (at {}): rtl '{}', model '{}'", line, time, ga ? la : "<end>", gb ? lb : "<end>");
    if (!la.empty() && la[0] == '#') time = "time " + la.substr(1) + " ps";
  }
}

// Flips one bit of every 3rd COMMANDS frame the host sends that is long enough
// (a word or its CRC), the same on both engines. (Every 7th frame of any kind
// was damaged before the host batched its frames: a job's few frames are now
// mostly POLLs, whose padding the card ignores.)
class DamagingLink final : public card::Link {
 public:
  explicit DamagingLink(card::Link& inner) : inner_(inner) {}
  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override {
    std::vector<uint8_t> bytes(mosi.begin(), mosi.end());
    if (!bytes.empty() && bytes[0] == uint8_t(card::FrameType::commands) && ++n_ % 3 == 0 && bytes.size() > 12)
      bytes[4 + n_ % 8] ^= uint8_t(1u << (n_ % 8));
    return inner_.transfer(bytes);
  }
  void wait(double seconds) override { inner_.wait(seconds); }
  [[nodiscard]] double now_s() const override { return inner_.now_s(); }
  [[nodiscard]] std::string name() const override { return inner_.name(); }

 private:
  card::Link& inner_;
  uint64_t n_ = 0;
};

struct Case {
  const char* job;
  const char* board;
  bool damage;
};

class Engines : public ::testing::TestWithParam<Case> {};

// The same job on the Verilated card and on the fast engine: the same pins,
// edge for edge, and the same everything else the run reports.
TEST_P(Engines, TheSameRunOnBothEngines) {
  const Case c = GetParam();
  const card::CardCaps caps = run::connect_sim(c.board, run::Engine::rtl);
  EXPECT_EQ(run::connect_sim(c.board, run::Engine::model), caps);
  auto prepared = run::prepare_job(kSource + "/examples/jobs/" + c.job, kSource + "/examples/machines/seed002.toml", caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "engines";
  fs::create_directories(dir);
  const std::string stem = fmt::format("{}_{}{}", fs::path(c.job).stem().string(), c.board, c.damage ? "_damaged" : "");
  run::CardRun runs[2];
  fs::path vcds[2];
  const run::Engine engines[2] = {run::Engine::rtl, run::Engine::model};
  for (int e = 0; e < 2; ++e) {
    run::SimRunOptions o;
    o.engine = engines[e];
    o.board = c.board;
    vcds[e] = dir / fmt::format("{}.{}.vcd", stem, run::engine_name(engines[e]));
    o.vcd = vcds[e].string();
    if (c.damage) o.wrap_link = [](card::Link& l) { return std::make_unique<DamagingLink>(l); };
    runs[e] = run::run_on_sim(*prepared.value, o);
  }
  const run::CardRun &rtl = runs[0], &model = runs[1];
  ASSERT_TRUE(rtl.ok()) << rtl.faults.front().name << ": " << rtl.faults.front().message;
  EXPECT_EQ(vcd_difference(vcds[0], vcds[1]), "") << "the pins differ: " << vcds[0] << " vs " << vcds[1];
  EXPECT_GT(fs::file_size(vcds[0]), 1000u);
  EXPECT_TRUE(model.ok());
  EXPECT_EQ(model.position, rtl.position);
  EXPECT_EQ(model.status.fault, rtl.status.fault);
  EXPECT_EQ(model.status.err_code, rtl.status.err_code);
  EXPECT_EQ(model.status.running, rtl.status.running);
  EXPECT_EQ(model.status.stretched, rtl.status.stretched);
  EXPECT_EQ(model.moves_done, rtl.moves_done);
  EXPECT_EQ(model.segments_done, rtl.segments_done);
  EXPECT_EQ(model.stretch_count, rtl.stretch_count);
  EXPECT_EQ(model.start_cycle, rtl.start_cycle);
  EXPECT_EQ(model.cycles, rtl.cycles);
  EXPECT_EQ(model.sim_cycles, rtl.sim_cycles);
  EXPECT_EQ(model.move_cycles, rtl.move_cycles);
  EXPECT_EQ(model.checked_segments, rtl.checked_segments);
  for (int a = 0; a < plan::kAxes; ++a) {
    EXPECT_EQ(model.pulses[a].cycles, rtl.pulses[a].cycles) << "axis " << a;
    EXPECT_EQ(model.pulses[a].dirs, rtl.pulses[a].dirs) << "axis " << a;
  }
  const card::LinkStats &ls = model.link.stats, &lr = rtl.link.stats;
  EXPECT_EQ(ls.transfers, lr.transfers);
  EXPECT_EQ(ls.command_frames, lr.command_frames);
  EXPECT_EQ(ls.polls, lr.polls);
  EXPECT_EQ(ls.bytes, lr.bytes);
  EXPECT_EQ(ls.resent, lr.resent);
  EXPECT_EQ(ls.damaged, lr.damaged);
  EXPECT_EQ(ls.no_room, lr.no_room);
  EXPECT_EQ(ls.bad_replies, lr.bad_replies);
  EXPECT_EQ(ls.lost_results, lr.lost_results);
  EXPECT_EQ(model.link.busy_cycles, rtl.link.busy_cycles);
  if (c.damage) {
    EXPECT_GT(lr.damaged + lr.bad_replies, 0u) << "the link damaged nothing";
  }
  // The fast engine took its shortcuts.
  EXPECT_EQ(model.engine, run::Engine::model);
  EXPECT_GT(model.skipped_cycles, model.sim_cycles / 2);
  EXPECT_EQ(rtl.skipped_cycles, 0u);
}

INSTANTIATE_TEST_SUITE_P(ExampleJobs, Engines,
                         ::testing::Values(Case{"tab.ngc", "icebreaker", false}, Case{"tab.ngc", "hx8k", false},
                                           Case{"tight_arcs.ngc", "icebreaker", false},
                                           Case{"tab.ngc", "icebreaker", true}),
                         [](const auto& p) {
                           return fmt::format("{}_{}{}", fs::path(p.param.job).stem().string(), p.param.board,
                                              p.param.damage ? "_damaged" : "");
                         });

// A G-code program written into the test's directory, planned on seed002.toml for the card `caps`.
plan::Result<run::CardJob> job_of(const std::string& name, const std::string& gcode, const card::CardCaps& caps) {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "engines";
  fs::create_directories(dir);
  std::ofstream(dir / name) << gcode;
  return run::prepare_job((dir / name).string(), kSource + "/examples/machines/seed002.toml", caps);
}

// A dwell longer than the card can time between two moves (2^32 - 1 cycles: 260
// s at the iCEBreaker's 16.5 MHz) and one after the last move run as pause
// moves (docs/PLANNING.md "Dwells"): on the card they step no axis, the pins show
// the gap, the card counts them, and it runs on to the trailing dwell's end.
// 4.6 * 10^9 cycles: about 20 minutes on the Verilated card, seconds here.
TEST(EngineLongJobs, ADwellLongerThanAMoveIntervalAndATrailingOneRunAsPauseMoves) {
  const card::CardCaps caps = run::connect_sim("icebreaker", run::Engine::model);
  auto prepared = job_of("long_dwell.ngc", "G21 G90\nG1 X1 F600\nG4 P270\nG1 X2\nG4 P3\nM2\n", caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  const run::CardJob& job = *prepared.value;
  EXPECT_TRUE(job.warnings.empty()) << plan::join(job.warnings);
  ASSERT_GT(job.card_moves(), job.moves());
  const run::CardRun r = run::run_on_sim(job, {});
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  const double hz = double(caps.clock_hz);
  EXPECT_EQ(r.move_cycles.size(), job.moves());
  EXPECT_EQ(r.moves_done, job.card_moves());
  EXPECT_EQ(r.position[0], 2 * 80);
  // The gap at the pins between the last step of X1 and the first of X2: the
  // dwell and the ramps around it, each move on its planned time.
  const size_t half = job.moves() / 2;
  const double gap_s = double(r.move_cycles[half] - r.move_cycles[half - 1]) / hz;
  EXPECT_GT(gap_s, 270.0);
  EXPECT_LT(gap_s, 270.5);
  const std::vector<int64_t> chunk_cycles = run::chunk_cycles(job);
  ASSERT_EQ(chunk_cycles.size(), r.move_cycles.size());
  for (size_t i = 0; i < r.move_cycles.size(); ++i)
    ASSERT_NEAR(double(r.move_cycles[i] - r.start_cycle), double(chunk_cycles[i]), 1.0) << "move " << i;
  // The card ran on for the trailing dwell: running_o fell 3 s after the last step.
  const double tail_s = double(r.cycles - r.move_cycles.back()) / hz;
  EXPECT_GT(tail_s, 3.0 - 1e-3);
  EXPECT_LT(tail_s, 3.0 + 1e-3);
  EXPECT_NEAR(double(r.cycles - r.start_cycle) / hz, job.planned.stats.duration_s, 1e-3);
  EXPECT_GT(r.skipped_cycles, r.sim_cycles / 2);
}

// A pause segment (every v = 0) on the Verilated card, in lockstep with the fast
// engine: a trailing dwell of 0.2 s.
TEST(EngineLongJobs, ATrailingDwellRunsInLockstep) {
  const card::CardCaps caps = run::connect_sim("icebreaker", run::Engine::rtl);
  auto prepared = job_of("trailing_dwell.ngc", "G21 G90\nG1 X1 F600\nG4 P0.2\nM2\n", caps);
  ASSERT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  run::SimRunOptions o;
  o.engine = run::Engine::lockstep;
  const run::CardRun r = run::run_on_sim(*prepared.value, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  EXPECT_EQ(r.moves_done, prepared.value->card_moves());
  EXPECT_EQ(r.moves_done, r.move_cycles.size() + 1);
  EXPECT_NEAR(double(r.cycles - r.move_cycles.back()) / double(caps.clock_hz), 0.2, 1e-3);
}

// The lockstep engine's check: a fast engine built for another card (STEP
// active low after reset instead of high) differs from the Verilated card in the
// very first cycle, and the mismatch names the cycle, the signal and both values.
TEST(EngineLockstep, AMismatchNamesTheCycleTheSignalAndBothValues) {
  using Card = sim::CardIcebreaker;
  model::CpCardParams other = Card::model_params();
  other.core.step_pol_reset = !other.core.step_pol_reset;
  sim::TwinCardDut<Card> twin(other);
  sim::SpiMaster<sim::TwinCardDut<Card>> spi(twin);
  try {
    spi.reset();
    spi.idle(10);
    FAIL() << "the engines did not differ";
  } catch (const sim::EngineMismatch& m) {
    EXPECT_EQ(m.signal, "step_o");
    EXPECT_EQ(m.cycle, 0u);
    EXPECT_NE(m.expected, m.actual);
    EXPECT_NE(std::string(m.what()).find("cycle 0: step_o"), std::string::npos) << m.what();
  }
  // Built for the same card, they agree through a reset, a POLL and idle time.
  sim::TwinCardDut<Card> same;
  sim::SpiMaster<sim::TwinCardDut<Card>> spi2(same);
  spi2.reset();
  const std::vector<uint8_t> poll(64, 0);
  EXPECT_NO_THROW(spi2.transfer(poll));
  EXPECT_NO_THROW(spi2.idle(100000));
  EXPECT_GT(same.skipped(), 90000u);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The host's SPI client (host/card/card_client.h) against the Verilated card,
// through its pins: the whole job path of `cpstep run` (run_on_sim), the
// spidev path over the simulated card (run_on_link), and the client alone on the
// small card (a 32-word command buffer), with links that damage bytes in flight
// or talk to the card behind the client's back.
//
// Expected values come from the plan's checkpoints and the test's own segments
// (positions summed here), from a clean run of the same job (pins compared cycle
// by cycle from START), and from the card's replies decoded by the frame codec
// (docs/PROTOCOL.md), never from the client's own account.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <limits>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "Vcp_card_small.h"
#include "card/caps.h"
#include "card/card_client.h"
#include "card/frame.h"
#include "card/protocol.h"
#include "run/card_job.h"
#include "run/feed.h"
#include "run/link_run.h"
#include "run/sim_run.h"
#include "sim/card_configs.h"
#include "sim/sim_link.h"
#include "sim/spi_master.h"

namespace cpstep::tb {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- links

// Forwards every call to another link; a test may change the bytes of a
// transfer on the way out (MOSI) or back (MISO), and may send frames of its own
// before one of the client's. Transfers are numbered from 0; COMMANDS frames
// (type byte 0x01) are also numbered among themselves.
class TamperLink : public card::Link {
 public:
  struct Transfer {
    uint64_t index = 0;     // among all transfers
    int64_t commands = -1;  // among COMMANDS frames, -1 for a POLL
    std::vector<uint8_t> mosi, miso;
  };
  using Hook = std::function<void(Transfer&)>;

  explicit TamperLink(card::Link& inner) : inner_(inner) {}

  Hook before;  // may change t.mosi (t.miso is empty)
  Hook after;   // may change t.miso
  Hook intrude; // called before the transfer; may call send_own()

  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override {
    Transfer t;
    t.index = log_->size();
    t.mosi.assign(mosi.begin(), mosi.end());
    if (t.mosi[0] == uint8_t(card::FrameType::commands)) t.commands = int64_t(commands_++);
    if (intrude) intrude(t);
    if (before) before(t);
    t.miso = inner_.transfer(t.mosi);
    if (after) after(t);
    log_->push_back(t);
    return t.miso;
  }
  void wait(double seconds) override { inner_.wait(seconds); }
  double now_s() const override { return inner_.now_s(); }
  std::string name() const override { return "tampered " + inner_.name(); }

  // A frame straight to the card, not logged as the client's.
  std::vector<uint8_t> send_own(const std::vector<uint8_t>& mosi) { return inner_.transfer(mosi); }
  // What went over the link, as the card saw it (after `before`) and answered;
  // shared, so that it outlives the link.
  const std::vector<Transfer>& log() const { return *log_; }
  std::shared_ptr<const std::vector<Transfer>> shared_log() const { return log_; }

 private:
  card::Link& inner_;
  std::shared_ptr<std::vector<Transfer>> log_ = std::make_shared<std::vector<Transfer>>();
  uint64_t commands_ = 0;
};

using Log = std::vector<TamperLink::Transfer>;

// The card's reply in transfer i (it reports on the frame before it).
card::Reply reply_of(const Log& log, size_t i, unsigned axes) { return card::decode_reply(log.at(i).miso, axes); }

// ---------------------------------------------------------------- jobs on the default card

// A fast two-axis machine (short moves take few cycles) and a star of eight
// lines with direction changes on x and y: 8 card segments, 280 moves, about
// 0.13 s of motion; START goes after the first four, the rest stream in while
// the card runs. Planned for the card the tests run it on (sim::CardDefault), at
// that card's clock.
run::CardJob star() {
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "card_link";
  fs::create_directories(dir);
  // One pair of files per test process (ctest runs the tests in parallel).
  const std::string pid = std::to_string(::getpid());
  const fs::path machine = dir / ("fast." + pid + ".toml"), file = dir / ("star." + pid + ".ngc");
  std::ofstream(machine).close();
  for (const char* axis : {"x", "y"})
    std::ofstream(machine, std::ios::app)
        << "[axes." << axis << "]\nsteps_per_mm = 80\ntravel_min_mm = 0\ntravel_max_mm = 100\n"
        << "max_velocity_mm_s = 200\nmax_accel_mm_s2 = 20000\nmax_jerk_mm_s3 = 2000000\ndriver = \"TMC2209\"\n";
  std::ofstream(file) << "G21 G90\nG1 X0.4 Y0.2 F6000\nG1 X0.1 Y0.5\nG1 X0.5 Y0.6\nG1 X0.2 Y0.1\n"
                         "G1 X0.6 Y0.3\nG1 X0.3 Y0.7\nG1 X0.7 Y0.5\nG1 X0 Y0\nM2\n";
  auto r = run::prepare_job(file, machine, card::caps_of(sim::CardDefault::kBuild));
  if (!r.ok()) throw std::runtime_error("the star job does not plan: " + plan::join(r.errors));
  EXPECT_EQ(r.value->wire.segments.size(), 8u);
  EXPECT_EQ(r.value->wire.start_after, 4u);
  return std::move(*r.value);
}

// The longest command of a stream, in words.
size_t longest_command(const std::vector<uint32_t>& words) {
  size_t longest = 0;
  for (size_t i = 0; i < words.size(); i += card::command_words(words[i], 4))
    longest = std::max(longest, card::command_words(words[i], 4));
  return longest;
}

// A pin change: cycle from START, STEP and DIR of every axis after it.
struct PinChange {
  int64_t cycle;
  uint32_t step, dir;
  friend bool operator==(const PinChange&, const PinChange&) = default;
};

struct Outcome {
  run::CardRun run;
  std::vector<PinChange> pins;  // from the START cycle on
  uint32_t pins_at_start = 0;   // STEP and DIR (dir << 8 | step) in the START cycle
};

Outcome run_job(const run::CardJob& job, run::SimRunOptions o) {
  // Both engines, every output compared every cycle (docs/SIM.md "Engines").
  o.engine = run::Engine::lockstep;
  struct Seen {
    uint64_t cycle;
    uint32_t step, dir;
  };
  std::vector<Seen> all;
  o.pins = [&all](uint64_t c, uint32_t step, uint32_t dir) {
    if (all.empty() || all.back().step != step || all.back().dir != dir) all.push_back({c, step, dir});
  };
  Outcome out;
  out.run = run::run_on_sim(job, o);
  const auto start = int64_t(out.run.start_cycle);
  for (const Seen& s : all) {
    if (int64_t(s.cycle) <= start) out.pins_at_start = s.dir << 8 | s.step;
    else out.pins.push_back({int64_t(s.cycle) - start, s.step, s.dir});
  }
  return out;
}

// The job ran exactly as planned: every card segment's end checked on the pins,
// the card's counters and positions equal to the plan's.
void expect_exact(const run::CardJob& job, const run::CardRun& r) {
  EXPECT_TRUE(r.ok()) << (r.faults.empty() ? "" : r.faults.front().name + ": " + r.faults.front().message);
  EXPECT_EQ(r.checked_segments, job.checkpoints.size());
  EXPECT_EQ(r.position_mismatches, 0u);
  EXPECT_EQ(r.move_cycles.size(), job.moves());
  EXPECT_EQ(r.moves_done, job.moves());
  EXPECT_EQ(r.segments_done, job.wire.segments.size());
  EXPECT_EQ(r.position, job.checkpoints.back().position);
  EXPECT_EQ(r.stretch_count, 0u);
}

// A job, its clean runs in large and in one-command frames, shared by the tests.
class CardLink : public ::testing::Test {
 protected:
  // A failure here must fail every test, not skip it (GoogleTest skips a suite whose
  // SetUpTestSuite fails, and ctest counts a skip as no failure): SetUp checks.
  static void SetUpTestSuite() {
    try {
      job_ = new run::CardJob(star());
      small_frames_ = longest_command(job_->words) + 1;  // a command and the marker
    } catch (const std::exception& e) {
      setup_error_ = e.what();
    }
  }
  void SetUp() override { ASSERT_NE(job_, nullptr) << setup_error_; }
  static void TearDownTestSuite() {
    delete job_;
    delete clean_large_;
    delete clean_small_;
    clean_large_ = clean_small_ = nullptr;
  }

  // The clean runs, made when a test first needs them.
  static const Outcome& clean_large() {
    if (!clean_large_) clean_large_ = new Outcome(run_job(*job_, {}));
    return *clean_large_;
  }
  static const Outcome& clean_small() {
    if (!clean_small_) {
      run::SimRunOptions o;
      o.client.max_frame_words = small_frames_;
      clean_small_ = new Outcome(run_job(*job_, o));
      // The frame to damage: the next to last, a segment sent while the card runs.
      victim_ = int64_t(clean_small_->run.link.stats.command_frames) - 2;
    }
    return *clean_small_;
  }

  // The job in small frames, through a TamperLink set up by `setup`; `log`
  // receives what went over it.
  static Outcome tampered(const std::function<void(TamperLink&)>& setup,
                          std::shared_ptr<const Log>* log = nullptr) {
    clean_small();  // victim_
    run::SimRunOptions o;
    o.client.max_frame_words = small_frames_;
    o.wrap_link = [&](card::Link& inner) {
      auto t = std::make_unique<TamperLink>(inner);
      setup(*t);
      if (log) *log = t->shared_log();
      return t;
    };
    return run_job(*job_, o);
  }

  struct Repairs {
    uint64_t bad_replies, lost_results, resent;
  };
  // The link's counts, one COMMANDS frame more than the clean run per resend,
  // and nothing ran twice or was skipped: the job exact and, from START on, the
  // pins those of the clean run.
  static void expect_repaired(const Outcome& out, const Repairs& want) {
    const card::LinkStats& s = out.run.link.stats;
    EXPECT_EQ(s.bad_replies, want.bad_replies);
    EXPECT_EQ(s.lost_results, want.lost_results);
    EXPECT_EQ(s.resent, want.resent);
    EXPECT_EQ(s.command_frames, clean_small().run.link.stats.command_frames + want.resent);
    expect_exact(*job_, out.run);
    EXPECT_TRUE(out.pins == clean_small().pins);
  }

  static run::CardJob* job_;
  static std::string setup_error_;
  static size_t small_frames_;
  static int64_t victim_;
  static Outcome* clean_large_;
  static Outcome* clean_small_;
};
run::CardJob* CardLink::job_ = nullptr;
std::string CardLink::setup_error_;
size_t CardLink::small_frames_ = 0;
int64_t CardLink::victim_ = 0;
Outcome* CardLink::clean_large_ = nullptr;
Outcome* CardLink::clean_small_ = nullptr;

// The job's segment ends (run::CardJob::segment_end_cycle, from each wire
// segment's chunks in closed form) are the planner's move times
// (chunk_cycles, its chunks expanded move by move): the end of each segment is
// the time of its last move.
TEST_F(CardLink, SegmentEndsAreTheLastMoveTimesAndBufferedTimeSpansThem) {
  const run::CardJob& j = *job_;
  const std::vector<int64_t> chunk_cycles = run::chunk_cycles(j);
  ASSERT_EQ(j.segment_end_cycle.size(), j.wire.segments.size());
  ASSERT_EQ(j.segment_end_word.size(), j.wire.segments.size());
  uint64_t moves = 0;
  for (size_t i = 0; i < j.wire.segments.size(); ++i) {
    const card::WireSegment& w = j.wire.segments[i];
    moves += uint64_t(w.u) << w.k;
    ASSERT_LE(moves, chunk_cycles.size());
    EXPECT_EQ(int64_t(j.segment_end_cycle[i]), chunk_cycles[moves - 1]) << "segment " << i;
    // The word just past the segment starts the next command (or ends the stream).
    EXPECT_LE(j.segment_end_word[i], j.words.size());
  }
  EXPECT_EQ(moves, chunk_cycles.size());
  // buffered_seconds() from the card's next move (its moves done, as an index
  // into the planner's move times: this job has no pause moves) to the end of
  // the last segment handed over, for every segment the card may run and
  // moves into it, and every segment handed over.
  const double hz = j.clock_hz();
  ASSERT_EQ(j.segment_end_moves.back(), chunk_cycles.size());
  for (uint64_t done = 0; done < 8; ++done) {
    const uint64_t first = done ? j.segment_end_moves[done - 1] : 0;
    for (const uint64_t made : {first, first + 1, (first + j.segment_end_moves[done]) / 2, j.segment_end_moves[done] - 1})
      for (uint64_t sent = 0; sent <= 8; ++sent) {
        const uint64_t handed = sent ? j.segment_end_word[sent - 1] : 0;
        const double expect = sent > done ? double(int64_t(j.segment_end_cycle[sent - 1]) - chunk_cycles[made]) / hz : 0;
        EXPECT_DOUBLE_EQ(run::buffered_seconds(j, done, made, handed), std::max(expect, 0.0))
            << "segments done " << done << ", moves made " << made << ", segments handed " << sent;
        // A word short of the segment: it is not the card's yet.
        if (sent > 0 && handed > 0) {
          EXPECT_LE(run::buffered_seconds(j, done, made, handed - 1), run::buffered_seconds(j, done, made, handed));
        }
      }
  }
  EXPECT_EQ(run::buffered_seconds(j, 0, 0, 0), 0.0);
}

TEST_F(CardLink, ManySmallFramesAndOneLargeEndInTheSamePins) {
  const Outcome& large = clean_large();
  const Outcome& small = clean_small();
  expect_exact(*job_, large.run);
  expect_exact(*job_, small.run);
  // Both runs first read the card's capabilities, one READ a frame; then the large
  // run sends the job in one frame (it fits the card's 512 words), the small one a
  // frame per command.
  const size_t caps_reads = card::kCapsRegisters.size();
  size_t commands = 0;
  for (size_t i = 0; i < job_->words.size(); i += card::command_words(job_->words[i], 4)) ++commands;
  ASSERT_LT(job_->words.size() + 1, 512u);
  EXPECT_EQ(large.run.link.stats.command_frames, caps_reads + 1);
  EXPECT_GE(small.run.link.stats.command_frames, caps_reads + job_->wire.segments.size());
  EXPECT_LT(small.run.link.stats.command_frames, caps_reads + commands);
  EXPECT_GE(victim_, int64_t(caps_reads) + 5);
  EXPECT_EQ(large.run.link.stats.words, caps_reads + job_->words.size());
  EXPECT_EQ(small.run.link.stats.words, caps_reads + job_->words.size());
  // From START on, every STEP and DIR pin changes at the same cycle in both.
  ASSERT_FALSE(large.pins.empty());
  EXPECT_EQ(large.pins_at_start, small.pins_at_start);
  EXPECT_EQ(large.pins.size(), small.pins.size());
  EXPECT_TRUE(large.pins == small.pins);
  // And the moves fired at the chunk times the plan computed.
  const std::vector<int64_t> chunk_cycles = run::chunk_cycles(*job_);
  ASSERT_EQ(small.run.move_cycles.size(), chunk_cycles.size());
  for (size_t i = 0; i < small.run.move_cycles.size(); ++i)
    ASSERT_EQ(int64_t(small.run.move_cycles[i] - small.run.start_cycle), chunk_cycles[i]) << "move " << i;
}

TEST_F(CardLink, AFrameDamagedOnMosiIsRefusedAndSentAgainOnce) {
  std::shared_ptr<const Log> log;
  const Outcome out = tampered(
      [](TamperLink& t) {
        t.before = [](TamperLink::Transfer& x) {
          if (x.commands == victim_) x.mosi[5] ^= 0x10;  // a bit of the first command word
        };
      },
      &log);
  // The card refused it with BAD_CRC (in the next reply, naming its seq), and
  // the same words went again, once.
  size_t damaged = 0;
  for (size_t i = 0; i < log->size(); ++i)
    if ((*log)[i].commands == victim_) damaged = i;
  ASSERT_GT(damaged, 0u);
  EXPECT_TRUE(reply_of(*log, damaged, 4).status & 1) << "the card runs while the frame goes";
  const card::Reply next = reply_of(*log, damaged + 1, 4);
  ASSERT_TRUE(next.ok()) << next.error;
  EXPECT_EQ(next.last_result, uint8_t(card::FrameResult::bad_crc));
  EXPECT_EQ(next.last_seq, (*log)[damaged].mosi[1]);
  const auto& again = log->at(damaged + 2);  // after the POLL that told
  ASSERT_EQ(again.commands, victim_ + 1);
  std::vector<uint8_t> a = again.mosi, d = (*log)[damaged].mosi;
  d[5] ^= 0x10;  // the words as the client sent them
  const size_t n = 4 + 4 * (size_t(d[2]) << 8 | d[3]);
  a.resize(n);
  d.resize(n);
  a[1] = d[1] = 0;  // the seq differs
  EXPECT_EQ(a, d) << "the resent frame carries the same words";

  EXPECT_EQ(out.run.link.stats.damaged, 1u);
  expect_repaired(out, {.bad_replies = 0, .lost_results = 0, .resent = 1});
}

TEST_F(CardLink, ALostResultIsSettledByTheMarkerAndNotResent) {
  std::shared_ptr<const Log> log;
  int64_t hit = -1;
  const Outcome out = tampered(
      [&hit](TamperLink& t) {
        uint64_t victim = UINT64_MAX;
        t.after = [&hit, victim](TamperLink::Transfer& x) mutable {
          if (x.commands == victim_) victim = x.index;
          if (victim != UINT64_MAX && x.index == victim + 1) {  // the POLL with the victim's result
            x.miso[1] ^= 0x01;          // last_seq, under the CRC
            hit = int64_t(x.index);
          }
        };
      },
      &log);
  ASSERT_GE(hit, 0);
  const card::Reply damaged = reply_of(*log, size_t(hit), 4);
  EXPECT_FALSE(damaged.crc_ok);
  expect_repaired(out, {.bad_replies = 1, .lost_results = 1, .resent = 0});
}

TEST_F(CardLink, ADamagedFrameWhoseResultIsLostIsSentExactlyOnceMore) {
  const Outcome out = tampered([](TamperLink& t) {
    t.before = [](TamperLink::Transfer& x) {
      if (x.commands == victim_) x.mosi[x.mosi.size() / 2] ^= 0x80;
    };
    uint64_t victim = UINT64_MAX;
    t.after = [victim](TamperLink::Transfer& x) mutable {
      if (x.commands == victim_) victim = x.index;
      if (victim != UINT64_MAX && x.index == victim + 1) x.miso[9] ^= 0x04;  // the status word
    };
  });
  expect_repaired(out, {.bad_replies = 1, .lost_results = 1, .resent = 1});
}

// A freshly reset default card behind its pins, as a Link.
struct DefaultCard {
  using Dut = sim::RtlDut<sim::CardDefault>;
  Dut dut;
  sim::SpiMaster<Dut> spi{dut};
  sim::SimLink<Dut> link;
  explicit DefaultCard(double clock_hz) : link(spi, clock_hz) { spi.reset(); }
};

TEST_F(CardLink, TheSpidevPathOverTheSimulatedCard) {
  // run_on_link is what `--transport spidev` runs; here its link is the
  // Verilated card's pins.
  DefaultCard card(job_->clock_hz());
  auto& spi = card.spi;
  auto& link = card.link;
  const run::CardRun r = run::run_on_link(*job_, link, {});
  EXPECT_TRUE(r.ok()) << (r.faults.empty() ? "" : r.faults.front().message);
  EXPECT_FALSE(r.pins_observed);
  EXPECT_EQ(r.moves_done, job_->moves());
  EXPECT_EQ(r.segments_done, job_->wire.segments.size());
  EXPECT_EQ(r.start_position, (plan::PerAxis<int64_t>{}));
  EXPECT_EQ(r.position, job_->checkpoints.back().position);
  // The card's own pins agree with its reply.
  for (int a = 0; a < 4; ++a) EXPECT_EQ(spi.last().position[size_t(a)], r.position[a]) << a;
  EXPECT_FALSE(spi.last().running);

  // The same card again: the second job starts where the first ended (here at
  // the origin). An E-stop latched on the card is not cleared unasked (nothing is
  // sent); acknowledged (ack_estop: an URGENT ACK frame), the job runs.
  spi.set_estop(true);
  spi.idle(8);
  spi.set_estop(false);
  spi.idle(8);
  const run::CardRun refused = run::run_on_link(*job_, link, {});
  ASSERT_EQ(refused.faults.size(), 1u);
  EXPECT_NE(refused.faults[0].message.find("the card latched an E-stop"), std::string::npos)
      << refused.faults[0].message;
  EXPECT_EQ(refused.link.stats.command_frames, 0u);
  run::LinkRunOptions ack;
  ack.ack_estop = true;
  const run::CardRun again = run::run_on_link(*job_, link, ack);
  EXPECT_TRUE(again.ok()) << (again.faults.empty() ? "" : again.faults.front().message);
  EXPECT_EQ(again.moves_done, job_->moves());
  EXPECT_EQ(again.position, job_->checkpoints.back().position);
}

// The feed on the spidev path (docs/HOST.md "Feed hold and override"): the override
// before the job's words and a HOLD and a RESUME timed from the first reply that shows
// the card running reach the (Verilated default, HX8K) card as URGENT frames; the job
// ends exactly, its moves all made, at 50 % in about twice its planned time.
TEST_F(CardLink, TheSpidevPathSendsTheFeed) {
  ASSERT_TRUE(job_->caps.feed) << "the default card has feed hold";
  DefaultCard card(job_->clock_hz());
  run::LinkRunOptions o;
  o.override_pct = 50;
  const double planned = job_->planned.stats.duration_s;
  o.feed = run::parse_feed_events(fmt::format("{}:hold,{}:resume", 0.2 * planned, 0.4 * planned));
  const run::CardRun r = run::run_on_link(*job_, card.link, o);
  EXPECT_TRUE(r.ok()) << (r.faults.empty() ? "" : r.faults.front().message);
  ASSERT_EQ(r.feed.size(), 3u);
  EXPECT_EQ(r.feed[0].what, "override 50 %");
  EXPECT_EQ(r.feed[1].what, "hold");
  EXPECT_EQ(r.feed[2].what, "resume");
  EXPECT_GE(r.feed[1].taken_s, 0.2 * planned);
  EXPECT_TRUE(r.feed_scaled);
  EXPECT_EQ(r.moves_done, job_->moves());
  EXPECT_EQ(r.position, job_->checkpoints.back().position);
  EXPECT_GT(r.link.seconds, 2 * planned) << "at 50 %, and held a while";
  for (int a = 0; a < 4; ++a) EXPECT_EQ(card.spi.last().position[size_t(a)], r.position[a]) << a;
}

TEST_F(CardLink, TheSpidevPathPlansFromWhereTheCardIs) {
  // A job that ends away from the origin, then one that goes back: planned from
  // the position the card reports, as `cpstep run --transport spidev` does.
  const fs::path dir = fs::path(CPSTEP_TEST_DIR) / "card_link";
  const std::string pid = std::to_string(::getpid());
  const fs::path out = dir / ("out." + pid + ".ngc"), back = dir / ("back." + pid + ".ngc");
  std::ofstream(out) << "G21 G90\nG1 X0.5 Y0.25 F3000\nM2\n";
  std::ofstream(back) << "G21 G90\nG1 X0 Y0 F3000\nM2\n";
  const std::string machine = (dir / ("fast." + pid + ".toml")).string();  // star()'s: 80 steps/mm
  const card::CardCaps caps = card::caps_of(sim::CardDefault::kBuild);
  DefaultCard card(job_->clock_hz());

  auto first = run::prepare_job(out, machine, caps);
  ASSERT_TRUE(first.ok()) << plan::join(first.errors);
  const run::CardRun r1 = run::run_on_link(*first.value, card.link, {});
  ASSERT_TRUE(r1.ok()) << (r1.faults.empty() ? "" : r1.faults.front().message);
  const plan::PerAxis<int64_t> there{40, 20, 0, 0};
  ASSERT_EQ(r1.position, there);

  // Planned as if from the origin: refused before anything is sent.
  auto stale = run::prepare_job(back, machine, caps);
  ASSERT_TRUE(stale.ok()) << plan::join(stale.errors);
  EXPECT_EQ(stale.value->moves(), 0u) << "from the origin to the origin: nothing to move";
  const run::CardRun r2 = run::run_on_link(*stale.value, card.link, {});
  ASSERT_EQ(r2.faults.size(), 1u);
  EXPECT_EQ(r2.faults[0].name, "LINK");
  EXPECT_EQ(r2.faults[0].message.rfind("the card is at x=40 y=20 z=0 a=0"), std::string::npos)
      << "only the machine's axes are named: " << r2.faults[0].message;
  EXPECT_EQ(r2.faults[0].message.rfind("the card is at x=40 y=20, but the job was planned from x=0 y=0", 0), 0u)
      << r2.faults[0].message;
  EXPECT_NE(r2.faults[0].message.find("nothing was sent"), std::string::npos);
  EXPECT_EQ(r2.link.stats.command_frames, 0u);

  // Planned from where the card is: the card comes back to the origin.
  auto from_there = run::prepare_job(back, machine, caps, there);
  ASSERT_TRUE(from_there.ok()) << plan::join(from_there.errors);
  EXPECT_EQ(from_there.value->start, there);
  EXPECT_EQ(from_there.value->moves(), 40u) << "the longer axis's steps";
  const run::CardRun r3 = run::run_on_link(*from_there.value, card.link, {});
  EXPECT_TRUE(r3.ok()) << (r3.faults.empty() ? "" : r3.faults.front().message);
  EXPECT_EQ(r3.start_position, there);
  EXPECT_EQ(r3.position, (plan::PerAxis<int64_t>{}));

  // A simulated card is fresh for each run: a job planned from elsewhere is refused.
  const run::CardRun r4 = run::run_on_sim(*from_there.value, {});
  ASSERT_EQ(r4.faults.size(), 1u);
  EXPECT_NE(r4.faults[0].message.find("a simulated card starts at 0; nothing was sent"), std::string::npos)
      << r4.faults[0].message;
}

TEST_F(CardLink, TheSpidevPathRefusesABusyCard) {
  DefaultCard card(job_->clock_hz());
  // Start the job by hand, then ask run_on_link to run it on the moving card.
  card::CardClient c(card.link);
  c.send(job_->words);
  const run::CardRun r = run::run_on_link(*job_, card.link, {});
  ASSERT_EQ(r.faults.size(), 1u);
  EXPECT_EQ(r.faults[0].name, "LINK");
  EXPECT_EQ(r.faults[0].message, "the card is running; nothing was sent");
  EXPECT_EQ(r.link.stats.command_frames, 0u);
}

// ---------------------------------------------------------------- the small card

// rtl/CMakeLists.txt's small card: 2 axes, a chunk queue of 8, a command buffer
// of 32 words.
using CardSmall = sim::CardOf<builds::small, Vcp_card_small>;
using SmallDut = sim::RtlDut<CardSmall>;
constexpr unsigned kSmallBuffer = 32;

// Segments of 8 moves in three chunks (2000 cycles a move), x back and forth,
// y 3 or 5 steps forward; START after the first two (6 of the 8 chunks the core
// queues before it runs). 10 words a segment: the buffer holds three.
struct SmallJob {
  std::vector<uint32_t> words;
  int32_t x = 0, y = 0;
  uint32_t moves = 0, segments = 0;
};
SmallJob small_job(unsigned n) {
  SmallJob j;
  card::encode_drivers(true, j.words);
  for (unsigned a = 0; a < 2; ++a) {
    card::encode_config(a, card::ConfigField::step_high, 3, j.words);
    card::encode_config(a, card::ConfigField::step_low, 3, j.words);
  }
  for (unsigned s = 0; s < n; ++s) {
    if (s == 2) card::encode_control(true, false, false, j.words);
    card::WireSegment w;
    w.u = 8;
    const bool forward = s % 2 == 0;
    const uint32_t vy = s % 3 ? 5 : 3;
    w.dir_positive = {forward, true};
    w.v = {8, vy};
    w.chunks = {{2000, 3, 0, 0}, {2000, 3, 0, 0}, {2000, 2, 0, 0}};
    w.end = s + 1 == n;
    card::encode_segment(w, j.words);
    j.x += forward ? 8 : -8;
    j.y += int32_t(vy);
    j.moves += 8;
    ++j.segments;
  }
  return j;
}

class SmallCard : public ::testing::Test {
 protected:
  SmallCard() : spi_(dut_), link_(spi_, 48e6), tamper_(link_) { spi_.reset(); }

  card::ClientOptions options() const {
    card::ClientOptions o;
    o.axes = 2;
    o.poll_interval_s = 4000 / 48e6;
    return o;
  }
  // Runs the job to its end; checks the card's final reply and its pins
  // against the job's sums.
  void run_and_check(card::CardClient& c, const SmallJob& j) {
    ASSERT_EQ(c.send(j.words), j.words.size());
    ASSERT_TRUE(c.wait_until_stopped());
    const card::Reply& r = c.poll();
    EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault";
    EXPECT_EQ(r.moves, j.moves);
    EXPECT_EQ(r.segments, j.segments);
    EXPECT_EQ(r.stretch, 0u);
    EXPECT_EQ(r.positions, (std::vector<int32_t>{j.x, j.y}));
    EXPECT_EQ(spi_.last().position[0], j.x);
    EXPECT_EQ(spi_.last().position[1], j.y);
  }

  SmallDut dut_;
  sim::SpiMaster<SmallDut> spi_;
  sim::SimLink<SmallDut> link_;
  TamperLink tamper_;
};

TEST_F(SmallCard, ALargeJobWaitsForRoomInASmallBuffer) {
  const SmallJob j = small_job(24);
  ASSERT_GT(j.words.size(), 5 * kSmallBuffer);
  card::CardClient c(tamper_, options());
  run_and_check(c, j);
  const card::LinkStats& s = c.stats();
  EXPECT_GT(s.waits, 10u);
  EXPECT_EQ(s.no_room, 0u);
  EXPECT_EQ(s.resent, 0u);
  EXPECT_EQ(s.words, j.words.size());
  // No frame the client sent was larger than the free words the card had
  // announced in the reply before it (decoded here from the log).
  const auto& log = tamper_.log();
  for (size_t i = 1; i < log.size(); ++i) {
    if (log[i].commands < 0) continue;
    const size_t nwords = size_t(log[i].mosi[2]) << 8 | log[i].mosi[3];
    const card::Reply before = card::decode_reply(log[i - 1].miso, 2);
    EXPECT_LE(nwords, before.free_words) << "transfer " << i;
    EXPECT_LE(nwords, kSmallBuffer);
  }
}

// The first wait for room sized from the last ones (ClientOptions::
// first_wait_share): the same job on two fresh cards, once polling every
// poll_interval_s from the start of each wait and once with the default; both
// run to the same end without a fault (no underrun), and the second sends
// fewer POLLs.
TEST_F(SmallCard, TheFirstWaitForRoomFollowsTheLastOnesWithFewerPolls) {
  const SmallJob j = small_job(24);
  auto run = [&](double share) {
    SmallDut dut;
    sim::SpiMaster<SmallDut> spi(dut);
    sim::SimLink<SmallDut> link(spi, 48e6);
    spi.reset();
    card::ClientOptions o = options();
    o.first_wait_share = share;
    card::CardClient c(link, o);
    EXPECT_EQ(c.send(j.words), j.words.size());
    EXPECT_TRUE(c.wait_until_stopped());
    const card::Reply& r = c.poll();
    EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault, share " << share;
    EXPECT_EQ(r.moves, j.moves);
    EXPECT_EQ(r.positions, (std::vector<int32_t>{j.x, j.y}));
    return c.stats().polls;
  };
  const uint64_t every = run(0), sized = run(card::ClientOptions{}.first_wait_share);
  std::printf("POLLs: %llu with the first wait sized, %llu every poll_interval_s\n", (unsigned long long)sized,
              (unsigned long long)every);
  EXPECT_LT(sized, every);
}

// Batching (ClientOptions::batch_share with a BufferedTime): frames wait for
// 70 % of the buffer (22 words: two segments and the marker) while the card
// holds enough motion, told here from the job's own segments (8 moves of
// 2000 cycles each); the job runs to its end, without underrun, in fewer
// COMMANDS frames and POLLs than one segment a frame. With the card always
// short of motion (urgent_s above what it can hold) frames do not wait for a
// batch: more of them.
TEST_F(SmallCard, FramesWaitForABatchWhileTheCardHoldsMotion) {
  const SmallJob j = small_job(24);
  std::vector<uint64_t> seg_end;  // word index past each segment
  for (size_t i = 0; i < j.words.size(); i += card::command_words(j.words[i], 2))
    if (card::command_words(j.words[i], 2) > 1) seg_end.push_back(i + card::command_words(j.words[i], 2));
  ASSERT_EQ(seg_end.size(), 24u);
  const double seg_s = 8 * 2000 / 48e6;
  auto run = [&](double urgent_s, bool batch) {
    SmallDut dut;
    sim::SpiMaster<SmallDut> spi(dut);
    sim::SimLink<SmallDut> link(spi, 48e6);
    spi.reset();
    card::ClientOptions o = options();
    if (batch) {
      o.buffer_words = kSmallBuffer;
      o.batch_share = 0.7;
      o.urgent_s = urgent_s;
    }
    card::CardClient c(link, o);
    if (batch)
      c.set_buffered_time([&](const card::Reply& r, uint64_t handed) {
        if (!(r.status & 1)) return std::numeric_limits<double>::infinity();
        const auto sent = uint64_t(std::upper_bound(seg_end.begin(), seg_end.end(), handed) - seg_end.begin());
        return sent > r.segments + 1 ? double(sent - r.segments - 1) * seg_s : 0.0;
      });
    EXPECT_EQ(c.send(j.words), j.words.size());
    EXPECT_TRUE(c.wait_until_stopped());
    const card::Reply& r = c.poll();
    EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault, urgent_s " << urgent_s << (batch ? " batched" : "");
    EXPECT_EQ(r.moves, j.moves);
    EXPECT_EQ(r.positions, (std::vector<int32_t>{j.x, j.y}));
    return c.stats();
  };
  const card::LinkStats plain = run(0, false), batched = run(0.5 * seg_s, true), urgent = run(1.0, true);
  std::printf("COMMANDS frames / POLLs: %llu / %llu one segment a frame, %llu / %llu batched\n",
              (unsigned long long)plain.command_frames, (unsigned long long)plain.polls,
              (unsigned long long)batched.command_frames, (unsigned long long)batched.polls);
  EXPECT_LT(batched.command_frames, plain.command_frames);
  EXPECT_LE(batched.command_frames, 24u / 2 + 2);
  EXPECT_GT(urgent.command_frames, batched.command_frames);
}

TEST_F(SmallCard, NoRoomAfterAnotherMasterFilledTheBufferIsWaitedOutAndResent) {
  const SmallJob j = small_job(16);
  // Before the client's 6th COMMANDS frame, another master fills the buffer
  // with no-op CONTROL words (taking the client's last seq, so the replies still
  // name what the client expects); the core, blocked on a full chunk queue,
  // takes none of them in between.
  int refused_at = -1;
  card::Reply intruder_reply;
  tamper_.intrude = [&](TamperLink::Transfer& t) {
    if (t.commands != 5) return;
    const auto& log = tamper_.log();
    const card::Reply last = card::decode_reply(log.back().miso, 2);
    ASSERT_TRUE(last.ok());
    const std::vector<uint32_t> noops(last.free_words, 0x30000000u);
    intruder_reply = card::decode_reply(
        tamper_.send_own(card::encode_frame(card::FrameType::commands, log.back().mosi[1], noops,
                                            card::reply_bytes(2))),
        2);
    refused_at = int(log.size());
  };
  card::CardClient c(tamper_, options());
  run_and_check(c, j);
  ASSERT_GE(refused_at, 0);
  EXPECT_GT(intruder_reply.free_words, 0u);
  // The card refused the client's frame for room (reported in the next reply).
  const card::Reply told = reply_of(tamper_.log(), size_t(refused_at) + 1, 2);
  EXPECT_EQ(told.last_result, uint8_t(card::FrameResult::no_room));
  const card::LinkStats& s = c.stats();
  EXPECT_EQ(s.no_room, 1u);
  EXPECT_EQ(s.resent, 1u);
  EXPECT_EQ(s.damaged, 0u);
}

TEST_F(SmallCard, ADamagedReplyWithRoomInItIsNotActedOn) {
  const SmallJob j = small_job(12);
  // While the client waits for room, one POLL reply claims 32768 more free words
  // (bit 31 of word 1); the CRC no longer matches. Acted on, it would send a
  // frame larger than the buffer's room, which the card refuses (NO_ROOM).
  int hits = 0;
  tamper_.after = [&](TamperLink::Transfer& t) {
    if (hits || t.commands >= 0 || tamper_.log().size() < 12) return;
    const card::Reply r = card::decode_reply(t.miso, 2);
    if (r.free_words >= 10) return;  // waiting for room: less than a segment free
    t.miso[4] ^= 0x80;
    ++hits;
  };
  card::CardClient c(tamper_, options());
  run_and_check(c, j);
  EXPECT_EQ(hits, 1);
  const card::LinkStats& s = c.stats();
  EXPECT_EQ(s.bad_replies, 1u);
  EXPECT_EQ(s.no_room, 0u);
  EXPECT_EQ(s.resent, 0u);
}

TEST_F(SmallCard, PipelinedFramesAndARefusalTheClientCannotRepair) {
  // Without confirmation each result comes in the next frame's reply. A frame
  // that breaks a command across its end is not the client's to send, so send a
  // bad opcode instead: the card refuses the frame (BAD_COMMAND) and the client
  // names the code.
  card::ClientOptions o = options();
  o.confirm_each_frame = false;
  card::CardClient c(tamper_, o);
  const SmallJob j = small_job(6);
  ASSERT_EQ(c.send(j.words), j.words.size());
  ASSERT_TRUE(c.wait_until_stopped());
  EXPECT_EQ(c.last().moves, j.moves);
  EXPECT_EQ(c.last().positions, (std::vector<int32_t>{j.x, j.y}));
  EXPECT_EQ(c.stats().markers, 0u);
  const std::vector<uint32_t> bad = {0x60000000u};  // no such opcode (0x5 is CONIC)
  c.send(bad);
  try {
    c.settle();
    ADD_FAILURE() << "the refusal was not reported";
  } catch (const card::CardError& e) {
    EXPECT_NE(std::string(e.what()).find("BAD_COMMAND (5)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cpstep::tb

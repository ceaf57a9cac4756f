// SPDX-License-Identifier: MIT
// Limit switches (issue 12, docs/CORE.md "Inputs"): synchronized, filtered (three
// samples P clocks apart that agree), active at their configured level when
// enabled. A segment under way that moves an axis toward an active limit stops at
// once: no move fires from the cycle the filtered input is active, LIMIT (20)
// latches with the limits that were active (READ 0x28), the queues are flushed;
// moving away is allowed. The small card behind its pins, RTL and fast engine in
// lockstep every cycle (small_card_job.h): the switch closes at random cycles
// mid-job, the last STEP edge is timed from the pin, positions equal the pins, no
// runt pulse; a job away from the switch runs exactly while it stays closed, one
// toward it is stopped before its first step; a glitch shorter than the filter is
// not seen.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "card/card_client.h"
#include "card/frame.h"
#include "card/protocol.h"
#include "small_card_job.h"

namespace cpstep::tb {
namespace {

using namespace small_card;

constexpr uint32_t kFilter = 4;  // CONFIG field 6: a sample every 4 clocks
// From the pin to the last move that can fire: 2 clocks of synchronizer, at most
// three sample periods for three agreeing samples (the first sample up to P - 1
// clocks after the pin reaches the filter), 1 for the level's register; the STEP
// edge of a move fired in the cycle before shows one clock later.
constexpr uint64_t kLatest = 2 + 3 * kFilter + 1 + 1;


void expect_limit_fault(const card::Reply& r) {
  expect_stopped_by(r, 20, "LIMIT");
  EXPECT_EQ(r.status >> 16, 0u) << "no segment and no chunk queued";
}

TEST(Limits, ASwitchClosedMidJobStopsAtOnceAndOnlyMovingAwayRuns) {
  std::mt19937_64 rng(20);
  for (int trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE(trial);
    const Job j = make_job(20, 1500 + 200 * uint32_t(trial));  // 12,000 clocks a segment or more
    Card card;
    card::CardClient c(card.link, card.options());
    const std::vector<uint32_t> setup = limits_setup(j, kFilter);
    ASSERT_EQ(c.send(setup), setup.size());
    ASSERT_TRUE(c.urgent(card::urgent::start));
    const uint64_t close_at = std::uniform_int_distribution<uint64_t>(15000, 60000)(rng);
    size_t w = 0;
    while (card.twin.cycle() < close_at) {
      w = send_what_fits(c, j, w);
      card.spi.idle(std::uniform_int_distribution<uint64_t>(100, 3000)(rng));
      ASSERT_FALSE(card::decode_status(c.poll().status).fault) << card::decode_status(c.last().status).err_code;
    }
    ASSERT_LT(c.last().moves + 16, j.moves) << "the switch should close well before the job's end";
    // x moves up: its max switch closes, and stays closed.
    const uint64_t closed = card.twin.cycle();
    card.spi.set_inputs(0, 0b01, false);
    card.spi.idle(3000);
    const card::Reply r = c.poll();
    expect_limit_fault(r);
    EXPECT_LE(card.last_step, closed + kLatest) << "a move fired after the switch was seen";
    EXPECT_GT(card.last_step + 2000, closed) << "the job was moving when the switch closed";
    EXPECT_EQ(r.positions, card.steps());
    EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
    EXPECT_EQ(c.read_register(card::Register::limits_at), 0x100u) << "x's max stopped it";
    EXPECT_EQ(c.read_register(card::Register::inputs), 0x100u) << "and is still active";
    card.spi.idle(20000);
    EXPECT_EQ(c.poll().free_words, 32u) << "the buffered words were read and dropped";

    // CLEAR; x down, away from the closed switch: runs whole.
    std::vector<uint32_t> clear;
    card::encode_control(false, false, true, clear);
    ASSERT_EQ(c.send(clear), clear.size());
    ASSERT_TRUE(c.settle());
    const card::Reply cleared = c.poll();
    EXPECT_FALSE(card::decode_status(cleared.status).fault);
    EXPECT_EQ(c.read_register(card::Register::limits_at), 0u) << "CLEAR drops the latched limits";
    const Job away = make_job(3, 500, false);
    expect_next_job_runs_exactly(c, card, away, cleared);

    // x up again, toward it: stopped before its first step.
    const card::Reply before = c.poll();
    const Job toward = make_job(2, 500, true);
    ASSERT_EQ(c.send(toward.segments), toward.segments.size());
    ASSERT_TRUE(c.urgent(card::urgent::start));
    card.spi.idle(5000);
    const card::Reply stopped = c.poll();
    expect_limit_fault(stopped);
    EXPECT_EQ(stopped.moves, before.moves) << "no move toward the closed switch";
    EXPECT_EQ(stopped.positions, before.positions);
  }
}

// A closed switch on an axis the segment does not move, and a glitch shorter than
// two sample periods on the axis it moves toward: the job runs whole.
TEST(Limits, GlitchesAndSwitchesOffThePathDoNotStopIt) {
  const Job j = make_job(6, 400);
  Card card;
  card::CardClient c(card.link, card.options());
  const std::vector<uint32_t> setup = limits_setup(j, kFilter);
  ASSERT_EQ(c.send(setup), setup.size());
  ASSERT_EQ(c.send(j.segments), j.segments.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  card.spi.idle(2000);
  // x moves up only: its min switch (behind it) closed is no hit.
  card.spi.set_inputs(0b01, 0, false);
  card.spi.idle(3000);
  // x's max for 2P - 1 clocks: fewer than three samples.
  card.spi.set_inputs(0b01, 0b01, false);
  card.spi.idle(2 * kFilter - 1);
  card.spi.set_inputs(0b01, 0, false);
  ASSERT_TRUE(c.wait_until_stopped());
  expect_job_done(c, card, j);
  EXPECT_EQ(c.read_register(card::Register::inputs), 0x01u) << "x's min is active";
}

}  // namespace
}  // namespace cpstep::tb

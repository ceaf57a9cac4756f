// SPDX-License-Identifier: MIT
// The seek (issue 12, docs/CORE.md "Seek: homing and probing"): a run that ends when
// an input trips, the position at the trip held exactly (the pulse count). The
// small card behind its pins, RTL and fast engine in lockstep every cycle
// (small_card_job.h): the probe (mode 1) or a limit switch (mode 3) closes at a
// random cycle mid-job; no move fires after the trip is seen (the last STEP edge is
// timed from the pin), the counters equal the pins, no runt pulse, READ 0x27 says
// tripped and disarmed, no fault, and what was queued stays until the host's FLUSH;
// the next run goes on exactly from the trip. Armed with the probe already in
// contact, START does not start the run; mode 2 trips on the contact's loss.
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
// From the pin to the last move that can fire (test_limits.cpp): 2 clocks of
// synchronizer, at most three sample periods, 1 for the level, 1 for the STEP edge.
constexpr uint64_t kLatest = 2 + 3 * kFilter + 1 + 1;

// Drivers, pulse timing, the filter, both axes' limits enabled active high, the
// probe active high, and the seek armed in `mode`.
std::vector<uint32_t> seek_setup(const Job& j, uint32_t mode) {
  std::vector<uint32_t> w = limits_setup(j, kFilter);
  card::encode_config(0, card::ConfigField::probe, 1, w);
  card::encode_config(0, card::ConfigField::seek, mode, w);
  return w;
}

uint32_t seek_state(card::CardClient& c) {
  return c.read_register(card::Register::inputs) >> card::inputs_bits::seek_mode_shift & 7;
}

// Runs `j` with the seek armed in `mode` and closes the input at a random cycle
// mid-job (the probe, or x's max switch); checks the stop and returns the reply.
card::Reply trip_mid_job(Card& card, card::CardClient& c, const Job& j, uint32_t mode, std::mt19937_64& rng) {
  const std::vector<uint32_t> setup = seek_setup(j, mode);
  EXPECT_EQ(c.send(setup), setup.size());
  EXPECT_EQ(seek_state(c), mode) << "armed";
  EXPECT_TRUE(c.urgent(card::urgent::start));
  const uint64_t close_at = card.twin.cycle() + std::uniform_int_distribution<uint64_t>(15000, 60000)(rng);
  size_t w = 0;
  while (card.twin.cycle() < close_at) {
    w = send_what_fits(c, j, w);
    card.spi.idle(std::uniform_int_distribution<uint64_t>(100, 3000)(rng));
  }
  EXPECT_LT(c.poll().moves + 16, j.moves) << "the input should close well before the job's end";
  const uint64_t closed = card.twin.cycle();
  if (mode == card::seek_mode::limit) card.spi.set_inputs(0, 0b01, false);
  else card.spi.set_inputs(0, 0, true);
  card.spi.idle(3000);
  const card::Reply r = c.poll();
  const card::Status st = card::decode_status(r.status);
  EXPECT_FALSE(st.fault) << "a seek's trip is no fault (code " << st.err_code << ")";
  EXPECT_FALSE(st.running);
  EXPECT_LE(card.last_step, closed + kLatest) << "a move fired after the trip was seen";
  EXPECT_GT(card.last_step + 2000, closed) << "the job was moving when the input closed";
  EXPECT_EQ(r.positions, card.steps())
      << "the counters hold the position at the trip: the pulses on the pins";
  EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
  EXPECT_GT(r.status >> 16, 0u) << "what was queued stays until FLUSH";
  // FLUSH drops the rest (a READ would wait behind the buffered words).
  EXPECT_TRUE(c.urgent(card::urgent::flush));
  EXPECT_EQ(seek_state(c), 4u) << "tripped, disarmed";
  return r;
}

TEST(Seek, TheProbeOrALimitEndsTheRunAtTheTripAndTheNextRunGoesOnFromIt) {
  std::mt19937_64 rng(38);
  for (int trial = 0; trial < 4; ++trial) {
    SCOPED_TRACE(trial);
    const uint32_t mode = trial % 2 ? card::seek_mode::limit : card::seek_mode::probe_contact;
    const Job j = make_job(20, 1500 + 200 * uint32_t(trial));
    Card card;
    card::CardClient c(card.link, card.options());
    const card::Reply tripped = trip_mid_job(card, c, j, mode, rng);
    // FLUSHed: the input released (or x moving away from its closed max), the next
    // job runs exactly from the trip.
    card.spi.idle(20000);
    const card::Reply flushed = c.poll();
    EXPECT_EQ(flushed.status >> 16, 0u) << "FLUSH emptied the queues";
    EXPECT_EQ(flushed.positions, tripped.positions);
    if (mode != card::seek_mode::limit) card.spi.set_inputs(0, 0, false);
    card.spi.idle(100);
    std::vector<uint32_t> off;
    card::encode_config(0, card::ConfigField::seek, card::seek_mode::off, off);
    ASSERT_EQ(c.send(off), off.size());
    EXPECT_EQ(seek_state(c), 0u) << "CONFIG field 10 clears tripped";
    const card::Reply now = c.poll();  // a copy: poll() returns the client's latest
    expect_next_job_runs_exactly(c, card, make_job(3, 500, false), now);
  }
}

// Armed for contact with the probe already in contact: START does not start the
// run (the host reports the probe tripped before the move); mode 2 (contact lost)
// then runs until the probe opens.
TEST(Seek, AProbeAlreadyInContactHoldsTheRunOffAndModeTwoTripsOnItsLoss) {
  const Job j = make_job(12, 1200);
  Card card;
  card::CardClient c(card.link, card.options());
  card.spi.set_inputs(0, 0, true);
  const std::vector<uint32_t> setup = seek_setup(j, card::seek_mode::probe_contact);
  ASSERT_EQ(c.send(setup), setup.size());
  ASSERT_GT(send_what_fits(c, j, 0), 0u);
  ASSERT_TRUE(c.urgent(card::urgent::start));
  card.spi.idle(20000);
  card::Reply r = c.poll();
  EXPECT_FALSE(card::decode_status(r.status).running);
  EXPECT_EQ(r.moves, 0u) << "no move with the probe in contact";
  ASSERT_TRUE(c.urgent(card::urgent::flush));
  EXPECT_EQ(seek_state(c), 1u) << "still armed, not tripped";

  std::vector<uint32_t> loss;
  card::encode_config(0, card::ConfigField::seek, card::seek_mode::probe_loss, loss);
  ASSERT_EQ(c.send(loss), loss.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  feed_for(c, card, j, 0, 30000);
  EXPECT_TRUE(card::decode_status(c.poll().status).running) << "in contact: mode 2 runs";
  const uint64_t opened = card.twin.cycle();
  card.spi.set_inputs(0, 0, false);
  card.spi.idle(3000);
  r = c.poll();
  EXPECT_FALSE(card::decode_status(r.status).running);
  EXPECT_FALSE(card::decode_status(r.status).fault);
  EXPECT_GT(r.moves, 0u);
  EXPECT_LT(r.moves, j.moves);
  EXPECT_LE(card.last_step, opened + kLatest);
  EXPECT_EQ(r.positions, card.steps());
  ASSERT_TRUE(c.urgent(card::urgent::flush));
  EXPECT_EQ(seek_state(c), 4u);
}

// Unarmed, a limit hit is still the LIMIT fault; armed for the probe, too (only
// mode 3 turns a limit hit into a trip).
TEST(Seek, OnlyModeThreeTurnsALimitHitIntoATrip) {
  const Job j = make_job(12, 1200);
  Card card;
  card::CardClient c(card.link, card.options());
  const std::vector<uint32_t> setup = seek_setup(j, card::seek_mode::probe_contact);
  ASSERT_EQ(c.send(setup), setup.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  feed_for(c, card, j, 0, 20000);
  card.spi.set_inputs(0, 0b01, false);
  card.spi.idle(3000);
  expect_stopped_by(c.poll(), 20, "LIMIT");
  EXPECT_EQ(seek_state(c), 1u) << "the probe seek is still armed, not tripped (the fault flushed the queues)";
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The card's watchdog (issue 12, docs/CORE.md "Watchdog"): CONFIG field 5 sets a
// timeout in units of 4096 clocks; no whole frame with a good CRC for that long
// stops motion at a move boundary, drops ENABLE and latches WATCHDOG (19). The
// small card behind its pins, RTL and fast engine in lockstep every cycle
// (small_card_job.h), driven by the host's client: kept alive through a job by the
// client's keep-alive, run out at random cycles mid-job (positions exact, no runt
// pulse, the ENABLE pin's fall timed from the last frame's CS rise), damaged
// frames that do not keep it alive, and a new job from where the card stands.
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

constexpr uint32_t kUnits = 2;                                   // the timeout in the field's units
constexpr uint64_t kTimeout = uint64_t(kUnits) * card::kWatchdogUnit;  // 8192 clocks
// From a frame's CS rise at the pin to its kick, 2 clocks: the front end's CS
// synchronizer (docs/PROTOCOL.md); the trip comes kTimeout clocks after the kick;
// from the trip to the ENABLE pin, 1: the drivers' enable register (the small card
// has no IO register on the pin).
constexpr uint64_t kLatency = 2 + 1;

std::vector<uint32_t> with_watchdog(std::vector<uint32_t> setup, uint32_t units = kUnits) {
  card::encode_config(0, card::ConfigField::watchdog, units, setup);
  return setup;
}

// The fault the card reports, and that it stopped and dropped its drivers.
void expect_watchdog_fault(const card::Reply& r) {
  expect_stopped_by(r, 19, "WATCHDOG");
  EXPECT_FALSE(card::decode_status(r.status).drivers_enabled);
}

// The ENABLE pin fell the timeout after the last whole frame's CS rise, and the
// latency.
void expect_trip_after(const Card& card, uint64_t last_frame) {
  ASSERT_GT(card.enable_fell, last_frame);
  EXPECT_EQ(card.enable_fell - last_frame, kTimeout + kLatency);
}

// The client's keep-alive (ClientOptions::keepalive_s, a quarter of the timeout)
// carries the card through a whole job whose waits are longer than the timeout;
// when the host then goes quiet, the watchdog runs out.
TEST(Watchdog, KeptAliveThroughAJobThenRunsOutWhenTheHostGoesQuiet) {
  const Job j = make_job(16, 1500);  // 12,000 clocks a segment: longer than the timeout
  Card card;
  card::ClientOptions o = card.options();
  o.poll_interval_s = 20000 / 48e6;             // waits longer than the timeout ...
  o.keepalive_s = double(kTimeout) / 4 / 48e6;  // ... but for the keep-alive
  card::CardClient c(card.link, o);
  const std::vector<uint32_t> setup = with_watchdog(j.setup);
  ASSERT_EQ(c.send(setup), setup.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  ASSERT_EQ(c.send(j.segments), j.segments.size());
  ASSERT_TRUE(c.wait_until_stopped());
  expect_job_done(c, card, j);
  EXPECT_EQ(card.enable_fell, 0u) << "ENABLE stayed on through the job";
  EXPECT_TRUE(card::decode_status(c.last().status).drivers_enabled);

  const uint64_t last_frame = card.cs_rose;
  card.spi.idle(3 * kTimeout);
  const card::Reply r = c.poll();
  expect_watchdog_fault(r);
  expect_trip_after(card, last_frame);
  EXPECT_EQ(r.positions, (std::vector<int32_t>{j.x, j.y})) << "nothing moved";
}

// The host goes quiet at random cycles mid-job: the run stops at a move boundary
// (the pins' steps are the counters, no STEP pulse cut short), ENABLE falls at the
// timeout, WATCHDOG latches and the queues are emptied; the words still buffered are
// dropped. CLEAR and drivers on, and a new job runs from where the card stands.
TEST(Watchdog, RunsOutAtRandomCyclesMidJobAndANewJobRunsExactly) {
  std::mt19937_64 rng(19);
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(trial);
    const Job j = make_job(20, 1500 + 250 * uint32_t(trial)), second = make_job(3, 500);
    Card card;
    card::CardClient c(card.link, card.options());
    const std::vector<uint32_t> setup = with_watchdog(j.setup);
    ASSERT_EQ(c.send(setup), setup.size());
    ASSERT_TRUE(c.urgent(card::urgent::start));
    size_t w = 0;
    const uint64_t quiet_after = std::uniform_int_distribution<uint64_t>(20000, 120000)(rng);
    uint64_t last_frame = 0;
    for (;;) {
      w = send_what_fits(c, j, w);
      // Frames closer than the timeout keep it alive.
      card.spi.idle(std::uniform_int_distribution<uint64_t>(100, 5000)(rng));
      const card::Reply now = c.poll();
      ASSERT_FALSE(card::decode_status(now.status).fault) << "kept alive: " << card::decode_status(now.status).err_code;
      ASSERT_LT(now.moves + 16, j.moves) << "the host should go quiet well before the job's end";
      if (card.twin.cycle() >= quiet_after) {
        last_frame = card.cs_rose;
        break;
      }
    }
    const uint32_t buffered = 32 - c.last().free_words;
    card.spi.idle(std::uniform_int_distribution<uint64_t>(kTimeout + 2000, 4 * kTimeout)(rng));
    const card::Reply r = c.poll();
    expect_watchdog_fault(r);
    expect_trip_after(card, last_frame);
    EXPECT_LE(card.last_step, card.enable_fell) << "no STEP edge after ENABLE fell";
    EXPECT_LT(r.moves, j.moves);
    EXPECT_EQ(r.positions, card.steps())
        << "the pins' steps are the counters";
    EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
    EXPECT_EQ(r.status >> 16, 0u) << "no segment and no chunk queued";
    EXPECT_GT(buffered, 0u) << "words were buffered when the host went quiet";
    card.spi.idle(20000);
    const card::Reply drained = c.poll();
    EXPECT_EQ(drained.free_words, 32u) << "the buffered words were read and dropped";
    EXPECT_EQ(drained.moves, r.moves) << "nothing buffered ran";

    // The operator's recovery: CLEAR, drivers on, a new job.
    std::vector<uint32_t> recover;
    card::encode_control(false, false, true, recover);
    card::encode_drivers(true, recover);
    ASSERT_EQ(c.send(recover), recover.size());
    expect_next_job_runs_exactly(c, card, second, r);
  }
}

// Only a whole frame with a good CRC keeps the watchdog alive: POLLs every 3,000
// clocks hold it for six timeouts; the same POLLs whole but with a CRC byte damaged do not, and it
// runs out one timeout after the last whole one. A timeout of 0 turns it off.
TEST(Watchdog, DamagedFramesDoNotKeepItAliveAndZeroTurnsItOff) {
  Card card;
  card::CardClient c(card.link, card.options());
  std::vector<uint32_t> setup;
  card::encode_drivers(true, setup);
  setup = with_watchdog(setup);
  ASSERT_EQ(c.send(setup), setup.size());
  ASSERT_TRUE(c.settle());
  uint8_t seq = 0x40;
  const auto polls = [&](bool damaged) {
    for (uint64_t t = 0; t < 6 * kTimeout; t += 3000) {
      std::vector<uint8_t> b = card::encode_poll(seq++, 2);
      if (damaged) b[4 + (t / 3000) % 2] ^= 0x10;  // a CRC byte: whole, but its CRC fails
      card.link.transfer(b);
      card.spi.idle(3000);
    }
  };
  // (Raw frames: the client would take their sequence numbers for another master's.)
  const auto read = [&] { return card::decode_reply(card.link.transfer(card::encode_poll(seq++, 2)), 2); };
  polls(false);
  const card::Reply alive = read();
  EXPECT_FALSE(card::decode_status(alive.status).fault);
  EXPECT_TRUE(card::decode_status(alive.status).drivers_enabled);
  EXPECT_EQ(card.enable_fell, 0u);

  const uint64_t last_frame = card.cs_rose;
  polls(true);
  expect_watchdog_fault(read());
  expect_trip_after(card, last_frame);

  // Off: CLEAR, drivers on, timeout 0; silence for many timeouts changes nothing.
  card::CardClient fresh(card.link, card.options());
  std::vector<uint32_t> off;
  card::encode_control(false, false, true, off);
  card::encode_drivers(true, off);
  off = with_watchdog(off, 0);
  ASSERT_EQ(fresh.send(off), off.size());
  ASSERT_TRUE(fresh.settle());
  const uint64_t fell = card.enable_fell;
  card.spi.idle(10 * kTimeout);
  const card::Status st = card::decode_status(fresh.poll().status);
  EXPECT_FALSE(st.fault) << st.err_code;
  EXPECT_TRUE(st.drivers_enabled);
  EXPECT_EQ(card.enable_fell, fell);
}

}  // namespace
}  // namespace cpstep::tb

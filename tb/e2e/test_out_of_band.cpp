// SPDX-License-Identifier: MIT
// Out-of-band control (issue 12, docs/PROTOCOL.md "Out of band"): URGENT frames
// act at their CS rise, past every word the command buffer holds. The small card
// (2 axes, a 32-word buffer, a chunk queue of 8) behind its pins, the Verilated
// RTL and the fast engine in lockstep every cycle (sim::TwinCardDut), driven by
// the host's client: START out of band after the buffer and every queue were
// filled (in band the START would wait behind the words forever: the old
// deadlock), STOP at random cycles with positions exact and no runt pulse, then
// START to go on to the job's end. Expected values are sums over the job's own
// segments, and pulse widths from the pins.
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

// (Replies are copied: CardClient::poll() returns a reference to its latest reply.)

// In band, a START queued behind a full buffer never reaches the core: the core
// takes no word while its queues are full and it is not running. Out of band it
// does, and the job runs to its end.
TEST(OutOfBand, StartPastAFullBufferEndsTheOldDeadlock) {
  const Job j = make_job(12, 300);
  Card card;
  card::CardClient c(card.link, card.options());
  ASSERT_EQ(c.send(j.setup), j.setup.size());
  // Segments until the card's buffer holds words its core cannot take.
  size_t sent = 0;
  uint32_t free_words = 0;
  for (size_t w = 0; w < j.segments.size();) {
    const size_t len = card::command_words(j.segments[w], 2);
    c.settle();
    const card::Reply r = c.poll();
    free_words = r.free_words;
    if (len > r.free_words) break;
    ASSERT_EQ(c.send(std::span(j.segments).subspan(w, len)), len);
    w += len;
    sent = w;
  }
  ASSERT_LT(sent, j.segments.size()) << "the buffer should fill before the job is sent";
  card.spi.idle(20000);
  const card::Reply stuck = c.poll();
  EXPECT_EQ(stuck.free_words, free_words) << "the core took nothing more: it is stuck";
  EXPECT_FALSE(card::decode_status(stuck.status).running);
  // A START in band would not fit (and would wait behind the words if it did).
  ASSERT_TRUE(c.urgent(card::urgent::start));
  ASSERT_EQ(c.send(std::span(j.segments).subspan(sent)), j.segments.size() - sent);
  ASSERT_TRUE(c.wait_until_stopped());
  expect_job_done(c, card, j);
  EXPECT_EQ(c.stats().urgent_frames, 1u);
}

// STOP at random cycles: the run is off at once, the pins' steps equal the
// counters (no move half made), no STEP pulse cut short; START goes on, and the job
// ends where it would have without the stops.
TEST(OutOfBand, StopAtRandomCyclesThenStartGoesOnExactly) {
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(trial);
    const Job j = make_job(20, 1500 + 250 * uint32_t(trial));  // a segment: 12,000 cycles or more
    Card card;
    card::CardClient c(card.link, card.options());
    ASSERT_EQ(c.send(j.setup), j.setup.size());
    ASSERT_TRUE(c.urgent(card::urgent::start));  // running, waiting for its first segment
    size_t w = 0;
    unsigned stops = 0;
    while (w < j.segments.size() || card::decode_status(c.poll().status).running) {
      // Every segment that fits (the card holds some 7 segments, 84,000 cycles or more).
      w = send_what_fits(c, j, w);
      card.spi.idle(std::uniform_int_distribution<uint64_t>(100, 20000)(rng));
      // A STOP while the run is on and well before its end (a START after the end
      // would start a run with nothing to run).
      const card::Reply now = c.poll();
      if (stops < 4 && card::decode_status(now.status).running && now.moves + 16 < j.moves) {
        ASSERT_TRUE(c.urgent(card::urgent::stop));
        ++stops;
        const card::Reply s = c.poll();
        EXPECT_FALSE(card::decode_status(s.status).running) << "STOP: the run is off";
        card.spi.idle(3000);
        const card::Reply still = c.poll();
        EXPECT_EQ(still.moves, s.moves) << "no move while stopped";
        EXPECT_EQ(still.positions, card.steps())
            << "the pins' steps are the counters";
        ASSERT_TRUE(c.urgent(card::urgent::start));
      }
    }
    EXPECT_GE(stops, 1u);
    expect_job_done(c, card, j);
    EXPECT_GE(card.shortest_high, kStepHigh) << "no runt STEP pulse";
  }
}

// FLUSH while the run is on, the buffer and queues full and the parser inside a
// segment: the run stops, the buffer and every queue are empty, no fault; the
// positions are the pins'; nothing sent before it runs, and a new job (one START
// out of band) runs from where the card stands, exactly.
TEST(OutOfBand, FlushEmptiesEverythingAndANewJobRunsExactly) {
  const Job first = make_job(40, 3000), second = make_job(3, 500);
  Card card;
  card::CardClient c(card.link, card.options());
  ASSERT_EQ(c.send(first.setup), first.setup.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  const size_t w = send_what_fits(c, first, 0);
  ASSERT_LT(w, first.segments.size()) << "the buffer should be full";
  card.spi.idle(5000);
  const card::Reply before = c.poll();
  ASSERT_TRUE(card::decode_status(before.status).running);
  ASSERT_LT(before.free_words, 32u) << "words wait in the buffer";
  ASSERT_GE(card::decode_status(before.status).segments_queued, 2u) << "and segments in the queues";
  ASSERT_TRUE(c.urgent(card::urgent::flush));
  card.spi.idle(2000);
  const card::Reply after = c.poll();
  const card::Status st = card::decode_status(after.status);
  EXPECT_FALSE(st.running);
  EXPECT_FALSE(st.fault) << st.err_code;
  EXPECT_EQ(after.free_words, 32u) << "the command buffer is empty";
  EXPECT_EQ(after.status >> 16, 0u) << "no segment and no chunk queued";
  EXPECT_LT(after.moves, first.moves);
  EXPECT_EQ(after.positions, card.steps());
  card.spi.idle(20000);
  EXPECT_EQ(c.poll().moves, after.moves) << "nothing that was buffered runs";

  expect_next_job_runs_exactly(c, card, second, after);
}

// URGENT frames the card refuses do nothing: a word count other than 1 is BAD_TYPE,
// a bad CRC is BAD_CRC; the START they carry never starts the run.
TEST(OutOfBand, RefusedUrgentFramesDoNothing) {
  const Job j = make_job(2, 300);
  Card card;
  card::CardClient c(card.link, card.options());
  ASSERT_EQ(c.send(j.setup), j.setup.size());
  ASSERT_EQ(c.send(j.segments), j.segments.size());
  c.settle();
  const uint32_t start[2] = {card::urgent::start, card::urgent::start};
  const auto frame = [&](std::span<const uint32_t> words, bool damage) {
    std::vector<uint8_t> b = card::encode_frame(card::FrameType::urgent, 0x77, words, card::reply_bytes(2));
    if (damage) b[5] ^= 0x01;
    card.link.transfer(b);
    card.spi.idle(2000);
    return card::decode_reply(card.link.transfer(card::encode_poll(0x78, 2)), 2);
  };
  EXPECT_EQ(frame(std::span(start, 2), false).last_result, uint8_t(card::FrameResult::bad_type));
  EXPECT_EQ(frame(std::span(start, 0), false).last_result, uint8_t(card::FrameResult::bad_type));
  const card::Reply damaged = frame(std::span(start, 1), true);
  EXPECT_EQ(damaged.last_result, uint8_t(card::FrameResult::bad_crc));
  EXPECT_FALSE(card::decode_status(damaged.status).running);
  EXPECT_EQ(damaged.moves, 0u);
  // The same frame whole starts the run.
  const card::Reply whole = frame(std::span(start, 1), false);
  EXPECT_EQ(whole.last_result, uint8_t(card::FrameResult::ok));
  EXPECT_TRUE(card::decode_status(whole.status).running || whole.moves > 0);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The card (rtl/cp_card.v) through its pins only: frames in over the pin-level
// SPI master, replies decoded by the host codec and checked against
// docs/PROTOCOL.md and against the card's own pins.
#include <gtest/gtest.h>

#include <algorithm>
#include <type_traits>
#include <utility>

#include "card_harness.h"

namespace cpstep::tb {
namespace {

template <class P>
class SpiCard : public ::testing::Test {};
using Cards = ::testing::Types<sim::CardDefault, CardSmall>;
TYPED_TEST_SUITE(SpiCard, Cards);

constexpr uint32_t kStatusRunning = 1u << 0;

TYPED_TEST(SpiCard, PollGivesAWellFormedReply) {
  constexpr unsigned N = TypeParam::kAxes;
  CardHarness<TypeParam> h({}, true);
  // Reset pins: STEP inactive (the small card's STEP is active low), drivers off.
  const uint32_t idle_step = std::is_same_v<TypeParam, CardSmall> ? (1u << N) - 1 : 0;
  EXPECT_EQ(h.pins().step, idle_step);
  EXPECT_FALSE(h.pins().enable);

  // Clock 8 bytes more than the reply: they must be zeros.
  auto bytes = card::encode_poll(0x5A, N);
  bytes.resize(bytes.size() + 8, 0);
  const auto miso = h.spi().transfer(bytes);
  const card::Reply r = card::decode_reply(miso, N);
  EXPECT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(miso[0], 0xC5);
  // The CRC, by the test's own reference.
  const size_t len = card::reply_bytes(N);
  const uint16_t crc = crc_reference(std::span(miso).first(len - 2));
  EXPECT_EQ(miso[len - 2], crc >> 8);
  EXPECT_EQ(miso[len - 1], crc & 0xFF);
  for (size_t i = len; i < miso.size(); ++i) EXPECT_EQ(miso[i], 0) << "byte " << i;
  // A card fresh from reset: no frame yet, an empty buffer, nothing done.
  EXPECT_EQ(r.last_seq, 0);
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.flags, card::reply_flag::fresh);
  EXPECT_EQ(r.free_words, TypeParam::kCbufWords);
  EXPECT_EQ(r.reads, 0);
  EXPECT_EQ(r.status, 0u);
  EXPECT_EQ(r.stretch, 0u);
  EXPECT_EQ(r.moves, 0u);
  EXPECT_EQ(r.segments, 0u);
  EXPECT_EQ(r.last_read, 0u);
  EXPECT_EQ(r.positions, std::vector<int32_t>(N, 0));

  const card::Reply r2 = h.poll();
  EXPECT_TRUE(r2.ok()) << r2.error;
  EXPECT_EQ(r2.last_seq, 0x5A);
  EXPECT_EQ(r2.last_result, 0);
  EXPECT_EQ(r2.flags, 0);

  // The adaptor names every output, positions last.
  const auto& fields = TypeParam::fields();
  ASSERT_EQ(fields.size(), 10 + N);
  EXPECT_STREQ(fields[10 + N - 1].name, ("position_o[" + std::to_string(N - 1) + "]").c_str());

  // MISO is driven exactly while CS is low.
  for (const PinCycle& c : h.trace()) ASSERT_EQ(c.out.miso_oe, !c.in.cs_n);
}

TYPED_TEST(SpiCard, SegmentRunsAndPositionsEqualItsDeltas) {
  constexpr unsigned N = TypeParam::kAxes;
  CardHarness<TypeParam> h;
  const VisibleJob job = visible_job(N);
  const card::Reply first = h.commands(job.words);
  EXPECT_TRUE(first.ok()) << first.error;
  const card::Reply next = h.poll();
  EXPECT_EQ(next.last_result, 0);
  EXPECT_EQ(next.last_seq, 1);
  EXPECT_TRUE(next.status & kStatusRunning);
  const card::Reply r = h.poll_until_idle();
  EXPECT_EQ(r.positions, job.deltas);
  EXPECT_EQ(r.moves, job.moves);
  EXPECT_EQ(r.segments, 1u);
  EXPECT_EQ(r.status, 1u << 4) << "only the drivers bit: no fault, nothing queued";
  EXPECT_EQ(r.flags, card::reply_flag::drivers);
  EXPECT_EQ(r.free_words, TypeParam::kCbufWords);
  for (unsigned a = 0; a < N; ++a) EXPECT_EQ(h.pins().position[a], job.deltas[a]) << a;
  EXPECT_TRUE(h.pins().enable);
  EXPECT_FALSE(h.pins().fault);
}

TYPED_TEST(SpiCard, ReadRepliesComeBackInLaterReplies) {
  constexpr unsigned N = TypeParam::kAxes;
  CardHarness<TypeParam> h;
  std::vector<uint32_t> w;
  card::encode_read(card::Register::id, 0, w);
  h.commands(w);
  card::Reply r = h.poll();
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.reads, 1);
  EXPECT_EQ(r.last_read, card::kCardId);
  EXPECT_EQ(r.last_read, 0x43505331u);  // "CPS1"

  // After a run, READ of a position; then of the moves counter.
  const VisibleJob job = visible_job(N);
  h.commands(job.words);
  h.poll_until_idle();
  w.clear();
  card::encode_read(card::Register::position0, N - 1, w);
  h.commands(w);
  r = h.poll();
  EXPECT_EQ(r.reads, 3);  // the job's READ 0x1F, then this one
  EXPECT_EQ(int32_t(r.last_read), job.deltas[N - 1]);
  w.clear();
  card::encode_read(card::Register::moves_done, 0, w);
  h.commands(w);
  r = h.poll();
  EXPECT_EQ(r.reads, 4);
  EXPECT_EQ(r.last_read, job.moves);
}

TYPED_TEST(SpiCard, BackToBackFramesWithMinimalCsHigh) {
  constexpr unsigned N = TypeParam::kAxes;
  // CS high for 2 clock cycles between frames, CS hold 2 (docs/PROTOCOL.md minimums).
  sim::SpiTiming t;
  t.cs_idle = 2;
  t.cs_hold = 2;
  CardHarness<TypeParam> h(t, true);
  uint8_t prev_seq = 0, prev_result = 0;
  uint16_t reads = 0;
  for (int f = 0; f < 24; ++f) {
    const uint8_t seq = uint8_t(0x80 + f);
    std::vector<uint8_t> bytes;
    uint8_t want = 0;
    if (f % 3 == 0) {
      bytes = card::encode_poll(seq, N);
    } else {
      std::vector<uint32_t> w;
      card::encode_read(card::Register::position0, unsigned(f) % N, w);
      bytes = card::encode_frame(card::FrameType::commands, seq, w, card::reply_bytes(N));
      if (f % 7 == 5) {
        bytes[5] ^= 0x04;  // a bad CRC now and then
        want = 2;
      }
    }
    const card::Reply r = h.exchange(bytes);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.last_seq, prev_seq) << "frame " << f;
    EXPECT_EQ(r.last_result, prev_result) << "frame " << f;
    EXPECT_EQ(r.reads, reads) << "frame " << f;
    prev_seq = seq;
    prev_result = want;
    if (f % 3 != 0 && want == 0) ++reads;
  }
  // The CS high gaps were exactly 2 cycles.
  const auto& tr = h.trace();
  int gaps = 0;
  for (size_t i = 1; i < tr.size(); ++i) {
    if (tr[i - 1].in.cs_n || !tr[i].in.cs_n) continue;
    size_t j = i;
    while (j < tr.size() && tr[j].in.cs_n) ++j;
    if (j == tr.size()) break;
    EXPECT_EQ(j - i, 2u);
    ++gaps;
  }
  EXPECT_EQ(gaps, 23);
}

// SCK rising edges every `period` cycles within a frame; MISO (while driven)
// changes only in the 3rd cycle after an SCK rising edge or a CS fall
// (docs/PROTOCOL.md, timing), so it holds for 2 cycles after the edge the host
// samples it at.
template <class P>
void check_pin_timing(const CardHarness<P>& h, unsigned period) {
  const auto& tr = h.trace();
  size_t rises = 0;
  std::vector<size_t> events;  // cycles of SCK rises and CS falls
  size_t last_rise = 0;
  for (size_t i = 1; i < tr.size(); ++i) {
    const bool cs_fall = tr[i - 1].in.cs_n && !tr[i].in.cs_n;
    const bool rise = !tr[i].in.cs_n && tr[i].in.sck && !tr[i - 1].in.sck;
    if (cs_fall) last_rise = 0;
    if (rise) {
      if (last_rise) {
        EXPECT_EQ(i - last_rise, period);
      }
      last_rise = i;
      ++rises;
    }
    if (rise || cs_fall) events.push_back(i);
  }
  EXPECT_GT(rises, 100u);
  size_t changes = 0;
  for (size_t i = 1; i < tr.size(); ++i) {
    if (tr[i].in.cs_n || tr[i - 1].in.cs_n || tr[i].out.miso == tr[i - 1].out.miso) continue;
    ++changes;
    EXPECT_TRUE(i >= 3 && std::binary_search(events.begin(), events.end(), i - 3))
        << "MISO changed in cycle " << i << " of the trace, not 3 cycles after an edge";
  }
  EXPECT_GT(changes, 10u);
}

TYPED_TEST(SpiCard, SckAtExactlyClkDiv8AndUnevenPhases) {
  constexpr unsigned N = TypeParam::kAxes;
  for (auto [low, high] : {std::pair{4u, 4u}, std::pair{3u, 5u}, std::pair{5u, 3u}}) {
    SCOPED_TRACE("SCK low " + std::to_string(low) + ", high " + std::to_string(high));
    sim::SpiTiming t;
    t.sck_low = low;
    t.sck_high = high;
    CardHarness<TypeParam> h(t, true);
    const VisibleJob job = visible_job(N);
    h.commands(job.words);
    const card::Reply r = h.poll();
    EXPECT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.last_result, 0);
    EXPECT_EQ(r.reads, 1);
    check_pin_timing(h, 8);
  }
}

TYPED_TEST(SpiCard, PaddingIsIgnored) {
  constexpr unsigned N = TypeParam::kAxes;
  CardHarness<TypeParam> h;
  // A POLL padded with ones, and a COMMANDS frame whose padding is itself a
  // well-formed frame (drivers on): only the first frame counts.
  auto poll = card::encode_frame(card::FrameType::poll, 1, {});
  poll.resize(card::reply_bytes(N) + 3, 0xFF);
  EXPECT_TRUE(h.exchange(poll).ok());
  std::vector<uint32_t> read, on;
  card::encode_read(card::Register::id, 0, read);
  card::encode_drivers(true, on);
  auto bytes = card::encode_frame(card::FrameType::commands, 2, read);
  const auto tail = card::encode_frame(card::FrameType::commands, 3, on);
  bytes.insert(bytes.end(), tail.begin(), tail.end());
  bytes.resize(card::reply_bytes(N) + 10, 0xA5);
  card::Reply r = h.exchange(bytes);
  EXPECT_EQ(r.last_seq, 1);
  EXPECT_EQ(r.last_result, 0);
  r = h.poll();
  EXPECT_EQ(r.last_seq, 2);
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.reads, 1);
  EXPECT_EQ(r.flags & card::reply_flag::drivers, 0);
  EXPECT_FALSE(h.pins().enable);
}

TYPED_TEST(SpiCard, EstopInputStopsTheCardAndShowsInTheReply) {
  constexpr unsigned N = TypeParam::kAxes;
  CardHarness<TypeParam> h;
  const VisibleJob job = visible_job(N);
  h.commands(job.words);
  // The parser takes the words and checks the two chunks (51 clocks each), then START.
  for (int i = 0; i < 100 && !h.pins().running; ++i) h.spi().idle(10);
  EXPECT_TRUE(h.pins().running) << "fault " << h.pins().fault << ", code " << unsigned(h.pins().err_code);
  EXPECT_TRUE(h.pins().enable);
  h.spi().set_estop(true);
  h.spi().idle(4);  // two synchronizer flops, then the core's next edge
  EXPECT_TRUE(h.pins().fault);
  EXPECT_EQ(h.pins().err_code, 10u);  // ESTOP
  EXPECT_FALSE(h.pins().enable);
  EXPECT_FALSE(h.pins().running);
  const card::Reply r = h.poll();
  EXPECT_TRUE(r.flags & card::reply_flag::estop);
  EXPECT_FALSE(r.flags & card::reply_flag::drivers);
  EXPECT_EQ(r.status & 0x0A, 0x0Au);  // fault, E-stop input
  EXPECT_EQ(r.status >> 8 & 0xFF, 10u);
  h.spi().set_estop(false);
  h.spi().idle(4);
  const card::Reply r2 = h.poll();
  EXPECT_FALSE(r2.flags & card::reply_flag::estop);
  EXPECT_EQ(r2.positions, r.positions);
}

TYPED_TEST(SpiCard, AWholeBufferInOneFrame) {
  CardHarness<TypeParam> h;
  const std::vector<uint32_t> reads(TypeParam::kCbufWords, 0x4000001F);
  h.commands(reads);
  const card::Reply r = h.poll_until_idle();
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.reads, TypeParam::kCbufWords);
  EXPECT_EQ(r.last_read, card::kCardId);
  EXPECT_EQ(r.free_words, TypeParam::kCbufWords);
}

// Positions in a reply are never torn: reply word 7 + a equals the card's
// position_o[a] in the cycle the word was latched — the cycle the card sees the
// SCK rising edge of the previous word's last bit, 2 cycles after the pin rose
// (docs/PROTOCOL.md) — while every axis steps every few cycles.
TEST(SpiCardMoving, RepliesAreNeverTornWhileTheCardMoves) {
  constexpr unsigned N = 4;
  CardHarness<sim::CardDefault> h({}, true);
  std::vector<uint32_t> w;
  card::WireSegment s;
  s.u = 1000;
  s.k = 4;
  s.end = true;
  s.dir_positive = {true, false, true, false};
  s.v = {1000, 999, 500, 1};
  s.chunks = {{3, 16000, 0, 0}};
  card::encode_segment(s, w);
  card::encode_control(true, false, false, w);
  h.commands(w);
  int words_that_moved = 0, polls = 0;
  for (;;) {
    h.clear_trace();
    const uint64_t start = h.cycle();
    const card::Reply r = h.poll();
    ++polls;
    ASSERT_TRUE(r.ok()) << r.error;
    const auto& tr = h.trace();
    ASSERT_EQ(h.trace_start(), start);
    std::vector<size_t> rises;
    for (size_t i = 1; i < tr.size(); ++i)
      if (!tr[i].in.cs_n && tr[i].in.sck && !tr[i - 1].in.sck) rises.push_back(i);
    for (unsigned a = 0; a < N; ++a) {
      const size_t word = 7 + a;
      const size_t latch = rises[32 * word - 1] + 2;
      const size_t last_bit = rises[32 * word + 31];
      EXPECT_EQ(r.positions[a], tr[latch].out.position[a]) << "axis " << a << " poll " << polls;
      if (tr[last_bit].out.position[a] != tr[latch].out.position[a]) ++words_that_moved;
    }
    // The status word (running) as of its own latch.
    EXPECT_EQ(bool(r.status & kStatusRunning), tr[rises[32 * 2 - 1] + 2].out.running);
    if (!(r.status & kStatusRunning) && r.segments == 1) break;
    ASSERT_LT(polls, 200);
  }
  EXPECT_GT(polls, 10);
  EXPECT_GT(words_that_moved, 20) << "the positions did not change while their words went out";
  const card::Reply r = h.poll();
  EXPECT_EQ(r.positions, (std::vector<int32_t>{16000, -15984, 8000, -16}));
  EXPECT_EQ(r.moves, 16000u);
}

// NO_ROOM while the core is blocked: a running segment with long chunks fills the
// small card's chunk queue, the next segment waits in the command buffer, and the
// buffer's free words stay put. A frame one word larger than them is refused and
// never executes (its READs are never counted); a frame of exactly that size is
// taken; a frame of one word into a full buffer is refused. When the run drains
// the buffer, only the accepted READs have run.
TEST(SpiCardBlocked, NoRoomWhileTheCoreIsBlocked) {
  constexpr unsigned N = 2;
  CardHarness<CardSmall> h;
  auto seg = [](bool dir0, uint32_t v1, uint32_t interval, bool end) {
    card::WireSegment s;
    s.u = 8;
    s.end = end;
    s.dir_positive = {dir0, true};
    s.v = {8, v1};
    s.chunks.assign(8, card::WireChunk{interval, 1, 0, 0});
    std::vector<uint32_t> w;
    card::encode_segment(s, w);
    return w;
  };
  auto a = seg(true, 3, 100000, false);
  card::encode_control(true, false, false, a);
  const auto b = seg(false, 5, 10, true);
  ASSERT_EQ(a.size(), 21u);
  ASSERT_EQ(b.size(), 20u);
  h.commands(a);
  h.commands(b);
  const card::Reply blocked = h.poll();
  EXPECT_EQ(blocked.last_result, 0);
  EXPECT_TRUE(blocked.flags & card::reply_flag::busy);
  const uint16_t free = blocked.free_words;
  EXPECT_GT(free, 12);
  EXPECT_LT(free, CardSmall::kCbufWords);
  h.spi().idle(1000);
  EXPECT_EQ(h.poll().free_words, free) << "the core is not blocked";

  const std::vector<uint32_t> too_many(free + 1u, 0x4000001F);
  h.commands(too_many);
  card::Reply r = h.poll();
  EXPECT_EQ(r.last_result, 4);
  EXPECT_EQ(r.free_words, free);
  EXPECT_EQ(r.reads, 0);

  const std::vector<uint32_t> exactly(free, 0x4000001F);
  h.commands(exactly);
  r = h.poll();
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.free_words, 0);
  const std::vector<uint32_t> one = {0x4000001F};
  h.commands(one);
  r = h.poll();
  EXPECT_EQ(r.last_result, 4);

  r = h.poll_until_idle(1'000'000);
  EXPECT_EQ(r.reads, free);
  EXPECT_EQ(r.segments, 2u);
  EXPECT_EQ(r.positions, (std::vector<int32_t>{0, 8}));
  EXPECT_EQ(r.status >> 8 & 0xFF, 0u);
  EXPECT_EQ(r.free_words, CardSmall::kCbufWords);
  (void)N;
}

// docs/PROTOCOL.md's worked example, byte for byte: the MOSI bytes printed there
// (by tb/spi/spi_example) are accepted by the card, which answers the MISO bytes
// printed there.
TEST(SpiCard, WorkedExampleFromProtocolMd) {
  CardHarness<sim::CardDefault> h;
  auto padded = [](std::vector<uint8_t> b) {
    b.resize(46, 0);
    return b;
  };
  const std::vector<uint8_t> poll1 = {0x00, 0x01, 0x00, 0x00, 0xB3, 0xF0};
  const std::vector<uint8_t> cmds = {0x01, 0x02, 0x00, 0x02, 0x30, 0x00, 0x00,
                                     0x08, 0x40, 0x00, 0x00, 0x1F, 0x28, 0xEB};
  const std::vector<uint8_t> poll3 = {0x00, 0x03, 0x00, 0x00, 0xDD, 0x90};
  std::vector<uint8_t> miso1(46, 0), miso2(46, 0), miso3(46, 0);
  const std::vector<uint8_t> head1 = {0xC5, 0x00, 0x00, 0x08, 0x02, 0x00, 0x00, 0x00};
  const std::vector<uint8_t> head2 = {0xC5, 0x01, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00};
  const std::vector<uint8_t> head3 = {0xC5, 0x02, 0x00, 0x04, 0x02, 0x00, 0x00, 0x01,
                                      0x00, 0x00, 0x00, 0x10};
  std::copy(head1.begin(), head1.end(), miso1.begin());
  std::copy(head2.begin(), head2.end(), miso2.begin());
  std::copy(head3.begin(), head3.end(), miso3.begin());
  miso3[24] = 0x43, miso3[25] = 0x50, miso3[26] = 0x53, miso3[27] = 0x31;  // "CPS1"
  miso1[44] = 0x93, miso1[45] = 0xD8;
  miso2[44] = 0x6E, miso2[45] = 0xF7;
  miso3[44] = 0x93, miso3[45] = 0x4A;
  EXPECT_EQ(h.spi().transfer(padded(poll1)), miso1);
  EXPECT_EQ(h.spi().transfer(padded(cmds)), miso2);
  EXPECT_EQ(h.spi().transfer(padded(poll3)), miso3);
  // And the codec makes the same MOSI bytes.
  std::vector<uint32_t> w;
  card::encode_drivers(true, w);
  card::encode_read(card::Register::id, 0, w);
  EXPECT_EQ(card::encode_frame(card::FrameType::commands, 0x02, w), cmds);
  EXPECT_EQ(card::encode_frame(card::FrameType::poll, 0x01, {}), poll1);
}

}  // namespace
}  // namespace cpstep::tb

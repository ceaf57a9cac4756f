// SPDX-License-Identifier: MIT
// Frames the card must refuse (docs/PROTOCOL.md, result codes 1..6), through
// the pins of the Verilated card: each refused frame is reported with its code
// in the next reply and nothing from it executes — the reply's counters, status,
// READ count, free words and positions and the card's pins stay as they were,
// also a while later — and a good frame after it works.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "card_harness.h"

namespace cpstep::tb {
namespace {

template <class P>
class SpiRefuse : public ::testing::Test {
 protected:
  static constexpr unsigned N = P::kAxes;
  static constexpr bool kConic = P::kBuild.conic != 0;

  // The visible job's frame, as the host would send it (seq 0x40).
  static std::vector<uint8_t> good_frame() {
    return card::encode_frame(card::FrameType::commands, 0x40, visible_job(N).words);
  }

  // Sends the first `bits` bits of `bytes` to a fresh card and checks the
  // result against `want` and against the protocol's reference; then that
  // nothing of it ran, and that the visible job runs after it.
  void refused(const std::string& what, const std::vector<uint8_t>& bytes, size_t bits, uint8_t want) {
    SCOPED_TRACE(what);
    CardHarness<P> h;
    h.set_seq(0x0F);
    h.poll();                             // seq 0x10: the reply after it is no longer fresh
    const card::Reply before = h.poll();  // seq 0x11
    ASSERT_TRUE(before.ok()) << before.error;
    const Observed was = observe(before, h.pins());

    auto padded = bytes;
    if (padded.size() < card::reply_bytes(N)) padded.resize(card::reply_bytes(N), 0);
    const auto miso = h.spi().transfer_bits(padded, bits);
    // The free words this frame's own reply announced (when it got that far).
    size_t free = was.free_words;
    if (bits >= 64) free = size_t(miso[4]) << 8 | miso[5];
    EXPECT_EQ(expected_result(padded, bits, free, N, kConic), want) << "the test's own reference disagrees";

    const card::Reply r = h.poll();
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(unsigned(r.last_result), unsigned(want)) << card::frame_result_name(r.last_result).name;
    EXPECT_EQ(r.last_seq, bits >= 16 ? padded[1] : 0x11);
    EXPECT_EQ(observe(r, h.pins()), was);
    h.spi().idle(3000);
    const card::Reply later = h.poll();
    EXPECT_EQ(later.last_result, 0);
    EXPECT_EQ(observe(later, h.pins()), was) << "something ran late";

    // A good frame still works.
    const VisibleJob job = visible_job(N);
    h.commands(job.words);
    const card::Reply done = h.poll_until_idle();
    EXPECT_EQ(done.reads, was.reads + 1);
    EXPECT_EQ(done.last_read, card::kCardId);
    EXPECT_TRUE(done.flags & card::reply_flag::drivers);
    EXPECT_EQ(done.positions, job.deltas);
    EXPECT_EQ(done.moves, job.moves);
    EXPECT_EQ(done.status >> 8 & 0xFF, 0u) << "core error";
  }
  void refused(const std::string& what, const std::vector<uint8_t>& bytes, uint8_t want) {
    refused(what, bytes, 8 * std::max(bytes.size(), card::reply_bytes(N)), want);
  }
};

using Cards = ::testing::Types<sim::CardDefault, CardSmall>;
TYPED_TEST_SUITE(SpiRefuse, Cards);

TYPED_TEST(SpiRefuse, BadCrcOneBitFlippedAnywhere) {
  const auto good = this->good_frame();
  const size_t last = 8 * good.size() - 1;
  // type, seq, the first word, inside a segment word, the last word, both CRC bytes.
  for (size_t bit : {size_t(0), size_t(6), size_t(9), size_t(32), size_t(32 + 4 * 32 + 13),
                     size_t(last - 16), last - 15, last - 8, last}) {
    auto bad = good;
    bad[bit / 8] ^= uint8_t(0x80 >> (bit % 8));
    this->refused("bit " + std::to_string(bit), bad, 2);
  }
  // A flip in nwords moves the CRC: one more word than sent is a truncated frame.
  auto more = good;
  more[3] ^= 0x01;
  const bool even = (good[3] & 1) == 0;
  this->refused("nwords +-1", more,
                even ? 1 : expected_result(more, 8 * std::max(more.size(), card::reply_bytes(TestFixture::N)),
                                           512, TestFixture::N));
}

TYPED_TEST(SpiRefuse, TruncatedAtAnyBit) {
  const auto good = this->good_frame();
  const size_t n = 8 * good.size();
  for (size_t bits : {size_t(0), size_t(1), size_t(7), size_t(8), size_t(15), size_t(16), size_t(17),
                      size_t(31), size_t(32), size_t(33), size_t(63), size_t(64), size_t(100),
                      n - 17, n - 16, n - 13, n - 8, n - 1}) {
    this->refused(std::to_string(bits) + " bits", good, bits, 1);
  }
}

TYPED_TEST(SpiRefuse, UnknownTypeAndPollWithWords) {
  const auto words = visible_job(TestFixture::N).words;
  for (uint8_t type : {0x02, 0x10, 0x80, 0xFF})
    this->refused("type " + std::to_string(type), card::encode_frame(type, 0x41, words), 3);
  this->refused("POLL with words", card::encode_frame(card::FrameType::poll, 0x42, words), 3);
  const std::vector<uint32_t> one = {0x4000001F};
  this->refused("POLL with one word", card::encode_frame(card::FrameType::poll, 0x43, one), 3);
  // Bad type wins over no room; a bad CRC wins over a bad type.
  const std::vector<uint32_t> many(600, 0x4000001F);
  this->refused("type 0x05, 600 words", card::encode_frame(0x05, 0x44, many), 3);
  auto bad = card::encode_frame(0x05, 0x45, words);
  bad[8] ^= 0x10;
  this->refused("type 0x05 and a bad CRC", bad, 2);
}

TYPED_TEST(SpiRefuse, NoRoomForMoreWordsThanFree) {
  // The visible job, then READs up to one word more than the whole buffer.
  auto words = visible_job(TestFixture::N).words;
  words.resize(TypeParam::kCbufWords + 1, 0x4000001F);
  this->refused("buffer + 1 words", card::encode_frame(card::FrameType::commands, 0x46, words), 4);
  // No room wins over a bad command.
  words.back() = 0x60000000;
  this->refused("buffer + 1 words and a bad opcode", card::encode_frame(card::FrameType::commands, 0x47, words), 4);
}

TYPED_TEST(SpiRefuse, UnknownOpcodeWhereACommandStarts) {
  const VisibleJob job = visible_job(TestFixture::N);
  for (uint32_t bad_word : {0x00000000u, 0x60000000u, 0x9000001Fu, 0xF0000001u}) {
    for (size_t at : {size_t(0), size_t(2), job.segment_first, job.segment_first + job.segment_words,
                      job.words.size()}) {
      auto words = job.words;
      words.insert(words.begin() + ptrdiff_t(at), bad_word);
      std::ostringstream what;
      what << "word 0x" << std::hex << bad_word << " at " << std::dec << at;
      this->refused(what.str(), card::encode_frame(card::FrameType::commands, 0x48, words), 5);
    }
  }
  // A bad opcode wins over a split command after it.
  auto words = job.words;
  words.insert(words.begin(), 0x70000000);
  words.resize(job.segment_first + 1 + 3);
  this->refused("bad opcode, then a split segment", card::encode_frame(card::FrameType::commands, 0x49, words), 5);
}

TYPED_TEST(SpiRefuse, SplitCommand) {
  const VisibleJob job = visible_job(TestFixture::N);
  const unsigned n = TestFixture::N;
  // The frame ends after the segment's H0, its H1, its v words, the middle of its
  // first chunk, and one word short of its end.
  for (size_t keep : {size_t(1), size_t(2), size_t(2 + n), size_t(3 + n), job.segment_words - 1}) {
    std::vector<uint32_t> words(job.words.begin(), job.words.begin() + ptrdiff_t(job.segment_first + keep));
    this->refused("segment cut after " + std::to_string(keep) + " words",
                  card::encode_frame(card::FrameType::commands, 0x4A, words), 6);
  }
  // A three-word-chunk segment (add2) missing its last C2.
  card::WireSegment s;
  s.u = 4;
  s.dir_positive.assign(n, true);
  s.v.assign(n, 0);
  s.v[0] = 4;
  s.chunks = {{20, 4, 1, 1}};
  std::vector<uint32_t> words;
  card::encode_segment(s, words);
  ASSERT_EQ(words.size(), 2 + n + 3);
  words.pop_back();
  this->refused("add2 segment without its C2", card::encode_frame(card::FrameType::commands, 0x4B, words), 6);
}

// CONIC (opcode 5, docs/CORE.md): a card whose core takes conics frames one whole,
// 2 + N + 7 + its chunks' words (2 + N + 2 + … for a continuation, H0[18]), and
// refuses one cut anywhere (SPLIT); a card without
// refuses the opcode where a command starts (BAD_COMMAND).
TYPED_TEST(SpiRefuse, ConicCommandsWholeOrRefused) {
  const unsigned n = TestFixture::N;
  card::WireConic c;
  c.t = 4;
  c.axis_u = 0;
  c.axis_v = 1;
  c.dir_positive.assign(n, true);
  c.v.assign(n, 0);
  c.a = c.c = 256;
  c.chunks = {{20, 3, 0, 0}, {30, 1, 2, 0}};
  std::vector<uint32_t> conic;
  card::encode_conic(c, conic);
  ASSERT_EQ(conic.size(), 2 + n + 7 + 2 * 2);
  const VisibleJob job = visible_job(n);
  if (!TestFixture::kConic) {
    auto words = job.words;
    words.insert(words.begin() + 1, conic.begin(), conic.end());
    this->refused("CONIC on a card without conics", card::encode_frame(card::FrameType::commands, 0x4C, words), 5);
    return;
  }
  // Cut after H0, H1, the v words, each K word, the middle of a chunk, one word short.
  std::vector<size_t> cuts = {1, 2, 2 + n};
  for (size_t k = 1; k <= 7; ++k) cuts.push_back(2 + n + k);
  cuts.push_back(2 + n + 7 + 1);
  cuts.push_back(conic.size() - 1);
  for (size_t keep : cuts) {
    std::vector<uint32_t> words = job.words;
    words.insert(words.end(), conic.begin(), conic.begin() + ptrdiff_t(keep));
    this->refused("CONIC cut after " + std::to_string(keep) + " words",
                  card::encode_frame(card::FrameType::commands, 0x4D, words), 6);
  }
  // Whole, it is one command: a bad opcode after it is where a command starts.
  std::vector<uint32_t> words = conic;
  words.push_back(0x60000000);
  this->refused("CONIC, then a bad opcode", card::encode_frame(card::FrameType::commands, 0x4E, words), 5);
  // Whole, with three-word chunks.
  c.chunks = {{20, 3, 0, 1}, {30, 1, 2, 0}};
  conic.clear();
  card::encode_conic(c, conic);
  ASSERT_EQ(conic.size(), 2 + n + 7 + 3 * 2);
  conic.pop_back();
  this->refused("add2 CONIC without its last C2", card::encode_frame(card::FrameType::commands, 0x4F, conic), 6);
  conic.push_back(0);
  CardHarness<TypeParam> h;
  h.poll();
  h.commands(conic);
  const card::Reply r = h.poll();
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(unsigned(r.last_result), 0u) << card::frame_result_name(r.last_result).name;
  // A continuation (H0[18]) is 2 + N + 2 + its chunks' words: cut one word short it is
  // SPLIT; whole, a bad opcode after it is where a command starts; framed as a whole
  // CONIC's length (five words more), its frame would end inside it.
  c.cont = true;
  c.chunks = {{20, 3, 0, 0}, {30, 1, 2, 0}};
  std::vector<uint32_t> cont;
  card::encode_conic(c, cont);
  ASSERT_EQ(cont.size(), 2 + n + 2 + 2 * 2);
  for (size_t keep : {size_t(2 + n + 1), size_t(2 + n + 2), cont.size() - 1}) {
    std::vector<uint32_t> cut(cont.begin(), cont.begin() + ptrdiff_t(keep));
    this->refused("continuation cut after " + std::to_string(keep) + " words",
                  card::encode_frame(card::FrameType::commands, 0x50, cut), 6);
  }
  std::vector<uint32_t> then_bad = cont;
  then_bad.push_back(0x60000000);
  this->refused("continuation, then a bad opcode", card::encode_frame(card::FrameType::commands, 0x51, then_bad), 5);
  // Whole, after its CONIC: the frame is taken (the core's own checks come after).
  std::vector<uint32_t> both = conic;
  both.insert(both.end(), cont.begin(), cont.end());
  h.commands(both);
  const card::Reply r2 = h.poll();
  ASSERT_TRUE(r2.ok()) << r2.error;
  EXPECT_EQ(unsigned(r2.last_result), 0u) << card::frame_result_name(r2.last_result).name;
}

// Random damage to the good frame: flipped bits, cut frames, other types, other
// nwords, words replaced or dropped (with the CRC made right again). The card's
// answer must be the protocol's, and a refused frame must leave no trace.
TYPED_TEST(SpiRefuse, RandomDamageAgreesWithTheProtocol) {
  std::mt19937 rng(20261121 + TestFixture::N);
  const VisibleJob job = visible_job(TestFixture::N);
  const auto good = this->good_frame();
  CardHarness<TypeParam> h;
  std::array<int, 7> seen{};
  for (int iter = 0; iter < 60; ++iter) {
    h.spi().reset();
    h.set_seq(0x20);
    h.poll();
    const card::Reply before = h.poll();
    const Observed was = observe(before, h.pins());
    std::vector<uint8_t> bytes = good;
    size_t bits = 8 * good.size();
    auto with_crc = [&](uint8_t type, const std::vector<uint32_t>& words) {
      bytes = card::encode_frame(type, 0x33, words);
      bits = 8 * bytes.size();
    };
    std::string what;
    switch (rng() % 6) {
      case 0: {  // one to three bits flipped
        const int flips = 1 + int(rng() % 3);
        for (int f = 0; f < flips; ++f) {
          const size_t b = rng() % bits;
          bytes[b / 8] ^= uint8_t(0x80 >> (b % 8));
        }
        what = "flips";
        break;
      }
      case 1:  // cut anywhere
        bits = rng() % bits;
        what = "cut";
        break;
      case 2:  // another type
        with_crc(uint8_t(rng() % 4 == 0 ? 0 : rng()), job.words);
        what = "type";
        break;
      case 3: {  // a word replaced by anything
        auto w = job.words;
        w[rng() % w.size()] = uint32_t(rng());
        with_crc(0x01, w);
        what = "word";
        break;
      }
      case 4: {  // words dropped from the end
        auto w = job.words;
        w.resize(rng() % w.size());
        with_crc(0x01, w);
        what = "drop";
        break;
      }
      default: {  // nwords says something else
        bytes[2] = uint8_t(rng() % 2);
        bytes[3] = uint8_t(rng());
        const uint16_t crc = crc_reference(std::span(bytes).first(bytes.size() - 2));
        bytes[bytes.size() - 2] = uint8_t(crc >> 8);
        bytes[bytes.size() - 1] = uint8_t(crc);
        what = "nwords";
        break;
      }
    }
    SCOPED_TRACE("iteration " + std::to_string(iter) + " (" + what + ", " + std::to_string(bits) + " bits)");
    if (bytes.size() < card::reply_bytes(TestFixture::N)) bytes.resize(card::reply_bytes(TestFixture::N), 0);
    const auto miso = h.spi().transfer_bits(bytes, bits);
    const size_t free = bits >= 64 ? (size_t(miso[4]) << 8 | miso[5]) : TypeParam::kCbufWords;
    const uint8_t want = expected_result(bytes, bits, free, TestFixture::N, TestFixture::kConic);
    ++seen[want];
    const card::Reply r = h.poll();
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(unsigned(r.last_result), unsigned(want));
    if (want != 0) {
      EXPECT_EQ(observe(r, h.pins()), was);
    }
  }
  // The damage reached most of the codes (OK included: a type byte of 0x01 or a
  // word replaced inside a chunk keeps the frame well formed).
  int kinds = 0;
  for (int c : seen) kinds += c > 0;
  EXPECT_GE(kinds, 5);
}

}  // namespace
}  // namespace cpstep::tb

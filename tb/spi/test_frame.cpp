// SPDX-License-Identifier: MIT
// The host's frame codec (host/card/frame.{h,cpp}) against docs/PROTOCOL.md:
// the CRC against a bit-serial reference written here and the standard check
// value, frames byte by byte, the split into whole commands, reply decoding.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

#include "card/frame.h"
#include "card/protocol.h"

namespace cpstep::tb {
namespace {

// CRC-16/CCITT-FALSE one bit at a time, as a shift register would do it: the
// register's top bit XOR the message bit decides whether 0x1021 is folded in.
uint16_t crc_bitwise(const std::vector<uint8_t>& bytes) {
  uint32_t reg = 0xFFFF;
  for (uint8_t byte : bytes) {
    for (int i = 7; i >= 0; --i) {
      const uint32_t top = (reg >> 15) & 1;
      const uint32_t in = (byte >> i) & 1;
      reg = (reg << 1) & 0xFFFF;
      if (top != in) reg ^= 0x1021;
    }
  }
  return uint16_t(reg);
}

std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

TEST(FrameCodec, CrcCheckValue) {
  // The catalogued check value of CRC-16/CCITT-FALSE over the ASCII digits.
  const auto digits = bytes_of("123456789");
  EXPECT_EQ(card::crc16(digits), 0x29B1);
  EXPECT_EQ(crc_bitwise(digits), 0x29B1);
  EXPECT_EQ(card::crc16({}), 0xFFFF);
}

TEST(FrameCodec, CrcMatchesTheBitwiseReference) {
  std::mt19937 rng(1234);
  for (int n = 0; n < 500; ++n) {
    std::vector<uint8_t> b(rng() % 80);
    for (auto& x : b) x = uint8_t(rng());
    ASSERT_EQ(card::crc16(b), crc_bitwise(b)) << "length " << b.size();
    // Continuing a CRC over a split message gives the same CRC.
    const size_t cut = b.empty() ? 0 : rng() % b.size();
    const std::span<const uint8_t> all(b);
    EXPECT_EQ(card::crc16(all.subspan(cut), card::crc16(all.first(cut))), crc_bitwise(b));
  }
}

TEST(FrameCodec, PollIsSixBytesPlusPadding) {
  // type 0x00, seq, nwords 0x0000, CRC over those four bytes, big-endian.
  const std::vector<uint8_t> head = {0x00, 0x2A, 0x00, 0x00};
  const uint16_t crc = crc_bitwise(head);
  const auto f = card::encode_frame(card::FrameType::poll, 0x2A, {});
  EXPECT_EQ(f, (std::vector<uint8_t>{0x00, 0x2A, 0x00, 0x00, uint8_t(crc >> 8), uint8_t(crc)}));
  const auto p = card::encode_poll(0x2A, 4);
  ASSERT_EQ(p.size(), 46u);  // 4 * (7 + 4) + 2
  EXPECT_TRUE(std::equal(f.begin(), f.end(), p.begin()));
  for (size_t i = f.size(); i < p.size(); ++i) EXPECT_EQ(p[i], 0) << i;
  EXPECT_EQ(card::reply_bytes(2), 38u);
  EXPECT_EQ(card::frame_bytes(3), 18u);
}

TEST(FrameCodec, CommandsFrameByteByByte) {
  const std::vector<uint32_t> words = {0x30000009, 0x4000001F, 0xDEADBEEF};
  const auto f = card::encode_frame(card::FrameType::commands, 0xFE, words);
  std::vector<uint8_t> want = {0x01, 0xFE, 0x00, 0x03, 0x30, 0x00, 0x00, 0x09, 0x40, 0x00,
                               0x00, 0x1F, 0xDE, 0xAD, 0xBE, 0xEF};
  const uint16_t crc = crc_bitwise(want);
  want.push_back(uint8_t(crc >> 8));
  want.push_back(uint8_t(crc));
  EXPECT_EQ(f, want);
  // The CRC over the whole frame, its own CRC included, leaves 0 (what the card checks).
  EXPECT_EQ(crc_bitwise(f), 0);
  // Padding comes after the CRC; a longer frame is not cut.
  EXPECT_EQ(card::encode_frame(card::FrameType::commands, 0xFE, words, 20).size(), 20u);
  EXPECT_EQ(card::encode_frame(card::FrameType::commands, 0xFE, words, 5).size(), 18u);
  // nwords is 16 bits.
  const std::vector<uint32_t> too_many(65536, 0x30000000);
  EXPECT_THROW(card::encode_frame(card::FrameType::commands, 0, too_many), std::invalid_argument);
  const std::vector<uint32_t> most(65535, 0x30000000);
  const auto big = card::encode_frame(card::FrameType::commands, 0, most);
  EXPECT_EQ(big[2], 0xFF);
  EXPECT_EQ(big[3], 0xFF);
}

// A segment on a card of `axes` axes with `chunks` chunks (of 3 words with add2).
std::vector<uint32_t> segment(unsigned axes, unsigned chunks, bool add2) {
  card::WireSegment s;
  s.u = chunks;
  s.dir_positive.assign(axes, true);
  s.v.assign(axes, 0);
  s.v[0] = chunks;
  for (unsigned c = 0; c < chunks; ++c) s.chunks.push_back({10, 1, 0, int16_t(add2 ? 1 : 0)});
  std::vector<uint32_t> w;
  card::encode_segment(s, w);
  return w;
}

TEST(FrameCodec, SplitKeepsCommandsWhole) {
  const unsigned axes = 4;
  std::vector<uint32_t> stream;
  std::vector<size_t> starts;  // where each command starts, and its length
  std::vector<size_t> lengths;
  auto add = [&](const std::vector<uint32_t>& cmd) {
    starts.push_back(stream.size());
    lengths.push_back(cmd.size());
    stream.insert(stream.end(), cmd.begin(), cmd.end());
  };
  add({0x30000008});                 // CONTROL, 1 word
  add(segment(axes, 3, false));      // 2 + 4 + 2*3 = 12 words
  add(segment(axes, 2, true));       // 2 + 4 + 3*2 = 12 words
  add({0x4000001F});                 // READ
  add(segment(axes, 10, false));     // 26 words
  add({0x20000002});                 // CONFIG
  ASSERT_EQ(lengths, (std::vector<size_t>{1, 12, 12, 1, 26, 1}));

  const auto frames = card::split_commands(stream, axes, 26);
  // Greedy: {CONTROL, seg, seg, READ} = 26, {seg} = 26, {CONFIG} = 1.
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0], (card::WordRange{0, 26}));
  EXPECT_EQ(frames[1], (card::WordRange{26, 26}));
  EXPECT_EQ(frames[2], (card::WordRange{52, 1}));
  // Every frame starts where a command starts, and they cover the stream.
  size_t next = 0;
  for (const auto& f : card::split_commands(stream, axes, 30)) {
    EXPECT_EQ(f.first, next);
    EXPECT_NE(std::find(starts.begin(), starts.end(), f.first), starts.end());
    EXPECT_LE(f.count, 30u);
    next += f.count;
  }
  EXPECT_EQ(next, stream.size());
  EXPECT_TRUE(card::split_commands({}, axes, 10).empty());

  // A command longer than a frame, and a stream that ends inside a command.
  try {
    card::split_commands(stream, axes, 25);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("word 26"), std::string::npos) << e.what();
  }
  std::vector<uint32_t> cut(stream.begin(), stream.begin() + 20);
  try {
    card::split_commands(cut, axes, 100);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("word 13"), std::string::npos) << e.what();
  }
}

void put32(std::vector<uint8_t>& b, uint32_t w) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(uint8_t(w >> s));
}

TEST(FrameCodec, DecodeReply) {
  // A reply of a 2-axis card, built from the table in docs/PROTOCOL.md.
  std::vector<uint8_t> b;
  put32(b, 0xC5'07'02'05);          // magic, last_seq 7, BAD_CRC, flags busy + drivers
  put32(b, 0x0123'0042);            // 291 free words, 66 reads
  put32(b, 0x0000'0C03);            // status
  put32(b, 5);                      // stretch
  put32(b, 1000);                   // moves
  put32(b, 3);                      // segments
  put32(b, 0x43505331);             // last READ reply
  put32(b, uint32_t(-17));          // axis 0
  put32(b, 0x7FFFFFFF);             // axis 1
  const uint16_t crc = crc_bitwise(b);
  b.push_back(uint8_t(crc >> 8));
  b.push_back(uint8_t(crc));
  b.push_back(0);                   // trailing zeros are ignored
  const card::Reply r = card::decode_reply(b, 2);
  EXPECT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.present);
  EXPECT_TRUE(r.crc_ok);
  EXPECT_EQ(r.last_seq, 7);
  EXPECT_EQ(r.last_result, 2);
  EXPECT_EQ(r.flags, card::reply_flag::busy | card::reply_flag::drivers);
  EXPECT_EQ(r.free_words, 291);
  EXPECT_EQ(r.reads, 66);
  EXPECT_EQ(r.status, 0xC03u);
  EXPECT_EQ(r.stretch, 5u);
  EXPECT_EQ(r.moves, 1000u);
  EXPECT_EQ(r.segments, 3u);
  EXPECT_EQ(r.last_read, card::kCardId);
  EXPECT_EQ(r.positions, (std::vector<int32_t>{-17, 0x7FFFFFFF}));

  // One bit off anywhere: the CRC says so.
  for (size_t bit = 0; bit < 8 * card::reply_bytes(2); bit += 7) {
    auto bad = b;
    bad[bit / 8] ^= uint8_t(0x80 >> (bit % 8));
    const card::Reply x = card::decode_reply(bad, 2);
    EXPECT_FALSE(x.ok()) << bit;
    if (bit >= 8) {
      EXPECT_FALSE(x.crc_ok) << bit;
      EXPECT_NE(x.error.find("CRC"), std::string::npos) << x.error;
    }
  }
  // No card: MISO pulled up reads 0xFF.
  const std::vector<uint8_t> none(card::reply_bytes(2), 0xFF);
  const card::Reply n = card::decode_reply(none, 2);
  EXPECT_FALSE(n.present);
  EXPECT_EQ(n.error, "no card: the reply starts with 0xFF, not the magic byte 0xC5");
  // Too short, or a card of no axes: the caller's mistake.
  EXPECT_THROW(card::decode_reply(std::span(b).first(37), 2), std::invalid_argument);
  EXPECT_THROW(card::decode_reply(b, 0), std::invalid_argument);
  EXPECT_THROW(card::decode_reply(b, 9), std::invalid_argument);
}

TEST(FrameCodec, ResultNames) {
  const char* want[] = {"OK", "TRUNCATED", "BAD_CRC", "BAD_TYPE", "NO_ROOM", "BAD_COMMAND", "SPLIT_COMMAND"};
  for (uint32_t c = 0; c < 7; ++c) EXPECT_STREQ(card::frame_result_name(c).name, want[c]);
  EXPECT_STREQ(card::frame_result_name(7).name, "UNKNOWN");
  EXPECT_EQ(uint32_t(card::FrameResult::split_command), 6u);
}

}  // namespace
}  // namespace cpstep::tb

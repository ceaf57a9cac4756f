// SPDX-License-Identifier: MIT
// Fuzz target: the SPI frame codec and the command-word encoder (host/card/frame.h,
// host/card/protocol.h). The first byte picks what is fuzzed:
//   0  decode_reply on the bytes: a short reply or a bad axis count throws
//      std::invalid_argument, anything else decodes; re-encoding the decoded fields
//      (docs/PROTOCOL.md's reply layout) gives back the same bytes, and `error` is
//      empty exactly when the magic byte and the CRC are right;
//   1  encode_frame of words from the bytes: the frame reads back field by field, its
//      CRC residue is 0, any one flipped bit makes it nonzero, the padding is zeros;
//      crc16 continues over split input;
//   2  split_commands of words from the bytes: whole commands, in order, none empty,
//      each frame within max_words and as full as the next command allows, or
//      std::invalid_argument;
//   3  encode_segment of a segment from the bytes: command_words() of its first word
//      is its length and the words decode back to the segment (docs/CORE.md layout).
// decode_status, error_name and frame_result_name run on a word from the bytes too.
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "card/frame.h"
#include "card/protocol.h"
#include "fuzz_util.h"

using namespace cpstep;

namespace {

void put32(std::vector<uint8_t>& out, uint32_t w) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(w >> s));
}

std::vector<uint32_t> words_of(fuzz::Bytes& in, size_t max) {
  std::vector<uint32_t> w;
  while (!in.empty() && w.size() < max) w.push_back(in.u32());
  return w;
}

void fuzz_reply(fuzz::Bytes& in) {
  const unsigned axes = in.u8() % 10;  // 0 and 9 are refused
  const std::string_view rest = in.rest();
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(rest.data()), rest.size());
  const bool valid = axes >= 1 && axes <= 8 && bytes.size() >= card::reply_bytes(axes);
  card::Reply r;
  try {
    r = card::decode_reply(bytes, axes);
  } catch (const std::invalid_argument&) {
    FUZZ_CHECK(!valid, "a valid reply refused");
    return;
  }
  FUZZ_CHECK(valid, "an invalid reply decoded (axes %u, %zu bytes)", axes, bytes.size());
  FUZZ_CHECK(r.positions.size() == axes, "%zu positions", r.positions.size());
  std::vector<uint8_t> again;
  put32(again, uint32_t(r.present ? card::kReplyMagic : bytes[0]) << 24 | uint32_t(r.last_seq) << 16 |
                   uint32_t(r.last_result) << 8 | r.flags);
  put32(again, uint32_t(r.free_words) << 16 | r.reads);
  for (uint32_t w : {r.status, r.stretch, r.moves, r.segments, r.last_read}) put32(again, w);
  for (int32_t p : r.positions) put32(again, uint32_t(p));
  const uint16_t crc = card::crc16(again);
  if (r.crc_ok) {
    again.push_back(uint8_t(crc >> 8));
    again.push_back(uint8_t(crc));
  } else {
    again.push_back(bytes[again.size()]);
    again.push_back(bytes[again.size()]);
  }
  FUZZ_CHECK(again.size() == card::reply_bytes(axes) && std::memcmp(again.data(), bytes.data(), again.size()) == 0,
             "the decoded reply does not encode back to its bytes");
  FUZZ_CHECK(r.crc_ok == (card::crc16(bytes.first(card::reply_bytes(axes))) == 0), "crc_ok vs the CRC residue");
  FUZZ_CHECK(r.ok() == (r.present && r.crc_ok), "error '%s' (present %d, crc_ok %d)", r.error.c_str(), r.present,
             r.crc_ok);
}

void fuzz_encode(fuzz::Bytes& in) {
  const uint8_t type = in.u8(), seq = in.u8();
  const size_t min_bytes = in.u16() % 2048;
  const size_t flip = in.u16();
  const std::vector<uint32_t> words = words_of(in, 4096);
  const std::vector<uint8_t> f = card::encode_frame(type, seq, words, min_bytes);
  const size_t n = card::frame_bytes(words.size());
  FUZZ_CHECK(f.size() == std::max(n, min_bytes), "%zu bytes for %zu words (min %zu)", f.size(), words.size(),
             min_bytes);
  FUZZ_CHECK(f[0] == type && f[1] == seq && (size_t(f[2]) << 8 | f[3]) == words.size(), "header");
  for (size_t i = 0; i < words.size(); ++i) {
    const uint32_t w = uint32_t(f[4 + 4 * i]) << 24 | uint32_t(f[5 + 4 * i]) << 16 | uint32_t(f[6 + 4 * i]) << 8 |
                       f[7 + 4 * i];
    FUZZ_CHECK(w == words[i], "word %zu", i);
  }
  const std::span<const uint8_t> frame(f.data(), n);
  FUZZ_CHECK(card::crc16(frame) == 0, "CRC residue not 0");
  for (size_t i = n; i < f.size(); ++i) FUZZ_CHECK(f[i] == 0, "padding byte %zu", i);
  const size_t cut = flip % (n + 1);
  FUZZ_CHECK(card::crc16(frame.subspan(cut), card::crc16(frame.first(cut))) == 0, "CRC continued at %zu", cut);
  std::vector<uint8_t> bad(f.begin(), f.begin() + long(n));
  bad[(flip / 8) % n] ^= uint8_t(1u << (flip % 8));
  FUZZ_CHECK(card::crc16(bad) != 0, "a flipped bit passes the CRC");
  if (words.size() == 0) {
    const auto poll = card::encode_poll(seq, 1 + seq % 8);
    FUZZ_CHECK(poll.size() == card::reply_bytes(1 + seq % 8) && poll[0] == 0 && card::crc16(std::span(poll).first(6)) == 0,
               "poll");
  }
}

void fuzz_split(fuzz::Bytes& in) {
  const unsigned axes = 1 + in.u8() % 8;
  const size_t max_words = 1 + in.u16() % 1024;
  std::vector<uint32_t> words = words_of(in, 4096);
  // Mostly short segments, so that whole streams split.
  for (uint32_t& w : words)
    if (w >> 28 == 1) w &= 0xFFFF0000u | 0x3u;
  std::vector<card::WordRange> frames;
  try {
    frames = card::split_commands(words, axes, max_words);
  } catch (const std::invalid_argument&) {
    // A command longer than max_words, or the stream ends inside one: check that it does.
    bool bad = false;
    for (size_t c = 0; c < words.size();) {
      const size_t len = card::command_words(words[c], axes);
      if (len > max_words || c + len > words.size()) {
        bad = true;
        break;
      }
      c += len;
    }
    FUZZ_CHECK(bad, "refused a stream of whole commands");
    return;
  }
  size_t at = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const card::WordRange& r = frames[i];
    FUZZ_CHECK(r.first == at && r.count >= 1 && r.count <= max_words, "frame %zu: %zu+%zu at %zu", i, r.first,
               r.count, at);
    size_t c = r.first;
    while (c < r.first + r.count) c += card::command_words(words[c], axes);
    FUZZ_CHECK(c == r.first + r.count, "frame %zu splits a command", i);
    if (i + 1 < frames.size())
      FUZZ_CHECK(r.count + card::command_words(words[c], axes) > max_words, "frame %zu could take the next command",
                 i);
    at += r.count;
  }
  FUZZ_CHECK(at == words.size(), "frames cover %zu of %zu words", at, words.size());
}

void fuzz_segment(fuzz::Bytes& in) {
  const unsigned axes = 1 + in.u8() % 8;
  card::WireSegment s;
  s.u = in.u32() & 0xFFFFFF;
  s.k = in.u8() & 0xF;
  s.end = in.flag();
  const uint8_t dirs = in.u8();
  for (unsigned a = 0; a < axes; ++a) {
    s.dir_positive.push_back(dirs >> a & 1);
    s.v.push_back(in.u32() & 0xFFFFFF);
  }
  const size_t nchunks = in.u8() % 40;
  for (size_t c = 0; c < nchunks; ++c)
    s.chunks.push_back({in.u32(), in.u16(), int16_t(in.u16()), int16_t(in.flag() ? in.u16() : 0)});
  std::vector<uint32_t> w;
  card::encode_segment(s, w);
  FUZZ_CHECK(card::command_words(w[0], axes) == w.size(), "command_words %zu, encoded %zu",
             card::command_words(w[0], axes), w.size());
  bool add2 = false;
  for (const auto& c : s.chunks) add2 = add2 || c.add2 != 0;
  FUZZ_CHECK(w[0] >> 28 == 1 && (w[0] >> 27 & 1) == s.end && (w[0] >> 23 & 0xF) == s.k &&
                 (w[0] >> 22 & 1) == add2 && (w[0] & 0xFFFF) == nchunks && (w[0] >> 16 & 0x3F) == 0,
             "H0 0x%08x", w[0]);
  FUZZ_CHECK((w[1] & 0xFFFFFF) == s.u && (w[1] >> 24) == (dirs & ((1u << axes) - 1)), "H1 0x%08x", w[1]);
  size_t at = 2;
  for (unsigned a = 0; a < axes; ++a) FUZZ_CHECK(w[at++] == s.v[a], "v%u", a);
  for (const card::WireChunk& c : s.chunks) {
    FUZZ_CHECK(w[at] == c.interval, "interval");
    FUZZ_CHECK((w[at + 1] & 0xFFFF) == c.count && int16_t(w[at + 1] >> 16) == c.add, "C1 0x%08x", w[at + 1]);
    at += 2;
    if (add2) {
      FUZZ_CHECK(w[at] == uint16_t(c.add2), "C2 0x%08x", w[at]);
      ++at;
    }
  }
  const auto frames = card::split_commands(w, axes, w.size());
  FUZZ_CHECK(frames.size() == 1 && frames[0].count == w.size(), "one segment, one frame");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  const uint8_t mode = in.u8();
  {
    fuzz::Bytes probe(data, size);
    const uint32_t w = probe.u32();
    const card::Status st = card::decode_status(w);
    FUZZ_CHECK(st.running == (w & 1) && st.err_code == (w >> 8 & 0xFF) && st.chunks_queued == w >> 24, "status");
    FUZZ_CHECK(card::error_name(w).name != nullptr && card::frame_result_name(w).name != nullptr, "names");
  }
  switch (mode % 4) {
    case 0: fuzz_reply(in); break;
    case 1: fuzz_encode(in); break;
    case 2: fuzz_split(in); break;
    default: fuzz_segment(in); break;
  }
  return 0;
}

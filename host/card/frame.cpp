// SPDX-License-Identifier: MIT
#include "card/frame.h"

#include <algorithm>
#include <array>
#include <iterator>
#include <stdexcept>
#include <string>

#include "card/protocol.h"

namespace cpstep::card {

namespace {

void put32(std::vector<uint8_t>& out, uint32_t w) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(w >> s));
}

uint32_t get32(std::span<const uint8_t> b, size_t at) {
  return uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 | b[at + 3];
}

std::string hex(uint32_t v, int digits) {
  static const char* d = "0123456789ABCDEF";
  std::string s = "0x";
  for (int i = digits - 1; i >= 0; --i) s.push_back(d[v >> (4 * i) & 0xF]);
  return s;
}

// CRC-16/CCITT-FALSE a byte at a time: entry b is the register's change for a
// top byte b, eight steps of the bitwise form (polynomial 0x1021, MSB first).
constexpr std::array<uint16_t, 256> kCrcTable = [] {
  std::array<uint16_t, 256> t{};
  for (unsigned b = 0; b < 256; ++b) {
    uint16_t c = uint16_t(b << 8);
    for (int i = 0; i < 8; ++i) c = uint16_t((c & 0x8000) ? (c << 1) ^ 0x1021 : c << 1);
    t[b] = c;
  }
  return t;
}();

}  // namespace

uint16_t crc16(std::span<const uint8_t> bytes, uint16_t crc) {
  for (uint8_t byte : bytes) crc = uint16_t(crc << 8) ^ kCrcTable[(crc >> 8 ^ byte) & 0xFF];
  return crc;
}

std::vector<uint8_t> encode_frame(uint8_t type, uint8_t seq, std::span<const uint32_t> words,
                                  size_t min_bytes) {
  if (words.size() > 0xFFFF)
    throw std::invalid_argument("a frame holds at most 65535 words, not " + std::to_string(words.size()));
  std::vector<uint8_t> out;
  out.reserve(std::max(frame_bytes(words.size()), min_bytes));
  out.push_back(type);
  out.push_back(seq);
  out.push_back(uint8_t(words.size() >> 8));
  out.push_back(uint8_t(words.size()));
  for (uint32_t w : words) put32(out, w);
  const uint16_t crc = crc16(out);
  out.push_back(uint8_t(crc >> 8));
  out.push_back(uint8_t(crc));
  if (out.size() < min_bytes) out.resize(min_bytes, 0);
  return out;
}

std::vector<uint8_t> encode_poll(uint8_t seq, unsigned axes) {
  return encode_frame(FrameType::poll, seq, {}, reply_bytes(axes));
}

std::vector<WordRange> split_commands(std::span<const uint32_t> words, unsigned axes, size_t max_words,
                                      bool ptimer) {
  std::vector<WordRange> frames;
  WordRange cur;
  for (size_t c = 0; c < words.size();) {
    const size_t len = command_words(words[c], axes, ptimer);
    if (len > max_words)
      throw std::invalid_argument("the command at word " + std::to_string(c) + " (" + hex(words[c], 8) +
                                  ") has " + std::to_string(len) + " words, more than a frame's " +
                                  std::to_string(max_words));
    if (c + len > words.size())
      throw std::invalid_argument("the command at word " + std::to_string(c) + " (" + hex(words[c], 8) +
                                  ") needs " + std::to_string(len) + " words; the stream ends after " +
                                  std::to_string(words.size() - c));
    if (cur.count + len > max_words) {
      frames.push_back(cur);
      cur = {c, 0};
    }
    cur.count += len;
    c += len;
  }
  if (cur.count > 0) frames.push_back(cur);
  return frames;
}

ResultName frame_result_name(uint32_t code) {
  static const ResultName names[] = {
      {"OK", "the frame was accepted; its words execute"},
      {"TRUNCATED", "CS rose before the frame's CRC was complete"},
      {"BAD_CRC", "the frame's CRC does not match"},
      {"BAD_TYPE", "an unknown frame type, or a POLL with words"},
      {"NO_ROOM", "more words than the command buffer had free"},
      {"BAD_COMMAND", "a command with an unknown opcode"},
      {"SPLIT_COMMAND", "the frame's last command does not end with the frame"},
  };
  if (code < std::size(names)) return names[code];
  return {"UNKNOWN", "a frame result this program does not know"};
}

Reply decode_reply(std::span<const uint8_t> bytes, unsigned axes) {
  if (axes < 1 || axes > 8)
    throw std::invalid_argument("a card has 1 to 8 axes, not " + std::to_string(axes));
  const size_t need = reply_bytes(axes);
  if (bytes.size() < need)
    throw std::invalid_argument("a reply of " + std::to_string(axes) + " axes is " + std::to_string(need) +
                                " bytes; only " + std::to_string(bytes.size()) + " were clocked in");
  Reply r;
  const uint32_t w0 = get32(bytes, 0);
  r.present = (w0 >> 24) == kReplyMagic;
  r.last_seq = uint8_t(w0 >> 16);
  r.last_result = uint8_t(w0 >> 8);
  r.flags = uint8_t(w0);
  const uint32_t w1 = get32(bytes, 4);
  r.free_words = uint16_t(w1 >> 16);
  r.reads = uint16_t(w1);
  r.status = get32(bytes, 8);
  r.stretch = get32(bytes, 12);
  r.moves = get32(bytes, 16);
  r.segments = get32(bytes, 20);
  r.last_read = get32(bytes, 24);
  for (unsigned a = 0; a < axes; ++a) r.positions.push_back(int32_t(get32(bytes, 4 * (kReplyFixedWords + a))));
  const size_t crc_at = need - kCrcBytes;
  const uint16_t sent = uint16_t(bytes[crc_at] << 8 | bytes[crc_at + 1]);
  const uint16_t computed = crc16(bytes.first(crc_at));
  r.crc_ok = sent == computed;
  if (!r.present)
    r.error = "no card: the reply starts with " + hex(w0 >> 24, 2) + ", not the magic byte " + hex(kReplyMagic, 2);
  else if (!r.crc_ok)
    r.error = "reply CRC mismatch: the card sent " + hex(sent, 4) + ", its bytes give " + hex(computed, 4);
  return r;
}

}  // namespace cpstep::card

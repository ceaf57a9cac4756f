// SPDX-License-Identifier: MIT
// The card's SPI frames and replies (docs/PROTOCOL.md), as bytes.
//
// A frame is what the host shifts out on MOSI in one CS-low period: type, seq,
// nwords, the command words and a CRC-16/CCITT-FALSE, all big-endian, then
// padding. The card's reply comes back on MISO in the same period.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cpstep::card {

// CRC-16/CCITT-FALSE: polynomial 0x1021, init 0xFFFF, MSB first, no final XOR.
// `crc` continues a CRC over earlier bytes.
uint16_t crc16(std::span<const uint8_t> bytes, uint16_t crc = 0xFFFF);

enum class FrameType : uint8_t { poll = 0x00, commands = 0x01, urgent = 0x02 };
// An URGENT frame's one word (docs/PROTOCOL.md "Out of band"): what it does at its CS
// rise, past the command buffer.
namespace urgent {
constexpr uint32_t start = 1u << 0;  // START, as CONTROL's
constexpr uint32_t stop = 1u << 1;   // STOP: no move from then on; what is loaded and queued stays
constexpr uint32_t flush = 1u << 2;  // FLUSH: the run off, the command buffer and every queue emptied
constexpr uint32_t ack = 1u << 3;    // ACK: clears a latched fault, an E-stop's too (input released)
// Feed (cards with FEED, docs/CORE.md "Feed hold and override"): the timer's scale ramps
// to 0 (HOLD), back to the override (RESUME), or to a new override (OVERRIDE, with it).
constexpr uint32_t hold = 1u << 4;
constexpr uint32_t resume = 1u << 5;
constexpr uint32_t override_set = 1u << 6;
constexpr uint32_t kOverrideOne = 0x4000;  // 100 %, Q2.14; the card takes at most 0x8000 (200 %)
// OVERRIDE to `q14` (Q2.14, 0x4000 = 100 %).
constexpr uint32_t override_to(uint32_t q14) { return override_set | (q14 & 0xFFFF) << 16; }
}  // namespace urgent

constexpr size_t kFrameHeaderBytes = 4;  // type, seq, nwords
constexpr size_t kCrcBytes = 2;
constexpr uint8_t kReplyMagic = 0xC5;
constexpr unsigned kReplyFixedWords = 7;  // words 0..6, then one per axis

// Bytes of a frame carrying `nwords` command words, without padding.
constexpr size_t frame_bytes(size_t nwords) { return kFrameHeaderBytes + 4 * nwords + kCrcBytes; }
// Bytes of the card's reply on a card of `axes` axes: (7 + axes) words and the CRC.
constexpr size_t reply_bytes(unsigned axes) { return 4 * (kReplyFixedWords + axes) + kCrcBytes; }

// The frame's bytes, then zero bytes up to `min_bytes` (pass reply_bytes(axes) to
// clock the whole reply in). `type` is a byte so that tests can send unknown
// types. Throws std::invalid_argument for more than 65535 words.
std::vector<uint8_t> encode_frame(uint8_t type, uint8_t seq, std::span<const uint32_t> words,
                                  size_t min_bytes = 0);
inline std::vector<uint8_t> encode_frame(FrameType type, uint8_t seq, std::span<const uint32_t> words,
                                         size_t min_bytes = 0) {
  return encode_frame(uint8_t(type), seq, words, min_bytes);
}
// A POLL padded to the reply's length.
std::vector<uint8_t> encode_poll(uint8_t seq, unsigned axes);

// Where a frame's words lie in a command stream.
struct WordRange {
  size_t first = 0;
  size_t count = 0;
  friend bool operator==(const WordRange&, const WordRange&) = default;
};
// Cuts a command stream into frames of whole commands, each at most `max_words`
// words, as few as possible in order (each frame takes as many whole commands as
// fit). Command lengths are command_words() on a card of `axes` axes (a
// phase-timer card's with `ptimer`). Throws std::invalid_argument naming the word
// when a command is longer than `max_words` or the stream ends inside a command.
std::vector<WordRange> split_commands(std::span<const uint32_t> words, unsigned axes, size_t max_words,
                                      bool ptimer = false);

// The result of a frame (reply word 0, [15:8]).
enum class FrameResult : uint8_t {
  ok = 0,
  truncated = 1,
  bad_crc = 2,
  bad_type = 3,
  no_room = 4,
  bad_command = 5,
  split_command = 6,
};
struct ResultName {
  const char* name;
  const char* meaning;
};
// "OK", "TRUNCATED", ... with a one-line meaning; "UNKNOWN" past the table.
ResultName frame_result_name(uint32_t code);

// Reply word 0, [7:0].
namespace reply_flag {
constexpr uint8_t busy = 1 << 0;     // the command buffer holds words the core has not taken
constexpr uint8_t estop = 1 << 1;    // the E-stop input
constexpr uint8_t drivers = 1 << 2;  // drivers enabled
constexpr uint8_t fresh = 1 << 3;    // no frame has ended since the card's reset
}  // namespace reply_flag

struct Reply {
  bool present = false;  // word 0 starts with the magic byte 0xC5
  bool crc_ok = false;   // the reply's CRC matches its bytes
  uint8_t last_seq = 0;
  uint8_t last_result = 0;  // FrameResult of the frame before this one
  uint8_t flags = 0;        // reply_flag
  uint16_t free_words = 0;  // free words in the command buffer
  uint16_t reads = 0;       // READ replies the core has given, mod 2^16
  uint32_t status = 0;      // the core's status word (READ 0x00)
  uint32_t stretch = 0, moves = 0, segments = 0;
  uint32_t last_read = 0;   // the last READ reply
  std::vector<int32_t> positions;
  std::string error;        // why this is not a good reply; "" when it is

  [[nodiscard]] bool ok() const { return error.empty(); }
};
// Decodes the first reply_bytes(axes) bytes (the rest is the card's trailing
// zeros). A missing card (no magic byte) or a CRC mismatch is reported in
// `error`, with the fields decoded anyway; fewer bytes than a reply, or axes
// outside 1..8, throw std::invalid_argument.
Reply decode_reply(std::span<const uint8_t> bytes, unsigned axes);

}  // namespace cpstep::card

// SPDX-License-Identifier: MIT
// A Verilated card driven through its pins only: the pin-level SPI master, the
// host's frame codec, and a record of every cycle's pins for the checks.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <ostream>
#include <span>
#include <vector>

#include "Vcp_card_small.h"
#include "card/frame.h"
#include "card/protocol.h"
#include "sim/card_configs.h"
#include "sim/spi_master.h"

namespace cpstep::tb {

// The small card of rtl/builds.json: 2 axes, W = 32, UMAX = 4095, KMAX = 3, a
// chunk queue of 8, a command buffer of 32 words, active-low STEP.
using CardSmall = sim::CardOf<builds::small, Vcp_card_small>;
static_assert(CardSmall::kCbufWords == 32);

// One cycle of the pins, as the master drove them and the card answered.
struct PinCycle {
  sim::CardIn in;
  sim::CardOut out;
};

template <class P>
class CardHarness {
 public:
  static constexpr unsigned N = P::kAxes;
  using Dut = sim::RtlDut<P>;

  explicit CardHarness(sim::SpiTiming t = {}, bool record = false)
      : spi_(dut_, t, [this](uint64_t c, const sim::CardIn& in, const sim::CardOut& out) {
          if (record_) {
            if (trace_.empty()) trace_start_ = c;
            trace_.push_back({in, out});
          }
        }),
        record_(record) {
    spi_.reset();
  }

  sim::SpiMaster<Dut>& spi() { return spi_; }
  const sim::CardOut& pins() const { return spi_.last(); }
  uint64_t cycle() const { return dut_.cycle(); }

  // The bytes of a frame, padded so the whole reply comes back.
  std::vector<uint8_t> frame(uint8_t type, uint8_t seq, std::span<const uint32_t> words) const {
    return card::encode_frame(type, seq, words, card::reply_bytes(N));
  }
  // Sends `bytes` (padded to a reply's length when shorter) and decodes the reply.
  card::Reply exchange(std::vector<uint8_t> bytes) {
    if (bytes.size() < card::reply_bytes(N)) bytes.resize(card::reply_bytes(N), 0);
    last_miso_ = spi_.transfer(bytes);
    return card::decode_reply(last_miso_, N);
  }
  card::Reply commands(std::span<const uint32_t> words) {
    return exchange(frame(uint8_t(card::FrameType::commands), ++seq_, words));
  }
  card::Reply poll() { return exchange(card::encode_poll(++seq_, N)); }
  // Polls until the card is not running and its buffer is empty (or gives up).
  card::Reply poll_until_idle(uint64_t max_cycles = 2'000'000) {
    const uint64_t until = cycle() + max_cycles;
    for (;;) {
      card::Reply r = poll();
      if (!(r.status & 1) && !(r.flags & card::reply_flag::busy)) return r;
      if (cycle() > until) {
        ADD_FAILURE() << "the card is still running after " << max_cycles << " cycles";
        return r;
      }
      spi_.idle(2000);
    }
  }
  uint8_t seq() const { return seq_; }
  void set_seq(uint8_t s) { seq_ = s; }
  const std::vector<uint8_t>& last_miso() const { return last_miso_; }

  // Cycles recorded since construction (with record = true) or the last clear.
  const std::vector<PinCycle>& trace() const { return trace_; }
  uint64_t trace_start() const { return trace_start_; }
  void clear_trace() { trace_.clear(); }

 private:
  Dut dut_;
  sim::SpiMaster<Dut> spi_;
  bool record_ = false;
  std::vector<PinCycle> trace_;
  uint64_t trace_start_ = 0;
  std::vector<uint8_t> last_miso_;
  uint8_t seq_ = 0;
};

// CRC-16/CCITT-FALSE one bit at a time, written here from the protocol's definition
// (polynomial 0x1021, init 0xFFFF, MSB first, no final XOR), not the codec's.
inline uint16_t crc_reference(std::span<const uint8_t> bytes) {
  uint32_t reg = 0xFFFF;
  for (uint8_t byte : bytes) {
    for (int i = 7; i >= 0; --i) {
      const bool top = reg >> 15 & 1;
      reg = (reg << 1) & 0xFFFF;
      if (top != bool(byte >> i & 1)) reg ^= 0x1021;
    }
  }
  return uint16_t(reg);
}

// What docs/PROTOCOL.md says the card answers to the first `bits` bits of `b`
// (the frame's result code), given the free words its reply announced; `conic`:
// the card's core takes CONIC commands (opcode 5). Written from the protocol's
// table, independently of the RTL and the codec.
inline uint8_t expected_result(std::span<const uint8_t> b, size_t bits, size_t free, unsigned axes,
                               bool conic = false, bool ptimer = false) {
  auto got = [&](size_t nbytes) { return bits >= 8 * nbytes && b.size() >= nbytes; };
  if (!got(4)) return 1;
  const size_t nwords = size_t(b[2]) << 8 | b[3];
  const size_t len = 4 + 4 * nwords + 2;
  if (!got(len)) return 1;
  const uint16_t crc = crc_reference(b.first(len - 2));
  if (b[len - 2] != (crc >> 8) || b[len - 1] != (crc & 0xFF)) return 2;
  const uint8_t type = b[0];
  // POLL: no words; URGENT ("Out of band"): one word, which is not a command.
  if (!(type == 0x01 || (type == 0x00 && nwords == 0) || (type == 0x02 && nwords == 1))) return 3;
  if (type == 0x02) return 0;
  if (type == 0x01 && nwords > free) return 4;
  size_t i = 0;
  while (i < nwords) {
    const size_t at = 4 + 4 * i;
    const uint32_t w = uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 | b[at + 3];
    const unsigned op = w >> 28;
    if (ptimer && (op == 1 || (op == 5 && conic))) {
      // A phase-timer card's segment: H0, H1, the v words of its axis form (with [15] set,
      // one per bit of [7:0]; else one per axis), a CONIC's K words, then L; no chunks.
      size_t v = axes;
      if (w >> 15 & 1) {
        v = 0;
        for (unsigned a = 0; a < 8; ++a) v += w >> a & 1;
      }
      i += 2 + v + (op == 5 ? ((w >> 18 & 1) ? 2 : 7) : 0) + 1;
    } else if (ptimer && op == 6) {
      i += 2 + ((w >> 24 & 1) ? 2 : 0) + ((w >> 27 & 1) ? 4 : 0);  // PHASE: u; r; S and H
    } else if (op == 1) i += 2 + axes + ((w >> 22 & 1) ? 3 : 2) * (w & 0xFFFF);
    else if (op == 5 && conic) i += 2 + axes + ((w >> 18 & 1) ? 2 : 7) + ((w >> 22 & 1) ? 3 : 2) * (w & 0xFFFF);
    else if (op >= 2 && op <= 4) i += 1;
    else return 5;
  }
  return i == nwords ? 0 : 6;
}

// A command list whose every word leaves a trace if it executes: drivers on (the
// enable flag), READ 0x1F (the READ counter and "CPS1"), a CONFIG, a short segment
// with the end flag (positions, counters), START.
struct VisibleJob {
  std::vector<uint32_t> words;
  size_t segment_first = 0, segment_words = 0;  // where the SEGMENT lies in `words`
  std::vector<int32_t> deltas;                  // what the segment moves each axis
  uint32_t moves = 0;
};
inline VisibleJob visible_job(unsigned axes) {
  VisibleJob j;
  card::encode_drivers(true, j.words);
  card::encode_read(card::Register::id, 0, j.words);
  card::encode_config(0, card::ConfigField::step_high, 2, j.words);
  card::WireSegment s;
  s.u = 6;
  s.k = 1;
  s.end = true;
  for (unsigned a = 0; a < axes; ++a) {
    s.dir_positive.push_back(a % 2 == 0);
    s.v.push_back(a == 0 ? 6 : (a * 5) % 7);  // 6, 5, 3, 1, ...: all <= U
  }
  s.chunks = {{300, 7, 1, 0}, {400, 5, -2, 0}};  // 12 moves = U * 2^k, about 4000 cycles
  j.segment_first = j.words.size();
  card::encode_segment(s, j.words);
  j.segment_words = j.words.size() - j.segment_first;
  card::encode_control(true, false, false, j.words);
  for (unsigned a = 0; a < axes; ++a)
    j.deltas.push_back(int32_t(s.v[a] << s.k) * (s.dir_positive[a] ? 1 : -1));
  j.moves = s.u << s.k;
  return j;
}

// Everything a refused frame must leave as it was: the reply's fields (but the
// frame's seq and result) and the card's pins.
struct Observed {
  uint8_t flags = 0;
  uint16_t free_words = 0, reads = 0;
  uint32_t status = 0, stretch = 0, moves = 0, segments = 0, last_read = 0;
  std::vector<int32_t> positions;
  uint32_t step = 0, dir = 0, err_code = 0;
  bool enable = false, running = false, fault = false;
  std::array<int32_t, sim::kCardMaxAxes> pin_position{};
  friend bool operator==(const Observed&, const Observed&) = default;
};
inline Observed observe(const card::Reply& r, const sim::CardOut& pins) {
  return {r.flags, r.free_words, r.reads, r.status, r.stretch, r.moves, r.segments, r.last_read,
          r.positions, pins.step, pins.dir, pins.err_code, pins.enable, pins.running, pins.fault,
          pins.position};
}
inline std::ostream& operator<<(std::ostream& os, const Observed& o) {
  os << "flags=" << unsigned(o.flags) << " free=" << o.free_words << " reads=" << o.reads << " status=0x"
     << std::hex << o.status << std::dec << " stretch=" << o.stretch << " moves=" << o.moves
     << " segments=" << o.segments << " last_read=0x" << std::hex << o.last_read << std::dec << " pos=";
  for (int32_t p : o.positions) os << p << ",";
  os << " pins: enable=" << o.enable << " running=" << o.running << " fault=" << o.fault
     << " err=" << o.err_code;
  return os;
}

}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// Bit helpers shared by the golden model's parts: the RTL's fixed-width fields
// and wide words (FifoWord: least significant 64-bit word first).
#pragma once

#include <cstdint>

#include "model/cp_fifo.h"

namespace cpstep::model::bits {

// The model's wide arithmetic (products and sums past 64 bits).
__extension__ typedef unsigned __int128 u128;
__extension__ typedef __int128 i128;

inline uint32_t mask(unsigned bits) { return bits >= 32 ? ~0u : (1u << bits) - 1; }
inline uint64_t mask64(unsigned bits) { return bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << bits) - 1; }

// Verilog's $clog2.
inline unsigned clog2(uint64_t x) {
  unsigned b = 0;
  while ((uint64_t(1) << b) < x) ++b;
  return b;
}

inline int64_t sext16(uint32_t x) { return int64_t(int16_t(uint16_t(x))); }

// A 16-bit tick counter (rtl/cp_inputs.v's samples, rtl/cp_feed.v's ramp ticks): a tick
// when it reads 0, then it starts again at P - 1, a period of max(P, 1) clocks; writing
// P starts it at 0. Its next value, and its value `cycles` clocks on.
inline uint32_t tick_next(uint32_t count, uint32_t period, bool written) {
  if (written) return 0;
  if (count == 0) return period == 0 ? 0 : period - 1;
  return (count - 1) & 0xFFFF;
}
inline uint32_t tick_skip(uint32_t count, uint32_t period, uint64_t cycles) {
  const uint64_t p = period == 0 ? 1 : period;
  return uint32_t((count + p - cycles % p) % p);
}

inline void put(FifoWord& w, unsigned lo, unsigned n, uint64_t value) {
  for (unsigned b = 0; b < n; ++b) {
    const unsigned at = lo + b;
    const uint64_t bit = uint64_t(1) << (at % 64);
    if (value >> b & 1) w[at / 64] |= bit;
    else w[at / 64] &= ~bit;
  }
}

inline uint64_t get(const FifoWord& w, unsigned lo, unsigned n) {
  uint64_t v = 0;
  for (unsigned b = 0; b < n; ++b) v |= (w[(lo + b) / 64] >> ((lo + b) % 64) & 1) << b;
  return v;
}

}  // namespace cpstep::model::bits

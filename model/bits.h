// SPDX-License-Identifier: MIT
// Bit helpers shared by the golden model's parts: the RTL's fixed-width fields
// and wide words (FifoWord: least significant 64-bit word first).
#pragma once

#include <cstdint>

#include "model/cp_fifo.h"

namespace cpstep::model::bits {

inline uint32_t mask(unsigned bits) { return bits >= 32 ? ~0u : (1u << bits) - 1; }
inline uint64_t mask64(unsigned bits) { return bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << bits) - 1; }

// Verilog's $clog2.
inline unsigned clog2(uint64_t x) {
  unsigned b = 0;
  while ((uint64_t(1) << b) < x) ++b;
  return b;
}

inline int64_t sext16(uint32_t x) { return int64_t(int16_t(uint16_t(x))); }

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

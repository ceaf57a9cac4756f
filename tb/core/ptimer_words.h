// SPDX-License-Identifier: MIT
// The phase timer's words for one phase (rtl/cp_ptimer.v: W0 last), for the
// benches that write phases: {sel, data}.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "card/job.h"
#include "plan/phases.h"

namespace cpstep::tb {

// kind = {load S and H, rest, timed, load r}.
inline std::vector<std::pair<uint32_t, uint32_t>> phase_words(uint32_t kind, uint32_t ticks, int64_t u,
                                                              uint64_t r_top, int64_t s, int64_t h) {
  std::vector<std::pair<uint32_t, uint32_t>> w;
  w.push_back({1, uint32_t(u)});
  if (kind & 1) {
    w.push_back({2, uint32_t(r_top)});
    w.push_back({3, uint32_t(r_top >> 32)});
  }
  if (kind & 8) {
    w.push_back({4, uint32_t(s)});
    w.push_back({5, uint32_t(uint64_t(s) >> 32)});
    w.push_back({6, uint32_t(h)});
    w.push_back({7, uint32_t(uint64_t(h) >> 32)});
  }
  w.push_back({0, (kind & 15) << 28 | (ticks & 0xFFFFFF)});
  return w;
}

// The card's words for one of the host's phases.
inline std::vector<std::pair<uint32_t, uint32_t>> host_phase_words(const plan::TimerPhase& ph) {
  const card::WirePhase w = card::wire_phase(ph);
  return phase_words(w.kind, w.ticks, w.u, w.r_top, w.s, w.h);
}

}  // namespace cpstep::tb

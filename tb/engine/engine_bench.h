// SPDX-License-Identifier: MIT
// Helpers shared by the engine benches: run a request in lockstep with random
// back-pressure and the move stream's contract checked on every cycle.
#pragma once

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "common/lockstep.h"
#include "model/oracle.h"
#include "sim/engine_configs.h"
#include "sim/engine_session.h"

namespace cpstep::tb {

// Back-pressure on the move stream: 0 = always ready, else ready with
// probability `ready_pct` percent, drawn from a seeded generator.
struct Backpressure {
  unsigned ready_pct = 100;
  uint64_t seed = 1;
};

// `pends`, if given, receives the 1-based index of every move taken with move_pend_o.
template <class P>
sim::EngineRun run_lockstep(Lockstep<P>& ls, const sim::EngineRequest& req, Backpressure bp = {},
                            std::vector<uint64_t>* pends = nullptr) {
  std::mt19937_64 rng(bp.seed);
  std::uniform_int_distribution<unsigned> pct(0, 99);
  StreamContract contract("move stream");
  const auto ready = [&](uint64_t) { return bp.ready_pct >= 100 || pct(rng) < bp.ready_pct; };
  uint64_t taken = 0;
  const auto observe = [&](uint64_t c, const model::CpEngineIn& in, const model::CpEngineOut& o) {
    contract.check(c, o.move_valid, in.move_ready, (uint64_t(o.move) << 2) | (uint64_t(o.move_pend) << 1) |
                                                       o.move_last);
    if (o.move_valid && in.move_ready) {
      ++taken;
      if (pends && o.move_pend) pends->push_back(taken);
    }
  };
  return sim::run_request(ls, P::model_params().aw(), req, ready, observe);
}

inline std::string repeat(const std::string& s, uint64_t n) {
  std::string out;
  out.reserve(s.size() * n);
  for (uint64_t i = 0; i < n; ++i) out += s;
  return out;
}

inline uint64_t gcd(uint64_t a, uint64_t b) { return b == 0 ? a : gcd(b, a % b); }

}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// Random host-like jobs streamed to a running core, in lockstep with the model and
// the pin checker on every cycle (CoreHarness): the body of the CoreRandom benches
// (test_core_random.cpp), shared with the post-synthesis bench (tb/netlist).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "core/core_bench.h"

namespace cpstep::tb {

// `batches` fresh harnesses (seeds seed, seed+1, ...), each running `jobs` jobs of
// `segments` segments with random pulse timing and command pacing, checked after
// every job; prints what ran and returns the cycles it ran. With a skipping model
// (sim::Skipping) `skipped` gets the clocks it skipped rather than ticked.
template <class P>
uint64_t random_jobs(const char* name, uint64_t seed, unsigned batches, unsigned jobs, unsigned segments,
                     JobShape shape, uint64_t* skipped = nullptr) {
  uint64_t moves = 0, late = 0, segs = 0, cycles = 0, add2_chunks = 0, curved = 0;
  for (unsigned b = 0; b < batches; ++b) {
    CoreHarness<P> h(name, seed + b);
    for (unsigned j = 0; j < jobs; ++j) {
      // Pulse timing from tight (mostly on time) to loose (mostly stretched).
      const uint32_t timings[] = {2, 8, shape.max_timing};
      h.configure_random(timings[h.gen.uniform(0, 2)]);
      h.word_gap = h.gen.chance(0.5) ? 0.0 : 0.3;
      const auto job = h.gen.job(segments, shape);
      for (const auto& s : job)
        for (const auto& c : s.chunks) {
          add2_chunks += c.add2 != 0;
          curved += c.add2 != 0 && c.count >= 3;
        }
      h.play(job);
      const std::string where = std::string(name) + " seed " + std::to_string(seed + b) + " job " +
                                std::to_string(j);
      h.expect_consistent(where);
      if (::testing::Test::HasFailure()) return cycles + h.cycles;
    }
    if constexpr (requires { h.ls.model_stepper().skipped(); })
      if (skipped) *skipped += h.ls.model_stepper().skipped();
    moves += h.chk.moves();
    late += h.chk.late_moves();
    segs += h.chk.segments_done();
    cycles += h.cycles;
  }
  std::printf("%s: %llu segments, %llu moves (%llu late), %llu cycles, %llu chunks with add2 "
              "(%llu of 3 moves or more)\n",
              name, (unsigned long long)segs, (unsigned long long)moves, (unsigned long long)late,
              (unsigned long long)cycles, (unsigned long long)add2_chunks, (unsigned long long)curved);
  EXPECT_GT(moves, 0u);
  EXPECT_GT(curved, 0u) << "the jobs have no chunk whose delays add2 shapes";
  return cycles;
}

}  // namespace cpstep::tb

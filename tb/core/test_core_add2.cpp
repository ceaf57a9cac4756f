// SPDX-License-Identifier: MIT
// cp_core chunks with add2 (docs/CORE.md "Command port", "Cycle behaviour"): move j
// of a chunk comes interval + j·add + add2·j(j−1)/2 cycles after the previous move;
// a segment's chunks are three words when its header has bit 22. RTL vs model in
// lockstep with the pin checker on; the expected cycles are worked out by hand.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/core_bench.h"
#include "core/core_validated.h"

namespace cpstep::tb {
namespace {

using Core = ValidatedCore;
using Harness = CoreHarness<Core>;

card::WireSegment seg_of(Harness& h, const std::vector<int64_t>& d, std::vector<card::WireChunk> chunks,
                         bool end = false) {
  card::WireSegment s;
  if (!h.gen.from_deltas(d, s)) throw std::runtime_error("bench error: segment does not fit");
  s.chunks = std::move(chunks);
  s.end = end;
  return s;
}

// Two-word and three-word segments in one run; every leading edge of x (the major
// axis of each) at START + 1 + the sum of the delays so far.
TEST(CoreAdd2, TwoAndThreeWordSegmentsInOneRun) {
  Harness h("add2_mixed", 1);
  h.word_gap = 0;
  // Delays 10, 12, 14, 16, 18, 20 (add only: two words per chunk).
  const card::WireSegment a = seg_of(h, {6, 2, 0, 0}, {{10, 6, 2}});
  // Increments 4, 2, 0: delays 20, 24, 26, 26.
  const card::WireSegment b = seg_of(h, {4, 0, -4, 0}, {{20, 4, 4, -2}});
  // Delays 8, 7, 6, 5, 4.
  const card::WireSegment c = seg_of(h, {5, 0, 0, 1}, {{8, 5, -1}});
  // Increments -1, -4, -7, -10, -13: delays 40, 39, 35, 28, 18, 5.
  const card::WireSegment d = seg_of(h, {6, -3, 0, 0}, {{40, 6, -1, -3}}, true);
  std::vector<uint32_t> wa, wb;
  card::encode_segment(a, wa);
  card::encode_segment(b, wb);
  ASSERT_EQ(wa.size(), 2u + 4 + 2);
  ASSERT_EQ(wb.size(), 2u + 4 + 3);
  EXPECT_EQ(wa[0] >> 22 & 1, 0u);
  EXPECT_EQ(wb[0] >> 22 & 1, 1u);
  EXPECT_EQ(wb.back(), 0x0000FFFEu) << "C2: add2 = -2 in [15:0], [31:16] zero";

  std::vector<uint64_t> edges;
  uint32_t prev = 0;
  h.hook = [&](uint64_t cyc, const model::CpCoreIn&, const model::CpCoreOut& o) {
    if (o.step & ~prev & 1) edges.push_back(cyc);
    prev = o.step;
  };
  for (const auto* s : {&a, &b, &c, &d}) h.segment(*s);
  h.idle(50);  // all built before START
  const uint64_t start = h.control(true, false, false);
  h.finish();
  h.idle(10);
  const std::vector<uint64_t> delays = {10, 12, 14, 16, 18, 20, 20, 24, 26, 26, 8,  7,
                                        6,  5,  4,  40, 39, 35, 28, 18, 5};
  std::vector<uint64_t> expected;
  uint64_t t = start + 1;
  for (uint64_t dl : delays) expected.push_back(t += dl);
  EXPECT_EQ(edges, expected);
  EXPECT_EQ(h.chk.late_moves(), 0u);
  EXPECT_EQ(h.chk.position(0), 6 + 4 + 5 + 6);
  EXPECT_EQ(h.chk.position(1), 2 - 3);
  EXPECT_EQ(h.chk.position(2), -4);
  EXPECT_EQ(h.chk.position(3), 1);
  h.expect_consistent("add2 mixed");
}

// The port's pause after each chunk's last word (docs/CORE.md, "Command port"): the
// bit-serial check's 51 clocks, whatever the values (with add2 or without, counts
// 1 to 65535, multipliers of every bit length). The next word is taken the cycle after.
TEST(CoreAdd2, PortPauseAfterEachChunk) {
  Harness h("add2_port", 2);
  h.word_gap = 0;
  h.expecting = false;
  struct Case {
    card::WireChunk chunk;
    uint64_t check;
  };
  constexpr uint64_t kCheck = JobGen::kCheckCycles;
  const std::vector<Case> three = {
      {{7, 1, 0, 0}, kCheck},       {{7, 1, 3, 5}, kCheck},        {{7, 2, 3, -7}, kCheck},
      {{7, 3, 1, 1}, kCheck},       {{7, 4, 2, 0}, kCheck},        {{5000, 100, 0, -1}, kCheck},
      {{1, 65535, 0, 1}, kCheck},
  };
  const std::vector<Case> two = {
      {{7, 1, 0}, kCheck},
      {{7, 4, 2}, kCheck},
      {{1, 65535, 0}, kCheck},
  };
  for (const auto* cases : {&three, &two}) {
    card::WireSegment s;
    s.dir_positive = {true, true, true, true};
    for (const Case& c : *cases) {
      s.chunks.push_back(c.chunk);
      s.u += c.chunk.count;
    }
    s.v = {s.u, 0, 0, 0};
    std::vector<uint32_t> w;
    card::encode_segment(s, w);
    const size_t per = cases == &three ? 3 : 2;
    ASSERT_EQ(w.size(), 6 + per * cases->size());
    std::vector<uint64_t> taken;
    h.hook = [&](uint64_t cyc, const model::CpCoreIn& in, const model::CpCoreOut& o) {
      if (in.cmd_valid && o.cmd_ready) taken.push_back(cyc);
    };
    h.send(w);
    h.read(card::Register::id);  // the word after the last chunk
    h.hook = nullptr;
    ASSERT_EQ(taken.size(), w.size() + 1);
    for (size_t i = 0; i < cases->size(); ++i) {
      const size_t last = 6 + per * i + per - 1;  // the chunk's last word
      EXPECT_EQ(taken[last + 1] - taken[last], (*cases)[i].check + 1)
          << (per == 3 ? "three" : "two") << "-word chunk " << i << " (count " << (*cases)[i].chunk.count
          << ", add2 " << (*cases)[i].chunk.add2 << ")";
    }
  }
  const card::Status st = h.status();
  EXPECT_FALSE(st.fault) << "code " << st.err_code;
  EXPECT_EQ(st.segments_queued, 2u);
  h.control(false, true, false);
  h.control(false, false, true);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// cp_core's parts on their own: each Verilated part (cp_cmd, cp_build, cp_run,
// cp_status) against its model twin every cycle, under random inputs shaped to
// reach every state (whole legal segments among junk for the parser; segment
// queue words for the builder; chunks, built segments and bank writes for the
// runner; every fault request for the status). A part is a deterministic
// function of its inputs, so any input sequence is a fair test of its twin; the
// counters below check that the traffic reached what it is meant to reach.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <set>

#include "common/lockstep.h"
#include "core/core_parts_ports.h"
#include "core/ptimer_words.h"

namespace cpstep::tb {
namespace {

using Rng = std::mt19937_64;

uint32_t pick(Rng& rng, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(rng);
}
bool chance(Rng& rng, unsigned pct) { return pick(rng, 0, 99) < pct; }

// ---------------------------------------------------------------- cp_cmd
// At most nch chunk counts summing to moves, each in 1..65535 (moves < 2^15, so any
// split fits).
std::vector<uint32_t> split_counts(Rng& rng, uint32_t moves, uint32_t nch) {
  std::vector<uint32_t> counts;
  uint32_t left = moves;
  for (uint32_t c = 0; c + 1 < nch && left > 1; ++c) {
    const uint32_t take = pick(rng, 1, left - 1);
    counts.push_back(take);
    left -= take;
  }
  counts.push_back(left);
  return counts;
}

// The words of one segment that passes every check (N = 3, UMAX 4095, KMAX 3,
// 2^CAW = 8 chunks), sometimes with add2; or with one field broken.
std::vector<uint32_t> segment_words(Rng& rng, bool legal) {
  const uint32_t k = pick(rng, 0, 3), u = pick(rng, 1, 4095), nch = pick(rng, 1, 4);
  const bool with_add2 = chance(rng, 40);
  const std::vector<uint32_t> counts = split_counts(rng, u << k, nch);
  std::vector<uint32_t> w;
  // H0[16], the torch, from what was drawn (the random stream stays as it was).
  w.push_back(0x1u << 28 | uint32_t(chance(rng, 20)) << 27 | k << 23 | uint32_t(with_add2) << 22 |
              ((u ^ nch) & 1) << 16 | uint32_t(counts.size()));
  w.push_back(pick(rng, 0, 7) << 24 | u);
  for (int a = 0; a < 3; ++a) w.push_back(chance(rng, 20) ? 0 : chance(rng, 20) ? u : pick(rng, 0, u));
  for (uint32_t c : counts) {
    w.push_back(pick(rng, 1, 5000));                            // interval
    const uint32_t add = chance(rng, 50) ? pick(rng, 0, 3) : uint32_t(-int32_t(pick(rng, 0, 3)));
    w.push_back((add & 0xFFFF) << 16 | c);
    if (with_add2) w.push_back(chance(rng, 50) ? 0 : pick(rng, 0, 1));
  }
  if (!legal) {
    // One field out of range: U, a v, a count, k, nchunks or an interval.
    switch (pick(rng, 0, 5)) {
      case 0: w[1] = (w[1] & 0xFF000000) | pick(rng, 4096, 0xFFFFFF); break;
      case 1: w[2] = (w[1] & 0xFFFFFF) + 1; break;
      case 2: w[6] ^= 1; break;
      case 3: w[0] = (w[0] & ~(0xFu << 23)) | pick(rng, 4, 15) << 23; break;
      case 4: w[0] = (w[0] & ~0xFFFFu) | (chance(rng, 50) ? 0 : pick(rng, 9, 0xFFFF)); break;
      default: w[5] = 0; break;
    }
  }
  return w;
}

// The words of one CONIC segment (docs/CORE.md "Command port": N = 3, UMAX 4095, 8
// chunks), legal or with one field broken: the plane axes (equal, or not an axis),
// a plane axis's v, T, the count sum.
std::vector<uint32_t> conic_words(Rng& rng, bool legal) {
  const uint32_t t = pick(rng, 1, 4095), nch = pick(rng, 1, 3);
  const uint32_t au = pick(rng, 0, 2), av = (au + pick(rng, 1, 2)) % 3;
  const bool with_add2 = chance(rng, 30);
  const std::vector<uint32_t> counts = split_counts(rng, t, nch);
  std::vector<uint32_t> w;
  w.push_back(0x5u << 28 | uint32_t(chance(rng, 20)) << 27 | uint32_t(chance(rng, 50)) << 26 | au << 23 |
              uint32_t(with_add2) << 22 | av << 19 | ((t ^ nch) & 1) << 16 | uint32_t(counts.size()));
  w.push_back(pick(rng, 0, 7) << 24 | t);
  for (uint32_t a = 0; a < 3; ++a) w.push_back(a == au || a == av ? 0 : chance(rng, 30) ? 0 : pick(rng, 0, t));
  for (int k = 0; k < 7; ++k) w.push_back(uint32_t(rng()));  // A B, C, G, Gx, Gy, du, dv: any bits
  for (uint32_t c : counts) {
    w.push_back(pick(rng, 1, 5000));
    w.push_back(pick(rng, 0, 2) << 16 | c);
    if (with_add2) w.push_back(0);
  }
  if (!legal) {
    switch (pick(rng, 0, 4)) {
      case 0: w[0] = (w[0] & ~(7u << 19)) | au << 19; break;           // u = v
      case 1: w[0] = (w[0] & ~(7u << 23)) | pick(rng, 3, 7) << 23; break;  // u not an axis
      case 2: w[2 + au] = pick(rng, 1, t); break;                      // a plane axis's v
      case 3: w[1] = (w[1] & 0xFF000000) | (chance(rng, 50) ? 0 : pick(rng, 4096, 0xFFFFFF)); break;
      default: w[w.size() - (with_add2 ? 2 : 1)] ^= 1; break;          // the count sum
    }
  }
  return w;
}

uint32_t other_word(Rng& rng) {
  switch (pick(rng, 0, 4)) {
    // CONFIG: every field, the refused ones (9 without FEED, 10 without INPUTS, 11..15) too.
    case 0: return 0x2u << 28 | pick(rng, 0, 4) << 24 | pick(rng, 0, 15) << 20 | pick(rng, 0, 300);
    case 1: return 0x3u << 28 | pick(rng, 0, 31);                                                 // CONTROL
    case 2: return 0x4u << 28 | pick(rng, 0, 0x30);                                               // READ
    case 3: return pick(rng, 5, 15) << 28 | pick(rng, 0, 0xFFFFFFF);                              // bad op
    default: return uint32_t(rng());                                                              // anything
  }
}

template <class P>
void cmd_traffic(uint64_t seed, int cycles, bool conic = false) {
  Rng rng(seed);
  Lockstep<P> ls;
  ls.reset();
  std::deque<uint32_t> words;
  model::CpCmdIn in;
  uint64_t commits = 0, rollbacks = 0, replies = 0, cfg_writes = 0, conic_commits = 0;
  bool in_conic = false;
  std::set<uint32_t> codes;
  for (int c = 0; c < cycles; ++c) {
    if (words.empty()) {
      const uint32_t kind = pick(rng, 0, 99);
      if (conic && kind < 25) {
        for (uint32_t w : conic_words(rng, kind < 18)) words.push_back(w);
      } else if (kind < 55) {
        for (uint32_t w : segment_words(rng, true)) words.push_back(w);
      } else if (kind < 75) {
        for (uint32_t w : segment_words(rng, false)) words.push_back(w);
      } else {
        words.push_back(other_word(rng));
      }
    }
    in.rst = pick(rng, 0, 9999) == 0;
    in.cmd_valid = chance(rng, 80);
    in.cmd_data = words.front();
    in.rsp_ready = chance(rng, 50);
    in.read_data = uint32_t(rng());
    if (pick(rng, 0, 999) < (in.fault ? 20u : 2u)) in.fault = !in.fault;  // mostly clear
    in.running = chance(rng, 10);
    in.pulse_busy = chance(rng, 10);
    in.seg_full = chance(rng, 10);
    in.ch_full = chance(rng, 10);
    in.flush = pick(rng, 0, 999) < 2;  // an out-of-band FLUSH now and then
    const model::CpCmdOut o = ls.step(in);
    if (in.cmd_valid && o.cmd_ready) words.pop_front();
    // A conic's header goes into the segment queue with the conic flag (bit 30 + N)
    // above {out, end, k, dir, U}; its other words have 32 bits.
    if (o.seg_wr && (o.seg_data >> 33 & 1)) in_conic = true;
    conic_commits += o.seg_commit && in_conic;
    if (o.seg_commit || o.seg_rollback) in_conic = false;
    commits += o.seg_commit;
    rollbacks += o.seg_rollback;
    replies += o.rsp_valid && in.rsp_ready;
    cfg_writes += o.cfg_write;
    if (o.fault) codes.insert(o.fault_code);
  }
  EXPECT_GT(commits, 100u) << "whole segments should pass";
  EXPECT_GT(rollbacks, 100u);
  EXPECT_GT(replies, 0u);
  EXPECT_GT(cfg_writes, 0u);
  // Every refusal the parser makes: 1..7, 12..15.
  for (uint32_t code : {1u, 2u, 3u, 4u, 5u, 6u, 7u, 12u, 13u, 14u, 15u})
    EXPECT_TRUE(codes.count(code)) << "refusal code " << code << " never raised";
  EXPECT_EQ(codes.count(16u), conic ? 1u : 0u) << "CONIC_AXES";
  if (conic) {
    EXPECT_GT(conic_commits, 50u) << "whole conic segments should pass";
  }
}

TEST(CorePartCmd, RandomWordsMatchTheModel) { cmd_traffic<CmdPort>(11, 300000); }
// With CONIC segments (docs/CORE.md): their words into the segment queue, K1 carrying
// the header's plane axes and direction, CONIC_AXES among the refusals.
TEST(CorePartCmd, ConicSegmentsMatchTheModel) { cmd_traffic<CmdConicPort>(12, 300000, true); }

// The phase timer's build (PTIMER = 1, with CONIC): segments with no chunks and their
// length per move last (a line's or a conic's; legal, or with one field broken:
// U, a v, k, a bad axis form, L = 0), every axis's v sent or in the compact axis
// form, and PHASE commands of every kind (its words as the timer's {sel, data} into
// the chunk queue, W0 last, committed whole).

// A long-form segment's words (H0[15:0] = 0, N = 3) in the compact axis form
// (docs/CORE.md "Phase-timer builds"): some axis whose v = U (not 0) as the major one,
// its v not sent; the others that move sent, and now and then one that does not.
std::vector<uint32_t> pt_compact(Rng& rng, const std::vector<uint32_t>& w) {
  const uint32_t u = w[1] & 0xFFFFFF;
  uint32_t major = 0, sent = 0;
  for (uint32_t a = 0; a < 3; ++a) {
    const uint32_t v = w[2 + a] & 0xFFFFFF;
    if (major == 0 && v == u && v != 0 && chance(rng, 80)) major = 8 | a;
    else if (v != 0 || chance(rng, 25)) sent |= 1u << a;
  }
  std::vector<uint32_t> c{w[0] | 0x8000u | major << 8 | sent, w[1]};
  for (uint32_t a = 0; a < 3; ++a)
    if (sent >> a & 1) c.push_back(w[2 + a]);
  c.insert(c.end(), w.begin() + 5, w.end());
  return c;
}

// An axis form the card refuses (SEG_FORM): not 0 with [15] clear, [14:12] set, an
// axis past N = 3 sent or major, or the major axis sent too.
uint32_t pt_bad_form(Rng& rng) {
  switch (pick(rng, 0, 4)) {
    case 0: return pick(rng, 1, 0x7FFF);
    case 1: return 0x8000u | pick(rng, 1, 7) << 12 | pick(rng, 0, 0xFFF);
    case 2: return 0x8000u | pick(rng, 0, 15) << 8 | pick(rng, 8, 255);
    case 3: return 0x8000u | (8 | pick(rng, 3, 7)) << 8 | pick(rng, 0, 7);
    default: {
      const uint32_t m = pick(rng, 0, 2);
      return 0x8000u | (8 | m) << 8 | 1u << m | pick(rng, 0, 7);
    }
  }
}

std::vector<uint32_t> pt_segment_words(Rng& rng, bool legal, bool bad_form_ok = true) {
  const bool conic = chance(rng, 30);
  const uint32_t k = conic ? 0 : pick(rng, 0, 3), u = pick(rng, 1, 4095);
  const uint32_t au = pick(rng, 0, 2), av = (au + pick(rng, 1, 2)) % 3;
  std::vector<uint32_t> w;
  w.push_back((conic ? 0x5u : 0x1u) << 28 | uint32_t(chance(rng, 20)) << 27 |
              (conic ? uint32_t(chance(rng, 50)) << 26 | au << 23 | av << 19 : k << 23) |
              uint32_t(chance(rng, 20)) << 16);
  w.push_back(pick(rng, 0, 7) << 24 | u);
  for (uint32_t a = 0; a < 3; ++a)
    w.push_back(conic && (a == au || a == av) ? 0 : chance(rng, 20) ? 0 : chance(rng, 20) ? u : pick(rng, 0, u));
  if (conic)
    for (int i = 0; i < 7; ++i) w.push_back(uint32_t(rng()));
  w.push_back(chance(rng, 5) ? uint32_t(rng()) : pick(rng, 1u << 20, 1u << 31));   // L
  if (!legal) {
    switch (pick(rng, bad_form_ok ? 0 : 1, 4)) {
      case 0: w[0] |= pt_bad_form(rng); return w;
      case 1: w[1] = (w[1] & 0xFF000000) | (chance(rng, 50) ? 0 : pick(rng, 4096, 0xFFFFFF)); break;
      case 2: w[2 + (conic ? au : 0)] = conic ? pick(rng, 1, u) : u + 1; break;   // CONIC_AXES, SEG_V_GT_U
      case 3: if (!conic) w[0] = (w[0] & ~(0xFu << 23)) | pick(rng, 4, 15) << 23; break;
      default: w.back() = 0; break;
    }
  }
  return chance(rng, 50) ? pt_compact(rng, w) : w;
}

std::vector<uint32_t> pt_phase_cmd(Rng& rng) {
  const uint32_t kind = pick(rng, 0, 15);
  std::vector<uint32_t> w{0x6u << 28 | kind << 24 | pick(rng, 0, 0xFFFFFF)};
  for (int i = 0; i < 1 + (kind & 1 ? 2 : 0) + (kind & 8 ? 4 : 0); ++i) w.push_back(uint32_t(rng()));
  return w;
}

TEST(CorePartCmd, PhaseTimerBuildMatchesTheModel) {
  Rng rng(13);
  Lockstep<CmdPtimerPort> ls;
  ls.reset();
  std::deque<uint32_t> words;
  model::CpCmdIn in;
  uint64_t commits = 0, rollbacks = 0, phases = 0, phase_drops = 0, phase_words = 0;
  std::set<uint32_t> codes;
  for (int c = 0; c < 300000; ++c) {
    if (words.empty()) {
      const uint32_t kind = pick(rng, 0, 99);
      const std::vector<uint32_t> w = kind < 35   ? pt_segment_words(rng, true)
                                      : kind < 50 ? pt_segment_words(rng, false)
                                      : kind < 85 ? pt_phase_cmd(rng)
                                                  : std::vector<uint32_t>{other_word(rng)};
      words.insert(words.end(), w.begin(), w.end());
    }
    in.rst = pick(rng, 0, 9999) == 0;
    in.cmd_valid = chance(rng, 80);
    in.cmd_data = words.front();
    in.rsp_ready = chance(rng, 50);
    in.read_data = uint32_t(rng());
    if (pick(rng, 0, 999) < (in.fault ? 20u : 2u)) in.fault = !in.fault;
    in.running = chance(rng, 10);
    in.pulse_busy = chance(rng, 10);
    in.seg_full = chance(rng, 10);
    in.ch_full = chance(rng, 10);
    in.flush = pick(rng, 0, 999) < 2;
    const model::CpCmdOut o = ls.step(in);
    if (in.cmd_valid && o.cmd_ready) words.pop_front();
    commits += o.seg_commit;
    rollbacks += o.seg_rollback;
    phases += o.ch_commit;
    phase_drops += o.ch_rollback;
    phase_words += o.ch_wr;
    if (o.fault) codes.insert(o.fault_code);
  }
  std::printf("segments committed %llu, rolled back %llu; phases committed %llu, dropped %llu, words %llu\n",
              (unsigned long long)commits, (unsigned long long)rollbacks, (unsigned long long)phases,
              (unsigned long long)phase_drops, (unsigned long long)phase_words);
  EXPECT_GT(commits, 100u);
  EXPECT_GT(rollbacks, 100u);
  EXPECT_GT(phases, 1000u);
  EXPECT_GT(phase_drops, 10u) << "phases read while a fault is latched are dropped whole";
  EXPECT_GT(phase_words, 3 * phases) << "phases of more than u and W0";
  // Its refusals: 1..3, 12..14, 16, 21 (L = 0), 22 (a bad axis form); no chunk checks.
  for (uint32_t code : {1u, 2u, 3u, 12u, 13u, 14u, 16u, 21u, 22u})
    EXPECT_TRUE(codes.count(code)) << "refusal code " << code << " never raised";
  for (uint32_t code : {4u, 5u, 6u, 7u, 15u}) EXPECT_FALSE(codes.count(code)) << "chunk refusal " << code;
}

// The compact axis form against every axis sent: the same segments (legal and broken,
// lines and conics), each stream through its own parser
// (RTL and model in lockstep), must write the same segment queue words and commit,
// roll back and refuse alike; the compact stream's words are fewer.
TEST(CorePartCmd, CompactAxisFormWritesWhatEveryAxisSentDoes) {
  Rng rng(14);
  std::vector<uint32_t> every, compact;
  for (int n = 0; n < 3000; ++n) {
    const std::vector<uint32_t> w = pt_segment_words(rng, chance(rng, 70), false);
    const bool is_compact = (w[0] >> 15 & 1) != 0;
    // Back to every axis sent if the generator made it compact, and the other way.
    std::vector<uint32_t> long_form = w;
    if (is_compact) {
      long_form = {w[0] & ~0xFFFFu, w[1]};
      size_t next = 2;
      for (uint32_t a = 0; a < 3; ++a) {
        const bool sent = w[0] >> a & 1, major = (w[0] >> 11 & 1) && (w[0] >> 8 & 7) == a;
        long_form.push_back(sent ? w[next++] : major ? w[1] & 0xFFFFFF : 0);
      }
      long_form.insert(long_form.end(), w.begin() + next, w.end());
    }
    const std::vector<uint32_t> short_form = is_compact ? w : pt_compact(rng, w);
    every.insert(every.end(), long_form.begin(), long_form.end());
    compact.insert(compact.end(), short_form.begin(), short_form.end());
  }
  const auto run = [&](const std::vector<uint32_t>& words, uint64_t seed) {
    Rng r(seed);
    Lockstep<CmdPtimerPort> ls;
    ls.reset();
    model::CpCmdIn in;
    std::vector<uint64_t> events;   // seg_wr data, then 1 << 40 commit, 2 << 40 rollback, 3 << 40 | code
    size_t next = 0;
    for (int idle = 0; idle < 20;) {
      in.cmd_valid = next < words.size() && chance(r, 80);
      in.cmd_data = next < words.size() ? words[next] : 0;
      in.seg_full = chance(r, 10);
      in.ch_full = chance(r, 10);
      const model::CpCmdOut o = ls.step(in);
      if (in.cmd_valid && o.cmd_ready) ++next;
      if (o.seg_wr) events.push_back(o.seg_data);
      if (o.seg_commit) events.push_back(uint64_t(1) << 40);
      if (o.seg_rollback) events.push_back(uint64_t(2) << 40);
      if (o.fault) events.push_back(uint64_t(3) << 40 | o.fault_code);
      idle += next == words.size();
    }
    return events;
  };
  const std::vector<uint64_t> a = run(every, 1), b = run(compact, 2);
  const auto count = [](const std::vector<uint64_t>& e, uint64_t x) { return std::count(e.begin(), e.end(), x); };
  std::printf("every axis sent: %zu words; compact: %zu words; %td commits, %td rollbacks, %zu queue writes\n",
              every.size(), compact.size(), count(a, uint64_t(1) << 40), count(a, uint64_t(2) << 40), a.size());
  EXPECT_LT(compact.size(), every.size());
  EXPECT_GT(count(a, uint64_t(1) << 40), 1000);
  EXPECT_GT(count(a, uint64_t(2) << 40), 300);
  for (uint32_t code : {1u, 2u, 3u, 16u, 21u}) EXPECT_GT(count(a, uint64_t(3) << 40 | code), 0) << "code " << code;
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "event " << i;
}

// ---------------------------------------------------------------- cp_build
// Segment queue words as the parser commits them (N = 3): header {out, end, k, dir, U},
// then v_0..v_2, 1 <= U <= UMAX = 200 and v <= U (cp_build's contract: its engine
// runs in one-period mode, which checks nothing but the pattern's length); U up to
// 200 against W = 32, so some patterns are too long.
// With conic: CONIC segments too, as the parser writes them (docs/CORE.md): the
// header with the conic flag (bit 30 + N = 33), k = 0, v = 0 on the plane axes, then
// K0 .. K6 with K1 = {cw, u, v, 9 zeros, C}.
// With ptimer: each segment's length per move (any bits) as its last word.
std::vector<uint64_t> build_words(Rng& rng, bool conic = false, bool ptimer = false) {
  const uint32_t u = chance(rng, 30) ? pick(rng, 1, 8) : pick(rng, 1, 200);
  const bool is_conic = conic && chance(rng, 35);
  const uint32_t au = pick(rng, 0, 2), av = (au + pick(rng, 1, 2)) % 3;
  std::vector<uint64_t> w;
  w.push_back(uint64_t(is_conic) << 33 | uint64_t(chance(rng, 50)) << 32 | uint64_t(chance(rng, 10)) << 31 |
              uint64_t(is_conic ? 0 : pick(rng, 0, 3)) << 27 | uint64_t(pick(rng, 0, 7)) << 24 | u);
  for (uint32_t a = 0; a < 3; ++a) {
    const uint32_t r = pick(rng, 0, 9);
    w.push_back(is_conic && (a == au || a == av) ? 0 : r < 2 ? 0 : r < 4 ? u : pick(rng, 0, u));
  }
  if (is_conic)
    for (int k = 0; k < 7; ++k)
      w.push_back(k == 1 ? uint64_t(pick(rng, 0, 1)) << 31 | uint64_t(au) << 28 | uint64_t(av) << 25 |
                               pick(rng, 0, 0xFFFF)
                         : uint64_t(uint32_t(rng())));
  if (ptimer) w.push_back(uint32_t(rng()));
  return w;
}

template <class P>
void build_traffic(uint64_t seed, bool conic, bool ptimer = false) {
  Rng rng(seed);
  Lockstep<P> ls;
  ls.reset();
  std::deque<uint64_t> words;
  model::CpBuildIn in;
  uint64_t built = 0, refused = 0, engine_moves = 0, conic_built = 0, pt_words = 0;
  for (int c = 0; c < 300000; ++c) {
    if (words.empty())
      for (uint64_t w : build_words(rng, conic, ptimer)) words.push_back(w);
    in.rst = pick(rng, 0, 9999) == 0;
    in.flush = pick(rng, 0, 999) < 3;
    if (chance(rng, 1)) in.fault = !in.fault;
    in.seg_valid = chance(rng, 85);
    in.seg_head = words.front();
    in.seg_commit = chance(rng, 20);
    in.run_level = chance(rng, 60) ? 0 : pick(rng, 0, 3);
    in.cur_valid = chance(rng, 50);
    in.walker_free = chance(rng, 70);
    const model::CpBuildOut o = ls.step(in);
    if (o.seg_pop) words.pop_front();
    conic_built += ptimer ? o.run_wr && (o.run_data >> 15 & 1) : o.cw_start && o.run_wr;
    pt_words += o.run_wr && o.run_data_pt != 0;
    // A flush or reset empties the segment queue: the next word is a header again.
    // So does a refused pattern in the core (its fault latches and flushes).
    if (in.flush || in.rst || o.fault) words.clear();
    built += o.run_wr;
    refused += o.fault;
    engine_moves += o.bank_we && o.bank_waddr > 0;
  }
  EXPECT_GT(built, 500u);
  EXPECT_GT(refused, 10u);
  EXPECT_GT(engine_moves, 10000u);
  EXPECT_EQ(pt_words > built / 2, ptimer) << "the run queue words' L, k, U";
  if (conic) {
    EXPECT_GT(conic_built, 100u) << "conics into the walker and the run queue";
  } else {
    EXPECT_EQ(conic_built, 0u);
  }
}

TEST(CorePartBuild, RandomSegmentsMatchTheModel) { build_traffic<BuildPort>(21, false); }
// With CONIC segments: their words into the walker once it is free (docs/CORE.md).
TEST(CorePartBuild, ConicSegmentsMatchTheModel) { build_traffic<BuildConicPort>(22, true); }
// The phase timer's build (with CONIC): each segment's length word into the run queue
// with its k and U, after its axes or its conic's words.
TEST(CorePartBuild, PhaseTimerBuildMatchesTheModel) { build_traffic<BuildPtimerPort>(23, true, true); }

// ---------------------------------------------------------------- cp_run
// With conic: conic run entries (bit 2N + 9, plane axes, some not axes), and the
// walker loaded with words of any bits (its walks are junk, so conic moves often meet
// a wrong end mark: CONIC_END). Whole conics that end right: the core's benches.
// With ptimer: the chunk queue carries the phase timer's words (random phases of
// every kind, now and then a random word), each run entry its moves U*2^k and its
// length per move.
template <class P>
void run_traffic(uint64_t seed, bool conic, bool ptimer = false) {
  Rng rng(seed);
  Lockstep<P> ls;
  ls.reset();
  model::CpRunIn in;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  uint64_t fires = 0, seg_done = 0, stretches = 0, underruns = 0, conic_faults = 0;
  uint64_t torch_edges = 0, lim_hits = 0, scaled_fires = 0;
  bool torch = false;
  // (The phase timer: twice the cycles, its moves being rarer: a clear leaves it
  // waiting for a phase from rest or one that loads r.)
  for (int c = 0; c < (ptimer ? 1000000 : 500000); ++c) {
    // The timer's scale (cp_feed): mostly 1, now and then held (0), slowed, sped up
    // to 2, or any value, for a while.
    if (pick(rng, 0, 1999) == 0) {
      const uint32_t k = pick(rng, 0, 9);
      in.scale = k <= 3 ? 0x10000 : k == 4 ? 0 : k <= 6 ? 0x20000 : pick(rng, 1, 0x20000);
    }
    // Limits: mostly none active; now and then one or two for a while.
    if (pick(rng, 0, 999) < 3) {
      in.lim_min = chance(rng, 90) ? 0 : pick(rng, 0, 7);
      in.lim_max = chance(rng, 90) ? 0 : pick(rng, 0, 7);
    }
    in.rst = pick(rng, 0, 9999) == 0;
    in.flush = pick(rng, 0, 999) < 5;
    in.estop = pick(rng, 0, 999) < 2;
    in.start = chance(rng, 5);
    in.stop = pick(rng, 0, 999) < 4;
    in.abort = pick(rng, 0, 999) < 2;
    if (chance(rng, 1)) in.fault = !in.fault;
    in.ch_valid = chance(rng, 70);
    const uint32_t add = chance(rng, 50) ? pick(rng, 0, 3) : uint32_t(-int32_t(pick(rng, 0, 3)));
    in.ch_head = {uint64_t(pick(rng, 1, 6)) << 48 | uint64_t(add & 0xFFFF) << 32 | pick(rng, 1, 12),
                  uint64_t(chance(rng, 30)) << 16 | (chance(rng, 70) ? 0 : pick(rng, 0, 0xFFFF)), 0, 0};
    if (ptimer) {
      // Phases as in the timer's own bench (tb/core/test_ptimer.cpp), shorter: steps of
      // about 2^50..2^54 against lengths of 2^42..2^50 (moves a clock to some tens apart).
      if (words.empty() && chance(rng, 20)) {
        const uint32_t kind = chance(rng, 50) ? 0 : uint32_t(pick(rng, 1, 15));
        const uint32_t ticks = chance(rng, 80) ? uint32_t(pick(rng, 1, 6)) : uint32_t(pick(rng, 7, 300));
        const int64_t u = int64_t(pick(rng, 0, 1u << 20)) - (1 << 19);
        const int64_t s = int64_t(rng() >> 10);
        const int64_t h = int64_t(rng() >> 28) - (int64_t{1} << 35);
        const uint64_t r_top = chance(rng, 80) ? uint64_t(-int64_t(rng() >> 5)) : rng();
        for (auto& w : phase_words(kind, ticks, u, r_top, s, h)) words.push_back(w);
      }
      in.ch_valid = !words.empty() && chance(rng, 90);
      const auto w = words.empty() || chance(rng, 1) ? std::pair<uint32_t, uint32_t>{pick(rng, 0, 7), uint32_t(rng())}
                                                      : words.front();
      in.ch_head = {uint64_t(w.first) << 32 | w.second | (rng() & ~uint64_t{0} << 35), rng(), 0, 0};
      // {L (Q2.30; 2^12 .. 2^20 mostly), k, U}
      const uint64_t len = chance(rng, 95) ? pick(rng, 1u << 12, 1u << 20) : uint64_t(uint32_t(rng()));
      in.run_head_pt = len << 28 | uint64_t(pick(rng, 0, 1)) << 24 | pick(rng, 1, 12);
    }
    in.run_valid = chance(rng, 60);
    in.run_head = pick(rng, 0, 511);  // {out, lane, end, moving, dir}
    in.run_level = pick(rng, 0, 2);
    in.segq_empty = chance(rng, 50);
    in.build_busy = chance(rng, 30);
    in.bank_we = chance(rng, 60);
    in.bank_axis = pick(rng, 0, 7);
    in.bank_waddr = pick(rng, 0, 31);
    in.bank_wbit = chance(rng, 50);
    in.bank_lane = chance(rng, 50);
    in.len_we = chance(rng, 15);
    in.len_m1 = pick(rng, 0, 31);
    in.pulse_ready = chance(rng, 70) ? 7 : pick(rng, 0, 7);
    if (conic) {
      const uint32_t au = pick(rng, 0, 3), av = pick(rng, 0, 3);
      if (chance(rng, 50)) in.run_head |= uint64_t(1) << 15 | uint64_t(au) << 12 | uint64_t(av) << 9;
      in.cw_wr = chance(rng, 20);
      in.cw_sel = pick(rng, 0, 7);
      in.cw_data = uint32_t(rng());
      if (in.cw_sel >= 5) in.cw_data = uint32_t(int32_t(pick(rng, 0, 8)) - 4);
      in.cw_start = pick(rng, 0, 999) < 15;
    }
    const model::CpRunOut o = ls.step(in);
    if (ptimer && o.ch_pop && !words.empty()) words.pop_front();
    scaled_fires += o.fire && in.scale != 0x10000;
    conic_faults += o.fault_conic;
    fires += o.fire;
    seg_done += o.seg_done;
    stretches += o.stretch;
    underruns += o.fault;
    torch_edges += o.torch != torch;
    torch = o.torch;
    lim_hits += o.lim_hit;
    if (o.lim_hit) {
      EXPECT_FALSE(o.fire) << "no move fires at a limit hit";
    }
  }
  EXPECT_GT(lim_hits, 100u) << "segments should run into active limits now and then";
  EXPECT_GT(scaled_fires, 1000u) << "moves should fire on scaled time too";
  EXPECT_GT(fires, 5000u);
  EXPECT_GT(torch_edges, 1000u) << "the torch output should follow the segments' out bits";
  EXPECT_GT(seg_done, conic ? 200u : 500u);
  EXPECT_GT(stretches, 1000u);
  std::printf("fires %llu, segments done %llu, stretched %llu, underruns %llu\n", (unsigned long long)fires,
              (unsigned long long)seg_done, (unsigned long long)stretches, (unsigned long long)underruns);
  EXPECT_GT(underruns, 10u);
  EXPECT_EQ(conic_faults > 0, conic) << conic_faults << " CONIC_END faults";
}

TEST(CorePartRun, RandomChunksAndSegmentsMatchTheModel) { run_traffic<RunPort>(31, false); }
// With the conic walker (IW = 36) and conic segments (docs/CORE.md "CONIC").
TEST(CorePartRun, ConicWalkerMatchesTheModel) { run_traffic<RunConicPort>(32, true); }
// Timed by the phase timer (PTIMER = 1; docs/PROTOCOL.md "Toward a compact wire").
TEST(CorePartRun, PhaseTimerMatchesTheModel) { run_traffic<RunPtimerPort>(33, false, true); }

// ---------------------------------------------------------------- cp_status
TEST(CorePartStatus, RandomRequestsMatchTheModel) {
  Rng rng(41);
  Lockstep<StatusPort> ls;
  ls.reset();
  model::CpStatusIn in;
  std::set<uint32_t> codes;
  uint64_t flushes = 0, cfg_changes = 0, trips = 0, trip_cycles = 0;
  model::CpStatusOut last;
  for (int c = 0; c < 300000; ++c) {
    in.rst = pick(rng, 0, 9999) == 0;
    in.estop = pick(rng, 0, 999) < 3;
    in.abort = pick(rng, 0, 999) < 3;
    in.clear = chance(rng, 3);
    in.ack = pick(rng, 0, 999) < 5;
    in.drivers_on = chance(rng, 3);
    in.drivers_off = chance(rng, 2);
    in.cfg_write = chance(rng, 5);
    in.cfg_word = 0x2u << 28 | pick(rng, 0, 4) << 24 | pick(rng, 0, 4) << 20 | pick(rng, 0, 0xFFFF);
    // The watchdog: a timeout of 0 (off) to 2 units of 4096 clocks set every 3,000
    // clocks or so, a kick one clock in 20,000 on average (so it runs out often).
    if (pick(rng, 0, 2999) == 0) {
      in.cfg_write = true;
      in.cfg_word = 0x2u << 28 | pick(rng, 0, 4) << 24 | 5u << 20 | (chance(rng, 80) ? pick(rng, 1, 2) : 0);
    }
    in.kick = pick(rng, 0, 19999) == 0;
    in.lim_hit = pick(rng, 0, 999) < 3;
    if (chance(rng, 2)) {
      in.lim_min = pick(rng, 0, 7);
      in.lim_max = pick(rng, 0, 7);
      in.probe = chance(rng, 50);
    }
    in.cmd_fault = chance(rng, 2);
    in.cmd_code = pick(rng, 0, 255);
    in.build_fault = pick(rng, 0, 999) < 5;
    in.run_fault = pick(rng, 0, 999) < 5;
    in.run_conic = chance(rng, 30);
    in.stretch = chance(rng, 5);
    in.fire = chance(rng, 30);
    in.seg_done = chance(rng, 5);
    in.seg_active = chance(rng, 70);
    in.running = chance(rng, 50);
    in.torch = chance(rng, 50);
    in.cur_valid = chance(rng, 50);
    in.segq = pick(rng, 0, 7);
    in.build_busy = chance(rng, 50);
    in.run_level = pick(rng, 0, 2);
    in.ch_level = pick(rng, 0, 9);
    for (unsigned a = 0; a < 3; ++a) in.position[a] = rng() & ((uint64_t(1) << 40) - 1);
    // READ every register there is, and some that are not.
    in.feed = uint32_t(c) * 2654435761u;  // (not from rng: the sequence of the rest stays)
    in.override = uint32_t(c) & 0xFFFF;
    in.rd_addr0 = chance(rng, 50) ? pick(rng, 0, 0x2B) : pick(rng, 0, 255);
    in.rd_addr1 = chance(rng, 50) ? pick(rng, 0, 0x2B) : pick(rng, 0, 255);
    const model::CpStatusOut o = ls.step(in);
    if (o.fault) codes.insert(o.err);
    flushes += o.flush;
    trips += o.wd_trip && !last.wd_trip;
    trip_cycles += o.wd_trip;
    if (last.wd_trip) {
      EXPECT_FALSE(o.enable) << "a tripped watchdog holds the drivers off";
    }
    if (c > 0 && o.cfg != last.cfg) ++cfg_changes;
    last = o;
  }
  for (uint32_t code : {8u, 9u, 10u, 11u}) EXPECT_TRUE(codes.count(code)) << "code " << code;
  EXPECT_GT(codes.size(), 50u) << "the parser's codes pass through";
  EXPECT_GT(flushes, 1000u);
  EXPECT_GT(cfg_changes, 1000u);
  EXPECT_GT(trips, 5u) << "the watchdog should run out now and then";
  EXPECT_GT(trip_cycles, 1000u);
  EXPECT_TRUE(codes.count(19)) << "WATCHDOG latched";
  EXPECT_TRUE(codes.count(20)) << "LIMIT latched";
}

// ---------------------------------------------------------------- cp_feed
// Random HOLD / RESUME / OVERRIDE (values past 2 included) and random ramp tick
// periods (CONFIG field 9) against the model.
TEST(CorePartFeed, RandomCommandsAndRampsMatchTheModel) {
  Rng rng(71);
  Lockstep<FeedPort> ls;
  ls.reset();
  model::CpFeedIn in;
  uint64_t moving = 0, holds_reached = 0;
  model::CpFeedOut last;
  for (int c = 0; c < 1000000; ++c) {
    in.rst = pick(rng, 0, 499999) == 0;
    in.cfg_write = pick(rng, 0, 49999) == 0;
    const uint32_t field = pick(rng, 8, 12);
    in.cfg_word = 0x2u << 28 | field << 20 | pick(rng, 0, 3);
    in.hold = pick(rng, 0, 39999) == 0;
    in.resume = pick(rng, 0, 39999) == 0;
    in.ovr = pick(rng, 0, 39999) == 0;
    in.ovr_val = chance(rng, 10) ? pick(rng, 0x8000, 0xFFFF) : pick(rng, 0, 0x8000);
    const model::CpFeedOut o = ls.step(in);
    moving += o.scale != last.scale;
    holds_reached += (o.feed >> 30 & 1) && (o.feed >> 31) && !((last.feed >> 30 & 1) && (last.feed >> 31));
    last = o;
  }
  EXPECT_GT(moving, 10000u);
  EXPECT_GT(holds_reached, 3u);
}

namespace {
// The ramp's contract, checked on the model clocked through a run of targets, each
// from rest (docs/CORE.md "Feed hold and override"): s moves only at a tick; toward
// its target, never past it; at a rate of at most |D| / (e·2^10) a tick and a change
// of rate of at most |D| / 2^20 a tick (D the target's step; a unit of rounding
// each); it arrives on the target exactly. Returns the ticks each target took.
std::vector<uint64_t> check_ramp(uint32_t period, const std::vector<uint32_t>& overrides_q14, bool hold_first) {
  model::CpFeed f;
  const auto clock = [&](model::CpFeedIn i) {
    f.in = i;
    f.tick();
  };
  model::CpFeedIn cfg;
  cfg.cfg_write = true;
  cfg.cfg_word = 0x2u << 28 | 9u << 20 | period;
  clock(cfg);
  std::vector<uint64_t> ticks_taken;
  std::vector<uint32_t> targets;
  if (hold_first) targets.push_back(0);
  for (uint32_t v : overrides_q14) targets.push_back(v << 16);
  for (size_t t = 0; t < targets.size(); ++t) {
    model::CpFeedIn cmd;
    if (hold_first && t == 0) {
      cmd.hold = true;
    } else {
      cmd.resume = true;
      cmd.ovr = true;
      cmd.ovr_val = overrides_q14[t - (hold_first ? 1 : 0)];
    }
    const uint32_t from = f.s();
    clock(cmd);
    const double span = std::abs(double(targets[t]) - double(from));
    // (The discrete stages' peaks come within 1 % of the continuous ramp's.)
    const double max_rate = 1.01 * span / (std::exp(1.0) * 1024) + 2,
                 max_change = 1.01 * span / (1024.0 * 1024) + 2;
    int64_t rate = 0;
    uint32_t s = f.s();
    uint64_t ticks = 0;
    for (uint64_t c = 0; c < 50'000'000 && !(f.s() == targets[t] && f.u() == targets[t]); ++c) {
      const bool tick = f.tick_now();
      clock({});
      if (!tick) {
        EXPECT_EQ(f.s(), s) << "s moves only at a tick";
        continue;
      }
      ++ticks;
      const int64_t r = int64_t(f.s()) - int64_t(s);
      // The last step may take what is left (within 2^10 units of rounding).
      if (f.s() != targets[t]) {
        EXPECT_LE(double(std::llabs(r)), max_rate) << "tick " << ticks;
        EXPECT_LE(double(std::llabs(r - rate)), max_change) << "tick " << ticks;
      }
      EXPECT_LE(std::abs(double(targets[t]) - double(f.s())), std::abs(double(targets[t]) - double(s)))
          << "toward the target, never past it";
      EXPECT_LE(std::min<double>(from, targets[t]), double(f.s()));
      EXPECT_LE(double(f.s()), std::max<double>(from, targets[t]));
      rate = r;
      s = f.s();
      if (::testing::Test::HasFailure()) return ticks_taken;
    }
    EXPECT_EQ(f.s(), targets[t]) << "target " << t;
    ticks_taken.push_back(ticks);
  }
  return ticks_taken;
}
}  // namespace

TEST(CorePartFeed, TheRampKeepsItsLimitsAndArrivesExactly) {
  // Hold from 1, resume to 1, 50 %, 200 %, 10 %, 120 %, a tick every clock and every 7.
  for (uint32_t period : {0u, 7u}) {
    const std::vector<uint64_t> ticks = check_ramp(period, {0x4000, 0x2000, 0x8000, 0x0666, 0x4CCC}, true);
    ASSERT_FALSE(::testing::Test::HasFailure()) << "period " << period;
    // From 1 to 0: (1 + x) e^-x falls to 2^-20 (the last stage's snap) at x = 16.9, in
    // units of 2^10 ticks, and a few ticks of rounding.
    EXPECT_GE(ticks[0], 16u * 1024);
    EXPECT_LE(ticks[0], 19u * 1024);
  }
}

// ---------------------------------------------------------------- cp_inputs
// Random pins (levels held for random spans, glitches of a clock or a few), random
// CONFIG of the filter (fields 6), the limits (7), the probe (8) and the seek (10),
// the run switching on and off and limit hits at random; the seek trips counted.
TEST(CorePartInputs, RandomPinsAndConfigurationMatchTheModel) {
  Rng rng(61);
  Lockstep<InputsPort> ls;
  ls.reset();
  model::CpInputsIn in;
  uint64_t changes = 0, trips = 0, stops = 0;
  model::CpInputsOut last;
  for (int c = 0; c < 300000; ++c) {
    in.rst = pick(rng, 0, 49999) == 0;
    if (pick(rng, 0, 99) < 3) {
      in.lim_min ^= 1u << pick(rng, 0, 2);
      in.lim_max ^= chance(rng, 50) ? 1u << pick(rng, 0, 2) : 0;
      in.probe = chance(rng, 50) ? !in.probe : in.probe;
    }
    if (pick(rng, 0, 99) < 2) in.running = !in.running;
    in.lim_hit = in.running && pick(rng, 0, 199) == 0;
    in.cfg_write = !in.running && pick(rng, 0, 999) < 3;
    const uint32_t field = pick(rng, 6, 10);
    const uint32_t value = field == 6 ? pick(rng, 0, 6) : pick(rng, 0, 15);
    in.cfg_word = 0x2u << 28 | pick(rng, 0, 3) << 24 | field << 20 | value;
    const model::CpInputsOut o = ls.step(in);
    changes += !(o == last);
    trips += (o.seek & 4) && !(last.seek & 4);
    stops += o.seek_stop && in.running;
    last = o;
  }
  EXPECT_GT(changes, 500u);
  EXPECT_GT(trips, 20u) << "the seek tripped";
  EXPECT_GT(stops, 20u);
}

// The seek against the documented rule: mode 1 trips on the probe while the run is
// on (and holds the run off while it is not), mode 2 on the probe's loss, mode 3 on
// a limit hit only; a trip disarms and sets `tripped`; field 10 clears it.
TEST(CorePartInputs, TheSeekTripsOnceAndDisarms) {
  Lockstep<InputsPort> ls;
  ls.reset();
  model::CpInputsIn in;
  const auto config = [&](uint32_t field, uint32_t value) {
    in.cfg_write = true;
    in.cfg_word = 0x2u << 28 | field << 20 | value;
    ls.step(in);
    in.cfg_write = false;
  };
  const auto settle = [&] {
    model::CpInputsOut o;
    for (int c = 0; c < 6; ++c) o = ls.step(in);  // P = 0: three samples and the level
    return o;
  };
  config(10, 1);  // probe contact
  model::CpInputsOut o = settle();
  EXPECT_EQ(o.seek, 1u);
  EXPECT_FALSE(o.seek_stop);
  in.probe = true;  // active high (reset)
  o = settle();
  EXPECT_TRUE(o.seek_stop) << "armed and in contact: the run is held off";
  EXPECT_EQ(o.seek, 1u) << "no trip while the run is off";
  in.running = true;
  o = ls.step(in);
  EXPECT_EQ(o.seek, 1u);
  o = ls.step(in);
  EXPECT_EQ(o.seek, 4u) << "tripped, disarmed";
  EXPECT_FALSE(o.seek_stop);
  in.running = false;
  config(10, 2);  // contact lost
  o = settle();
  EXPECT_EQ(o.seek, 2u) << "field 10 clears tripped";
  in.running = true;
  for (int c = 0; c < 10; ++c) EXPECT_EQ(ls.step(in).seek, 2u) << "in contact: no trip";
  in.probe = false;
  o = settle();
  EXPECT_EQ(o.seek, 4u);
  in.running = false;
  config(10, 3);  // a limit hit
  in.running = true;
  in.probe = true;
  o = settle();
  EXPECT_TRUE(o.seek_lim);
  EXPECT_FALSE(o.seek_stop) << "mode 3 does not look at the probe";
  EXPECT_EQ(o.seek, 3u);
  in.lim_hit = true;
  ls.step(in);
  in.lim_hit = false;
  o = ls.step(in);
  EXPECT_EQ(o.seek, 4u);
  EXPECT_FALSE(o.seek_lim);
}

// The filter against the documented rule, on the RTL's pins alone: with P = 4 a
// pulse of 7 clocks (shorter than two sample periods) never passes; one of 13 (three
// periods and more) does, within 3P clocks; active low and disabled as configured.
TEST(CorePartInputs, TheFilterPassesWhatStaysThreeSamples) {
  Lockstep<InputsPort> ls;
  ls.reset();
  model::CpInputsIn in;
  const auto config = [&](uint32_t axis, uint32_t field, uint32_t value) {
    in.cfg_write = true;
    in.cfg_word = 0x2u << 28 | axis << 24 | field << 20 | value;
    ls.step(in);
    in.cfg_write = false;
  };
  config(0, 6, 4);                 // P = 4
  config(1, 7, 0b1100);            // axis 1: min and max enabled, active low
  config(0, 7, 0b0101);            // axis 0: min enabled, active high; max disabled
  in.lim_min = 0b010;              // axis 1's min pin high: inactive (active low)
  in.lim_max = 0b010;
  for (int c = 0; c < 40; ++c) ls.step(in);
  model::CpInputsOut o = ls.step(in);
  EXPECT_EQ(o.lim_min, 0u);
  EXPECT_EQ(o.lim_max, 0u);
  // A 7-clock pulse on axis 0's min: never seen.
  in.lim_min |= 1;
  for (int c = 0; c < 7; ++c) EXPECT_EQ(ls.step(in).lim_min & 1, 0u) << c;
  in.lim_min &= ~1u;
  for (int c = 0; c < 20; ++c) EXPECT_EQ(ls.step(in).lim_min & 1, 0u) << c;
  // A 13-clock one: seen within 3P = 12 clocks, and gone within 3P after it ends.
  in.lim_min |= 1;
  int seen = -1;
  for (int c = 0; c < 13; ++c)
    if ((ls.step(in).lim_min & 1) && seen < 0) seen = c;
  EXPECT_GE(seen, 8) << "not before two sample periods";
  EXPECT_LE(seen, 12);
  in.lim_min &= ~1u;
  int gone = -1;
  for (int c = 0; c < 14; ++c)
    if (!(ls.step(in).lim_min & 1) && gone < 0) gone = c;
  EXPECT_GE(gone, 0);
  EXPECT_LE(gone, 12);
  // Axis 1's max, active low: the pin going low is active; axis 0's max never (disabled).
  in.lim_max = 0b001;
  for (int c = 0; c < 16; ++c) o = ls.step(in);
  EXPECT_EQ(o.lim_max, 0b010u);
}

// The priority encoder's order, written out from docs/CORE.md "Faults": E-stop,
// abort, watchdog, limit, underrun, pattern, the parser's code; nothing raised, nothing set.
TEST(CorePartStatus, FaultPriorityIsTheDocumentedOrder) {
  for (unsigned m = 0; m < 128; ++m) {
    const bool estop = m & 1, abort = m & 2, underrun = m & 4, pattern = m & 8, cmd = m & 16, wd = m & 32,
               limit = m & 64;
    const model::FaultPick f = model::pick_fault(estop, abort, wd, limit, underrun, pattern, cmd, 6);
    const uint32_t want =
        estop ? 10 : abort ? 11 : wd ? 19 : limit ? 20 : underrun ? 9 : pattern ? 8 : cmd ? 6 : 0;
    EXPECT_EQ(f.set, m != 0) << m;
    EXPECT_EQ(f.code, want) << m;
  }
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The motion core's bit-serial conic walker (rtl/cp_conic_serial.v, docs/CONIC.md
// "The walk, bit-serial") in lockstep with its model, every output every cycle, and
// its moves against the rule's walk (model::CpConic::rule, itself held to the
// one-move-a-clock engine by test_conic): circles over every octant, other conics,
// large circles, the pass timing, words while busy, clear, and a random soak of the
// narrow build, whose values wrap. With the length rule's divider (LEN = 1): every
// move's length against the rule's definition, evaluated here from the conic, not
// from the walker's recurrences.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "conic_random.h"
#include "conic_serial_port.h"

namespace cpstep::tb {
namespace {

using Serial = model::CpConicSerial;

struct SerialRun {
  std::vector<std::pair<int, int>> moves;
  std::vector<uint64_t> valid_at;  // the first cycle each move was valid
  uint64_t load_cycle = 0;
  bool ended = false;              // the last move taken carried move_end
  bool end_early = false;          // some earlier move carried it
  bool busy_after = true;          // busy the cycle after the end move was taken
};

// Loads the walk of `rq` (its start node's G and gradient, the end's offset) and
// takes moves, each cycle with probability ready_pct %, until the one marked as
// arriving at the end, or max_moves. With `cont` the walk goes on from where the
// last one ended (rq.start): only the end's offset is written, the start with cont.
template <class Stepper>
SerialRun run_serial(Stepper& dut, const ConicRequest& rq, unsigned ready_pct, std::mt19937_64& rng,
                     size_t max_moves, bool cont = false) {
  const unsigned iw = dut.model().params().iw;
  const auto k = rq.coeffs();
  const auto n = model::CpConic::at(k, rq.start.x, rq.start.y);
  const auto words = Serial::words(k, n, rq.cw, rq.end.x - rq.start.x, rq.end.y - rq.start.y);
  model::CpConicSerialIn in;
  SerialRun run;
  // The seven words (a continuation: the last two), the last with the start.
  for (unsigned w = cont ? 5 : 0; w < 7; ++w) {
    in.wr = true;
    in.wr_sel = w;
    in.wr_data = words[w];
    in.start = w == 6;
    in.cont = cont && in.start;
    if (in.start) run.load_cycle = dut.cycle();
    dut.step(in);
  }
  in.wr = in.start = in.cont = false;
  StreamContract contract("move stream");
  std::uniform_int_distribution<unsigned> pct(0, 99);
  bool fresh = true;
  const uint64_t limit = (max_moves + 2) * (iw + 2) * (ready_pct >= 100 ? 1 : 20) + 100;
  for (uint64_t c = 0; c < limit; ++c) {
    in.move_ready = ready_pct >= 100 || pct(rng) < ready_pct;
    const uint64_t cycle = dut.cycle();
    const model::CpConicSerialOut o = dut.step(in);
    contract.check(cycle, o.move_valid, in.move_ready,
                   uint64_t(o.move_dx & 3) << 2 | uint64_t(o.move_dy & 3) | uint64_t(o.move_end) << 4);
    if (!o.move_valid && (o.move_dx || o.move_dy || o.move_end))
      ADD_FAILURE() << "move outputs not zero while not valid at cycle " << cycle;
    if (o.move_valid && fresh) {
      run.valid_at.push_back(cycle);
      fresh = false;
    }
    if (o.move_valid && in.move_ready) {
      fresh = true;
      run.moves.push_back({o.move_dx, o.move_dy});
      if (o.move_end) {
        run.ended = true;
        in.move_ready = false;
        run.busy_after = dut.step(in).busy;
        break;
      }
      if (run.moves.size() >= max_moves) break;
    }
  }
  return run;
}

// The rule's walk from rq.start to the first arrival at rq.end, as moves; every node
// checked to fit the walker's width.
std::vector<std::pair<int, int>> expected_moves(const ConicRequest& rq, size_t max_moves, unsigned iw) {
  const std::vector<Node> nodes = walk(rq, rq.end, max_moves);
  std::vector<std::pair<int, int>> moves;
  Node p = rq.start;
  const auto k = rq.coeffs();
  for (const Node& q : nodes) {
    EXPECT_TRUE(Serial::fits(k, model::CpConic::at(k, p.x, p.y), iw)) << "node (" << p.x << ", " << p.y << ")";
    moves.push_back({int(q.x - p.x), int(q.y - p.y)});
    p = q;
  }
  return moves;
}

// One walk in lockstep, judged: the rule's moves, the end marked on the last only,
// the walker idle after it. A walk the rule never brings to its end (the open loops
// of radius about 1, docs/CONIC.md "Below one step") is judged on its first
// max_moves moves, none marked.
template <class P>
void expect_walk(Lockstep<P>& ls, const ConicRequest& rq, unsigned ready_pct, std::mt19937_64& rng,
                 size_t max_moves, const std::string& what) {
  const auto want = expected_moves(rq, max_moves, ls.model().params().iw);
  ASSERT_FALSE(want.empty()) << what;
  Node p = rq.start;
  for (const auto& m : want) p = {p.x + m.first, p.y + m.second};
  const bool reached = p == rq.end;
  const SerialRun run = run_serial(ls, rq, ready_pct, rng, want.size());
  EXPECT_EQ(run.moves, want) << what;
  EXPECT_EQ(run.ended, reached) << what << (reached ? ": the last move does not carry move_end" : ": an end marked");
  if (reached) {
    EXPECT_FALSE(run.busy_after) << what << ": still busy after the end";
  }
  if (!reached) ls.step({.clear = true});
}

// Quarter-grid circle (centre (p/4, q/4), radius s/4) scaled by 16, as conic_bench's.
ConicRequest circle_from(int p, int q, int s, bool cw, long double angle, size_t moves_on) {
  ConicRequest rq = circle(p, q, s, cw);
  const long double r = s / 4.0L;
  rq.start = nearest_node(rq.conic(), p / 4.0L + r * std::cos(angle), q / 4.0L + r * std::sin(angle));
  const std::vector<Node> nodes = walk(rq, {INT64_MAX, INT64_MAX}, moves_on);
  rq.end = nodes.back();
  return rq;
}

TEST(ConicSerial, CirclesEveryOctantMatchTheRuleInLockstep) {
  Lockstep<ConicSerialDefault> ls;
  ls.reset();
  std::mt19937_64 rng(seed_from_env());
  size_t walks = 0, moves = 0;
  for (int s : {4, 5, 7, 9, 13, 23, 40, 101, 257})
    for (int p : {0, 1, 2})
      for (int q : {0, 3})
        for (int oct = 0; oct < 8; ++oct)
          for (bool cw : {false, true}) {
            const long double angle = (oct + 0.5L) * M_PI / 4;
            // Most of a turn, or a whole one (end = start).
            const size_t full = size_t(std::ceil(s / 4.0 * 4 * std::sqrt(2.0))) + 8;
            const size_t on = (oct % 3 == 0) ? full * 4 : 1 + rng() % full;
            ConicRequest rq = circle_from(p, q, s, cw, angle, on);
            if (oct % 3 == 0) rq.end = rq.start;
            // Always ready, ready now and then, or a consumer slower than a pass
            // (the next move is decided and waits behind the one presented).
            const unsigned ready = (oct % 4 == 1) ? 100 : (oct % 4 == 3) ? 2 : 55;
            expect_walk(ls, rq, ready, rng, 8 * full,
                        "circle s=" + std::to_string(s) + " centre (" + std::to_string(p) + "/4, " +
                            std::to_string(q) + "/4) octant " + std::to_string(oct) + (cw ? " cw" : " ccw"));
            ++walks;
            moves += expected_moves(rq, 8 * full, 40).size();
            if (HasFailure()) return;
          }
  std::printf("circles: %zu walks, %zu moves, RTL = model = the rule\n", walks, moves);
}

TEST(ConicSerial, OtherConicsMatchTheRuleInLockstep) {
  Lockstep<ConicSerialDefault> ls;
  ls.reset();
  std::mt19937_64 rng(seed_from_env() + 1);
  for (Family f : {Family::ellipse, Family::rotated_ellipse, Family::parabola, Family::hyperbola})
    for (int i = 0; i < 6; ++i) {
      const ConicRequest rq = random_conic(f, rng, 300);
      expect_walk(ls, rq, 80, rng, 400, std::string(family_name(f)) + " #" + std::to_string(i));
      if (HasFailure()) return;
    }
}

// Circles of up to 20,000 steps at the host's scale (A = C = 256: centres on the
// 1/16-step grid), an arc of 1,500 moves from each of four starts.
TEST(ConicSerial, LargeCirclesAtTheHostsScale) {
  Lockstep<ConicSerialDefault> ls;
  ls.reset();
  std::mt19937_64 rng(seed_from_env() + 2);
  for (int64_t r : {300, 4000, 20000})
    for (int quarter = 0; quarter < 4; ++quarter) {
      ConicRequest rq;
      const int64_t cx16 = 5, cy16 = -11;  // centre (5/16, -11/16)
      rq.a = 256;
      rq.c = 256;
      rq.d = -32 * cx16;
      rq.e = -32 * cy16;
      rq.f = cx16 * cx16 + cy16 * cy16 - 256 * r * r;
      rq.cw = quarter & 1;
      const long double angle = quarter * M_PI / 2 + 0.3L;
      rq.start = nearest_node(rq.conic(), cx16 / 16.0L + r * std::cos(angle), cy16 / 16.0L + r * std::sin(angle));
      rq.end = walk(rq, {INT64_MAX, INT64_MAX}, 1500).back();
      expect_walk(ls, rq, 100, rng, 1500, "radius " + std::to_string(r));
      if (HasFailure()) return;
    }
}

// docs/CONIC.md "The walk, bit-serial": the first move is valid IW + 2 cycles after
// the start's cycle, and with the consumer always ready every IW + 1 cycles after.
// A walk in pieces, each after the first started with cont and only its end's
// offset written: the moves are the whole walk's, in lockstep (H0[18] of a CONIC,
// docs/CORE.md: the walker keeps the last walk's coefficients, node and last move).
TEST(ConicSerial, ContinuationsWalkOnFromTheLastEnd) {
  Lockstep<ConicSerialDefault> ls("conic_serial_cont");
  std::mt19937_64 rng(33);
  std::uniform_int_distribution<int> pick(0, 1 << 20);
  for (int t = 0; t < 40; ++t) {
    const int s = 8 + pick(rng) % 400;
    ConicRequest rq = circle_from(pick(rng) % 64 - 32, pick(rng) % 64 - 32, s, t % 2 == 1,
                                  (pick(rng) % 6283) / 1000.0L, 40 + pick(rng) % 900);
    const auto want = expected_moves(rq, 100000, 40);
    ASSERT_GE(want.size(), 3u);
    // Two or three pieces, cut at random moves.
    std::vector<size_t> cuts{size_t(1 + pick(rng) % (want.size() - 1))};
    if (t % 3 == 0 && cuts[0] + 1 < want.size()) cuts.push_back(cuts[0] + 1 + pick(rng) % (want.size() - cuts[0] - 1));
    cuts.push_back(want.size());
    std::vector<std::pair<int, int>> got;
    Node at = rq.start;
    size_t from = 0;
    for (size_t c = 0; c < cuts.size(); ++c) {
      Node to = at;
      for (size_t j = from; j < cuts[c]; ++j) to = {to.x + want[j].first, to.y + want[j].second};
      ConicRequest piece = rq;
      piece.start = at;
      piece.end = to;
      const SerialRun run = run_serial(ls, piece, 50 + pick(rng) % 51, rng, cuts[c] - from, c > 0);
      EXPECT_TRUE(run.ended) << "piece " << c << " of walk " << t;
      got.insert(got.end(), run.moves.begin(), run.moves.end());
      at = to;
      from = cuts[c];
    }
    EXPECT_EQ(got, want) << "walk " << t;
  }
}

TEST(ConicSerial, AMoveEveryIwPlusOneCycles) {
  Lockstep<ConicSerialDefault> ls;
  ls.reset();
  std::mt19937_64 rng(7);
  ConicRequest rq = circle_from(0, 0, 80, false, 0.1L, 30);
  const SerialRun run = run_serial(ls, rq, 100, rng, 100);
  ASSERT_TRUE(run.ended);
  ASSERT_GE(run.valid_at.size(), 20u);
  EXPECT_EQ(run.valid_at[0] - run.load_cycle, 40u + 2);
  for (size_t i = 1; i < run.valid_at.size(); ++i)
    EXPECT_EQ(run.valid_at[i] - run.valid_at[i - 1], 40u + 1) << "move " << i;
}

// Words written while the walker is busy are not taken: the walk goes on as it was.
// Clear drops a waiting move and stops the walk; a fresh walk follows.
TEST(ConicSerial, WordsWhileBusyAreIgnoredAndClearStops) {
  Lockstep<ConicSerialDefault> ls;
  ls.reset();
  std::mt19937_64 rng(8);
  const ConicRequest rq = circle_from(2, 1, 60, true, 1.0L, 40);
  const auto want = expected_moves(rq, 100, 40);
  SerialRun run = run_serial(ls, rq, 100, rng, 5);
  ASSERT_EQ(run.moves.size(), 5u);
  model::CpConicSerialIn in;
  for (unsigned w = 0; w < 7; ++w) {  // junk, while a pass runs or its move waits
    in.wr = true;
    in.wr_sel = w;
    in.wr_data = uint32_t(rng());
    ASSERT_TRUE(ls.step(in).busy);
  }
  in.wr = false;
  in.move_ready = true;
  for (int c = 0; c < 100 * 42 && run.moves.size() < want.size(); ++c) {
    const auto o = ls.step(in);
    if (o.move_valid) run.moves.push_back({o.move_dx, o.move_dy});
  }
  EXPECT_EQ(run.moves, want);
  // A walk, five moves in, a move waiting; then clear.
  run = run_serial(ls, rq, 100, rng, 5);
  ASSERT_EQ(run.moves.size(), 5u);
  in.move_ready = false;
  for (int i = 0; i < 60; ++i) ls.step(in);
  in.clear = true;
  ls.step(in);
  in.clear = false;
  const auto o = ls.step(in);
  EXPECT_FALSE(o.move_valid);
  EXPECT_FALSE(o.busy);
  for (int i = 0; i < 100; ++i) EXPECT_FALSE(ls.step(in).move_valid);
  expect_walk(ls, rq, 70, rng, 100, "after a clear");
}

// The narrow build (QW 6, IW 12, XW 8) under random words of any bits, starts, clears,
// resets and back-pressure: its values wrap, and RTL and model agree every cycle.
TEST(ConicSerial, NarrowBuildRandomSoakInLockstep) {
  Lockstep<ConicSerialSmall> ls;
  ls.reset();
  std::mt19937_64 rng(seed_from_env() + 3);
  std::uniform_int_distribution<unsigned> pct(0, 999);
  std::uniform_int_distribution<int64_t> any(INT64_MIN, INT64_MAX);
  model::CpConicSerialIn in;
  uint64_t moves = 0, ends = 0;
  bool slow = false;
  for (int c = 0; c < 400000; ++c) {
    const unsigned r = pct(rng);
    in.rst = r < 1;
    in.clear = r >= 1 && r < 4;
    in.start = r >= 4 && r < 12;
    // Words of any bits, often (most are refused while the walker is busy); the end
    // offsets small, so that walks end.
    in.wr = pct(rng) < 300;
    in.wr_sel = unsigned(rng() % 8);
    in.wr_data = uint32_t(any(rng));
    if (in.wr_sel >= 5) in.wr_data = uint32_t(int32_t(any(rng) % 6));
    // Stretches of a consumer slower than a pass (IW = 12 clocks) between fast ones.
    if (c % 64 == 0) slow = pct(rng) < 400;
    in.move_ready = pct(rng) < (slow ? 30u : 700u);
    const auto o = ls.step(in);
    if (o.move_valid && in.move_ready) {
      ++moves;
      ends += o.move_end;
    }
  }
  EXPECT_GT(moves, 10000u);
  EXPECT_GT(ends, 50u);
  std::printf("narrow build: %llu moves taken, %llu ends\n", (unsigned long long)moves, (unsigned long long)ends);
}

// The length rule (docs/CONIC.md "The length rule"): move j's length is
// floor(K 2^S / m), m the larger of |dG/dx| and |dG/dy| at the node the move
// leaves, saturated to 2^32 - 1 (m = 0 included). Evaluated from the conic here.
uint32_t rule_length(const ConicRequest& rq, const Node& p, uint32_t ks) {
  __extension__ typedef unsigned __int128 u128;
  const int64_t gx = 2 * rq.a * p.x + rq.b * p.y + rq.d, gy = rq.b * p.x + 2 * rq.c * p.y + rq.e;
  const u128 m = u128(std::max(std::abs(gx), std::abs(gy)));
  const u128 full = 0xFFFFFFFFu;
  if (m == 0) return uint32_t(full);
  const u128 q = (u128(ks & ((1u << 27) - 1)) << (ks >> 27)) / m;
  return uint32_t(std::min(q, full));
}

// One walk on the LEN walker, its {S, K} on len_k and its segment loaded (len_go)
// from `go_after` cycles after the start, and every cycle a move is presented, its
// length checked against the rule. Returns the moves taken.
struct LenRun {
  std::vector<std::pair<int, int>> moves;
  uint64_t lengths_checked = 0, saturated = 0;
  std::vector<uint64_t> valid_at;
  uint64_t load_cycle = 0;
};
LenRun run_len(Lockstep<ConicSerialLen>& ls, const ConicRequest& rq, uint32_t ks, unsigned ready_pct,
               std::mt19937_64& rng, const std::vector<std::pair<int, int>>& want, unsigned go_after = 0) {
  const auto k = rq.coeffs();
  const auto n = model::CpConic::at(k, rq.start.x, rq.start.y);
  const auto words = Serial::words(k, n, rq.cw, rq.end.x - rq.start.x, rq.end.y - rq.start.y);
  // The rule's length of every move, from the nodes the walk leaves.
  std::vector<uint32_t> len;
  Node p = rq.start;
  for (const auto& m : want) {
    len.push_back(rule_length(rq, p, ks));
    p = {p.x + m.first, p.y + m.second};
  }
  LenRun run;
  model::CpConicSerialIn in;
  in.len_k = ks;
  for (unsigned w = 0; w < 7; ++w) {
    in.wr = true;
    in.wr_sel = w;
    in.wr_data = words[w];
    in.start = w == 6;
    if (in.start) run.load_cycle = ls.cycle();
    ls.step(in);
  }
  in.wr = in.start = false;
  std::uniform_int_distribution<unsigned> pct(0, 99);
  bool fresh = true;
  for (uint64_t c = 0; c < (want.size() + 2) * 120 * (ready_pct >= 100 ? 1 : 100) && run.moves.size() < want.size();
       ++c) {
    in.move_ready = ready_pct >= 100 || pct(rng) < ready_pct;
    in.len_go = ls.cycle() - run.load_cycle > go_after;
    const model::CpConicSerialOut o = ls.step(in);
    const size_t j = run.moves.size();   // the move presented, or the next to be
    if (o.move_valid && fresh) {
      run.valid_at.push_back(ls.cycle() - 1);
      fresh = false;
    }
    if (o.move_valid) {
      EXPECT_EQ(o.len, len[j]) << "move " << j << " at cycle " << ls.cycle() - 1;
      ++run.lengths_checked;
    }
    if (o.move_valid && in.move_ready) {
      run.moves.push_back({o.move_dx, o.move_dy});
      fresh = true;
    }
    if (::testing::Test::HasFailure()) break;
  }
  for (uint32_t l : len) run.saturated += l == 0xFFFFFFFFu;
  return run;
}

// Circles at the host's scale and on the quarter grid, and ellipses (rotated ones
// among them), each with a {S, K} of its own, the consumer always ready, at random or
// slow: the walk's moves are the rule's, and every presented move's length is
// K 2^S / m, in lockstep (len_o every cycle).
TEST(ConicSerial, LenEveryMovesLengthIsTheRules) {
  Lockstep<ConicSerialLen> ls("conic_serial_len");
  ls.reset();
  std::mt19937_64 rng(seed_from_env() + 5);
  std::uniform_int_distribution<int> pick(0, 1 << 20);
  uint64_t checked = 0, saturated = 0, walks = 0;
  for (int t = 0; t < 60; ++t) {
    ConicRequest rq;
    if (t % 3 == 0) {   // the host's scale: A = C = 256, the centre on the 1/16 grid
      const int64_t r = 50 + pick(rng) % 30000, cx16 = pick(rng) % 32 - 16, cy16 = pick(rng) % 32 - 16;
      rq.a = rq.c = 256;
      rq.d = -32 * cx16;
      rq.e = -32 * cy16;
      rq.f = cx16 * cx16 + cy16 * cy16 - 256 * r * r;
      rq.cw = t % 2 == 1;
      const long double angle = (pick(rng) % 6283) / 1000.0L;
      rq.start = nearest_node(rq.conic(), cx16 / 16.0L + r * std::cos(angle), cy16 / 16.0L + r * std::sin(angle));
      rq.end = walk(rq, {INT64_MAX, INT64_MAX}, 300 + pick(rng) % 900).back();
    } else if (t % 3 == 1) {
      rq = circle_from(pick(rng) % 64 - 32, pick(rng) % 64 - 32, 8 + pick(rng) % 600, t % 2 == 1,
                       (pick(rng) % 6283) / 1000.0L, 40 + pick(rng) % 900);
    } else {   // an ellipse, rotated when b != 0: 4x^2 + bxy + 9y^2 = r^2 scaled
      rq.a = 4 + pick(rng) % 5;
      rq.c = 9 + pick(rng) % 7;
      rq.b = (t % 4 == 2) ? pick(rng) % 7 - 3 : 0;
      const int64_t r2 = 200 + pick(rng) % 40000;
      rq.f = -r2;
      rq.cw = t % 2 == 0;
      const long double x0 = std::sqrt((long double)r2 / rq.a);
      rq.start = nearest_node(rq.conic(), x0, 0);
      rq.end = walk(rq, {INT64_MAX, INT64_MAX}, 50 + pick(rng) % 400).back();
    }
    const auto want = expected_moves(rq, 100000, 40);
    if (want.empty()) continue;
    // K of 27 bits, S anywhere; now and then one that saturates.
    const uint32_t kk = uint32_t((1u << 26) + pick(rng) % (1 << 26));
    const uint32_t ss = t % 7 == 3 ? 31 : uint32_t(pick(rng) % 24);
    // The consumer: always ready, at random, or slower than a pass and a division (a
    // decided move then waits behind the one presented, whose length must hold).
    const unsigned ready = t % 2 ? 100 : t % 4 == 0 ? 1 + pick(rng) % 3 : 30 + pick(rng) % 70;
    const LenRun run = run_len(ls, rq, ss << 27 | kk, ready, rng, want, t % 5 == 0 ? pick(rng) % 500 : 0);
    ASSERT_EQ(run.moves, want) << "walk " << t;
    checked += run.lengths_checked;
    saturated += run.saturated;
    ++walks;
  }
  std::printf("%llu walks, %llu lengths checked, %llu moves saturated\n", (unsigned long long)walks,
              (unsigned long long)checked, (unsigned long long)saturated);
  EXPECT_GT(walks, 50u);
  EXPECT_GT(checked, 20000u);
  EXPECT_GT(saturated, 100u);
}

// docs/CONIC.md "The length rule": with LEN the walker presents a move once its
// division is done: a consumer always ready takes one every IW + 1 + 27 + S + 1
// cycles (the pass, then the 27 + S bits of K 2^S and the done clock); the first
// comes that long after the start's pass.
TEST(ConicSerial, LenAMoveEveryPassAndDivision) {
  Lockstep<ConicSerialLen> ls;
  ls.reset();
  std::mt19937_64 rng(9);
  for (uint32_t s : {0u, 7u, 31u}) {
    const ConicRequest rq = circle_from(0, 0, 80, false, 0.1L, 30);
    const auto want = expected_moves(rq, 100, 40);
    const LenRun run = run_len(ls, rq, s << 27 | (1u << 26), 100, rng, want);
    ASSERT_EQ(run.moves, want);
    ASSERT_GE(run.valid_at.size(), 20u);
    EXPECT_EQ(run.valid_at[0] - run.load_cycle, 40u + 2 + 27 + s + 1) << "S " << s;
    for (size_t i = 1; i < run.valid_at.size(); ++i)
      EXPECT_EQ(run.valid_at[i] - run.valid_at[i - 1], 40u + 1 + 27 + s + 1) << "move " << i << ", S " << s;
  }
}

}  // namespace
}  // namespace cpstep::tb

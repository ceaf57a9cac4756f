// SPDX-License-Identifier: MIT
// The conic length rule's serial divider (rtl/cp_div.v) against its model twin
// (model/cp_div.h) every cycle, and every quotient it gives against the division
// itself (k * 2^s / (d + d_inc) in 128-bit C++, saturated to 2^32 - 1): random
// starts, also while busy (ignored; the inputs held through a division, as its
// contract asks), divisors of every width, dividends that just fit (k + 1 would
// not) or give 2^32 exactly, D = 0, resets.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "Vcp_div.h"
#include "common/lockstep.h"
#include "core/bench_random.h"
#include "core/core_bench.h"
#include "model/cp_div.h"
#include "sim/dut.h"

namespace cpstep::tb {
namespace {

#define CPSTEP_FIELD(name, expr) {name, [](const Out& o) { return uint64_t(expr); }}

constexpr unsigned kDw = 40, kKw = 27, kSw = 5, kQw = 32;

struct DivPort {
  using Rtl = AfterOneResetEdge<Vcp_div>;
  using Model = model::CpDiv;
  using In = model::CpDivIn;
  using Out = model::CpDivOut;
  static Model::Params model_params() { return {}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.start_i = i.start;
    r.k_i = uint32_t(i.k & ((uint64_t{1} << kKw) - 1));
    r.s_i = i.s & ((1u << kSw) - 1);
    r.d_i = i.d & ((uint64_t{1} << kDw) - 1);
    r.d_inc_i = i.d_inc;
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.busy = r.busy_o;
    o.done = r.done_o;
    o.q = r.q_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("busy_o", o.busy),
        CPSTEP_FIELD("done_o", o.done),
        CPSTEP_FIELD("q_o", o.q),
    };
    return f;
  }
};

using unit_random::Rng;
using unit_random::pick;
using unit_random::chance;

__extension__ typedef unsigned __int128 u128;

// The length rule's quotient, from its definition: k 2^s / D, or 2^32 - 1 when
// that does not fit (D = 0: every bit of the KW + s fits, 2^(KW + s) - 1).
uint64_t expected_quotient(uint64_t k, unsigned s, u128 divisor) {
  const u128 full = (u128(1) << kQw) - 1;
  const u128 q = divisor == 0 ? (u128(1) << (kKw + s)) - 1 : (u128(k) << s) / divisor;
  return uint64_t(std::min(q, full));
}

TEST(Div, RandomDivisionsMatchTheModelAndTheQuotient) {
  Rng rng(core_seed(2611));
  Lockstep<DivPort> ls("div");
  ls.reset();
  model::CpDivIn in;
  uint64_t k = 0, d = 0, done = 0, saturated = 0, edge = 0, past = 0, shifted = 0, zero = 0;
  unsigned s = 0;
  bool inc = false, pending = false;
  const uint64_t qmax = (uint64_t{1} << kQw) - 1;
  for (int c = 0; c < 2000000; ++c) {
    in.rst = pick(rng, 0, 19999) == 0;
    in.start = chance(rng, 30);
    // A divisor of any width up to DW (given as d + d_inc); a dividend k 2^s whose
    // quotient is anything up to 2^QW, now and then exactly at the edge of
    // fitting, or one past it.
    const unsigned dbits = unsigned(pick(rng, 1, kDw));
    in.d = chance(rng, 2) ? 0 : pick(rng, uint64_t{1} << (dbits - 1), (uint64_t{1} << dbits) - 1);
    in.d_inc = chance(rng, 50) && in.d < (uint64_t{1} << kDw) - 1;
    const u128 divisor = u128(in.d) + in.d_inc;
    in.s = unsigned(pick(rng, 0, (1 << kSw) - 1));
    in.k = pick(rng, 0, (uint64_t{1} << kKw) - 1);
    if (divisor != 0 && chance(rng, 70)) {
      // Aim the quotient: k ~ q D / 2^s for a q up to (or at, or one past) 2^QW - 1.
      const uint64_t q = chance(rng, 10) ? qmax : chance(rng, 10) ? qmax + 1 : pick(rng, 0, qmax);
      for (unsigned sh = 0; sh < (1u << kSw); ++sh) {
        // The least k with k 2^s >= q D: the quotient is q where 2^s <= D.
        const u128 kk = ((u128(q) * divisor) + (u128(1) << sh) - 1) >> sh;
        if (kk < (u128(1) << kKw)) {
          in.s = sh;
          in.k = uint64_t(kk) - (kk > 0 && chance(rng, 30) ? 1 : 0);
          break;
        }
      }
    }
    if (pending) {   // a division runs: its inputs held (k, s, d, d_inc read every clock)
      in.k = k;
      in.s = s;
      in.d = d;
      in.d_inc = inc;
    }
    // The outputs of this cycle, before its edge: a division's done from before,
    // and whether this cycle's start is taken (not busy).
    const model::CpDivOut out = ls.step(in);
    if (out.done && pending) {
      const uint64_t want = expected_quotient(k, s, u128(d) + inc);
      ASSERT_EQ(out.q, want) << "k " << k << " s " << s << " d " << d << " + " << inc << " at cycle " << c;
      ++done;
      saturated += want == qmax && u128(d) + inc != 0 && (u128(k) << s) / (u128(d) + inc) > qmax;
      zero += u128(d) + inc == 0;
      // The edge: the largest k that fits (k + 1 would not).
      edge += want < qmax && u128(d) + inc != 0 && ((u128(k) + 1) << s) / (u128(d) + inc) > qmax;
      past += want == qmax && u128(d) + inc != 0 && (u128(k) << s) / (u128(d) + inc) == qmax + 1;
      shifted += s > 0 && want != qmax;
      pending = false;
    }
    if (in.rst) {
      pending = false;
    } else if (!out.busy && in.start) {
      k = in.k & ((uint64_t{1} << kKw) - 1);
      s = in.s;
      d = in.d & ((uint64_t{1} << kDw) - 1);
      inc = in.d_inc;
      pending = true;
    }
  }
  std::printf("divisions %llu, saturated %llu, at the edge of fitting: %llu, one past: %llu\n",
              (unsigned long long)done, (unsigned long long)saturated, (unsigned long long)edge,
              (unsigned long long)past);
  // What the run covers (the lockstep checks every cycle; the quotients each division).
  EXPECT_GT(done, 20000u);
  EXPECT_GT(shifted, 5000u) << "quotients of a shifted dividend that fit";
  EXPECT_GT(saturated, 500u);
  EXPECT_GT(zero, 50u) << "divisions by 0";
  EXPECT_GT(edge, 200u) << "the largest dividends that fit";
  EXPECT_GT(past, 200u) << "dividends one quotient past what fits";
}

}  // namespace
}  // namespace cpstep::tb

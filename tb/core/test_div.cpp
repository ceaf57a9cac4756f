// SPDX-License-Identifier: MIT
// The serial divider (rtl/cp_div.v) against its model twin (model/cp_div.h) every
// cycle, and every quotient it gives against the division itself (C++'s unsigned
// division of the k and d that started it): random starts, also while busy, with
// divisors of every width, dividends whose quotient just fits (2^32 - 1) or is
// one past (2^32 and a remainder), d = 0, resets.
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

constexpr unsigned kDw = 42, kQw = 32;

struct DivPort {
  using Rtl = AfterOneResetEdge<Vcp_div>;
  using Model = model::CpDiv;
  using In = model::CpDivIn;
  using Out = model::CpDivOut;
  static Model::Params model_params() { return {}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.start_i = i.start;
    r.k_i = i.k;
    r.d_i = i.d & ((uint64_t{1} << kDw) - 1);
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.busy = r.busy_o;
    o.done = r.done_o;
    o.err = r.err_o;
    o.q = r.q_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("busy_o", o.busy), CPSTEP_FIELD("done_o", o.done),
        CPSTEP_FIELD("err_o", o.err),   CPSTEP_FIELD("q_o", o.q),
    };
    return f;
  }
};

using unit_random::Rng;
using unit_random::pick;
using unit_random::chance;

TEST(Div, RandomDivisionsMatchTheModelAndTheQuotient) {
  Rng rng(core_seed(2611));
  Lockstep<DivPort> ls("div");
  ls.reset();
  model::CpDivIn in;
  uint64_t k = 0, d = 0, done = 0, refused = 0, edge = 0, past = 0;
  bool pending = false;
  for (int c = 0; c < 2000000; ++c) {
    in.rst = pick(rng, 0, 19999) == 0;
    in.start = chance(rng, 30);
    // A divisor of any width up to DW; a dividend whose quotient is anything up
    // to 2^QW, now and then exactly at the edge of fitting, or not fitting.
    const unsigned dbits = unsigned(pick(rng, 1, kDw));
    in.d = chance(rng, 2) ? 0 : pick(rng, uint64_t{1} << (dbits - 1), (uint64_t{1} << dbits) - 1);
    const uint64_t qmax = (uint64_t{1} << kQw) - 1;
    if (in.d != 0 && chance(rng, 90)) {
      const uint64_t q = chance(rng, 10) ? qmax : pick(rng, 0, qmax);
      __extension__ const unsigned __int128 base = static_cast<unsigned __int128>(q) * in.d;   // k = q d + r, r < d
      if (base <= UINT64_MAX) {
        const uint64_t room = UINT64_MAX - uint64_t(base);
        in.k = uint64_t(base) + pick(rng, 0, std::min<uint64_t>(in.d - 1, room));
      } else {
        in.k = rng();
      }
    } else if (in.d != 0 && in.d < (uint64_t{1} << (64 - kQw)) && chance(rng, 50)) {
      in.k = in.d << kQw | (rng() >> kQw);   // a quotient of 2^QW and a little: one past what fits
      ++past;
    } else {
      in.k = rng();   // mostly a quotient past QW bits: refused
    }
    // The outputs of this cycle, before its edge: a division's done from before,
    // and whether this cycle's start is taken (not busy).
    const model::CpDivOut out = ls.step(in);
    if (out.done && pending) {
      const bool fits = d != 0 && k / d <= qmax;
      ASSERT_EQ(out.err, !fits) << "k " << k << " d " << d << " at cycle " << c;
      if (fits) {
        ASSERT_EQ(out.q, k / d) << "k " << k << " d " << d << " at cycle " << c;
        ++done;
        edge += out.q == qmax;
      } else {
        ASSERT_EQ(out.q, 0u);
        ++refused;
      }
      pending = false;
    }
    if (in.rst) {
      pending = false;
    } else if (!out.busy && in.start) {
      k = in.k;
      d = in.d & ((uint64_t{1} << kDw) - 1);
      pending = true;
    }
  }
  std::printf("divisions %llu, refused %llu, quotients at 2^32 - 1: %llu\n", (unsigned long long)done,
              (unsigned long long)refused, (unsigned long long)edge);
  // What the run covers (the lockstep checks every cycle; the quotients each division).
  EXPECT_GT(done, 5000u);
  EXPECT_GT(refused, 500u);
  EXPECT_GT(edge, 500u) << "quotients of 2^QW - 1, the largest that fits";
  EXPECT_GT(past, 5000u) << "dividends one quotient past what fits";
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// The oracle's two forms agree, and both have SPEC §1's properties.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "model/oracle.h"

namespace cpstep {
namespace {

TEST(Oracle, StringAlgorithmEqualsClosedFormForAllUpTo300) {
  for (uint64_t u = 1; u <= 300; ++u)
    for (uint64_t v = 0; v <= u; ++v)
      ASSERT_EQ(oracle::castle_pitteway(u, v), oracle::closed_form(u, v)) << u << "," << v;
}

TEST(Oracle, LandsExactlyAndStaysWithinHalfAStep) {
  for (uint64_t u = 1; u <= 200; ++u)
    for (uint64_t v = 0; v <= u; ++v) {
      const std::string s = oracle::closed_form(u, v);
      ASSERT_EQ(s.size(), u);
      ASSERT_EQ(uint64_t(std::count(s.begin(), s.end(), '1')), v);
      uint64_t y = 0;
      for (uint64_t i = 1; i <= u; ++i) {
        y += s[i - 1] == '1';
        // |y - v*i/u| <= 1/2, ties rounded up: 2u*y - 2v*i in (-u, u].
        const int64_t d = int64_t(2 * u * y) - int64_t(2 * v * i);
        ASSERT_GT(d, -int64_t(u)) << u << "," << v << " i=" << i;
        ASSERT_LE(d, int64_t(u)) << u << "," << v << " i=" << i;
      }
    }
}

TEST(Oracle, PatternIsPalindromeExactlyWhenReducedLengthIsOdd) {
  for (uint64_t u = 2; u <= 150; ++u)
    for (uint64_t v = 1; v < u; ++v) {
      const uint64_t n = u / std::gcd(u, v);
      const std::string p = oracle::closed_form(u, v).substr(0, n);
      const bool palindrome = std::equal(p.begin(), p.end(), p.rbegin());
      ASSERT_EQ(palindrome, n % 2 == 1) << u << "," << v;
    }
}

TEST(Oracle, RegistersNeverExceedReducedLengthMinusOne) {
  for (uint64_t u = 2; u <= 150; ++u)
    for (uint64_t v = 1; v < u; ++v) {
      std::vector<oracle::Iteration> t;
      oracle::castle_pitteway(u, v, &t);
      const uint64_t n = u / std::gcd(u, v);
      for (const auto& r : t) {
        ASSERT_LE(r.m1.size(), n - 1);
        ASSERT_LE(r.m2.size(), n - 1);
      }
      if (!t.empty()) {
        ASSERT_EQ(t.back().x, std::gcd(u, v));
      }
    }
}

TEST(Oracle, DoublingIsReplay) {
  for (uint64_t u = 1; u <= 60; ++u)
    for (uint64_t v = 0; v <= u; ++v)
      for (unsigned k = 1; k <= 4; ++k) {
        std::string r;
        for (unsigned i = 0; i < (1u << k); ++i) r += oracle::closed_form(u, v);
        ASSERT_EQ(oracle::doubled(u, v, k), r) << u << "," << v << " k=" << k;
      }
}

}  // namespace
}  // namespace cpstep

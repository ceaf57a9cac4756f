// SPDX-License-Identifier: MIT
#include "oracle.h"

#include <algorithm>

namespace cpstep::oracle {

std::string closed_form(uint64_t u, uint64_t v) {
  std::string s;
  s.reserve(u);
  uint64_t prev = 0;
  for (uint64_t i = 1; i <= u; ++i) {
    const uint64_t pos = (2 * v * i + u) / (2 * u);
    s.push_back(pos != prev ? '1' : '0');
    prev = pos;
  }
  return s;
}

std::string doubled(uint64_t u, uint64_t v, unsigned k) { return closed_form(u << k, v << k); }

static std::string reversed(std::string s) {
  std::reverse(s.begin(), s.end());
  return s;
}

std::string castle_pitteway(uint64_t u, uint64_t v, std::vector<Iteration>* table) {
  if (v == 0) return std::string(u, '0');
  if (v == u) return std::string(u, '1');
  uint64_t x = u - v, y = v;
  std::string m1 = "0", m2 = "1";
  while (x != y) {
    if (x > y) {
      x -= y;
      m2 = m1 + reversed(m2);
    } else {
      y -= x;
      m1 = m2 + reversed(m1);
    }
    if (table) table->push_back({x, y, m1, m2});
  }
  const std::string pattern = m2 + reversed(m1);
  std::string out;
  out.reserve(u);
  for (uint64_t r = 0; r < x; ++r) out += pattern;
  return out;
}

}  // namespace cpstep::oracle

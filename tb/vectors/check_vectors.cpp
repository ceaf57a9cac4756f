// SPDX-License-Identifier: MIT
// check_vectors DIR: checks every line of DIR/engine.vec and DIR/segments.vec
// against its own few lines of SPEC section 1's closed form (not the project's
// oracle), and that each segment lands on its deltas. Prints "N passed, M failed".
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

static std::string expected(uint64_t u, uint64_t v) {  // floor((2 v i + u) / (2 u)), ties up
  std::string s;
  uint64_t prev = 0;
  for (uint64_t i = 1; i <= u; ++i) {
    const uint64_t p = (2 * v * i + u) / (2 * u);
    s += p != prev ? '1' : '0';
    prev = p;
  }
  return s;
}

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const std::string dir = argv[1];
  unsigned passed = 0, failed = 0;
  std::ifstream e(dir + "/engine.vec");
  for (std::string line; std::getline(e, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    uint64_t u, v, k;
    std::string moves;
    in >> u >> v >> k >> moves;
    if (moves == expected(u << k, v << k)) ++passed;
    else { ++failed; std::printf("engine.vec: wrong: %s\n", line.c_str()); }
  }
  std::ifstream s(dir + "/segments.vec");
  for (std::string line; std::getline(s, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    int64_t d[4], end[4];
    std::string m[4], arrow;
    in >> d[0] >> d[1] >> d[2] >> d[3] >> m[0] >> m[1] >> m[2] >> m[3] >> arrow >> end[0] >> end[1] >> end[2] >> end[3];
    uint64_t t = 0;
    for (int64_t x : d) t = std::max<uint64_t>(t, uint64_t(std::llabs(x)));
    bool ok = arrow == "->";
    for (int a = 0; a < 4; ++a) {
      ok = ok && m[a] == expected(t, uint64_t(std::llabs(d[a])));
      int64_t steps = 0;
      for (char c : m[a]) steps += c == '1';
      ok = ok && (d[a] < 0 ? -steps : steps) == end[a] && end[a] == d[a];
    }
    if (ok) ++passed;
    else { ++failed; std::printf("segments.vec: wrong: %.80s...\n", line.c_str()); }
  }
  std::printf("%u passed, %u failed\n", passed, failed);
  return failed == 0 && passed > 0 ? 0 : 1;
}

// SPDX-License-Identifier: MIT
// check_vectors DIR: checks every line of DIR/engine.vec and DIR/segments.vec
// against its own few lines of SPEC section 1's closed form (not the project's
// oracle), and that each segment lands on its deltas; and every walk of
// DIR/conic.vec: king moves, nodes near the curve, the end on the last move.
// Prints "N passed, M failed".
#include <cmath>
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
  // conic.vec: every move a step to one of the eight neighbours; every node of a
  // circle (A = C, B = 0) within half a step of it, of another conic within √½ (its
  // first-order distance |G| / |grad G|); the end node on the last move, on no other.
  std::ifstream c(dir + "/conic.vec");
  unsigned conics = 0;
  for (std::string line; std::getline(c, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    double k[6];
    int64_t x0, y0, x1, y1;
    int cw;
    std::string moves;
    in >> k[0] >> k[1] >> k[2] >> k[3] >> k[4] >> k[5] >> x0 >> y0 >> x1 >> y1 >> cw >> moves;
    const bool circle = k[0] == k[2] && k[1] == 0 && k[0] != 0;
    const double cx = circle ? -k[3] / (2 * k[0]) : 0, cy = circle ? -k[4] / (2 * k[0]) : 0;
    const double r = circle ? std::sqrt(cx * cx + cy * cy - k[5] / k[0]) : 0;
    bool ok = !moves.empty() && (cw == 0 || cw == 1);
    int64_t x = x0, y = y0;
    for (size_t i = 0; ok && i < moves.size(); ++i) {
      const int d = moves[i] - '0';
      if (d < 0 || d > 8 || d == 4) { ok = false; break; }
      x += d / 3 - 1;
      y += d % 3 - 1;
      double dist;
      if (circle) {
        dist = std::fabs(std::hypot(double(x) - cx, double(y) - cy) - r);
      } else {
        const double g = k[0] * x * x + k[1] * x * y + k[2] * y * y + k[3] * x + k[4] * y + k[5];
        dist = std::fabs(g) / std::hypot(2 * k[0] * x + k[1] * y + k[3], k[1] * x + 2 * k[2] * y + k[4]);
      }
      ok = ok && dist <= (circle ? 0.5 : 0.7072) + 1e-9;
      ok = ok && ((x == x1 && y == y1) == (i + 1 == moves.size()));
    }
    ++conics;
    if (ok) ++passed;
    else { ++failed; std::printf("conic.vec: wrong: %.80s...\n", line.c_str()); }
  }
  if (conics == 0) { ++failed; std::printf("conic.vec: no vectors\n"); }
  std::printf("%u passed, %u failed\n", passed, failed);
  return failed == 0 && passed > 0 ? 0 : 1;
}

// SPDX-License-Identifier: MIT
// Untimed oracle for the move string (SPEC §1). Deliberately tiny and independent
// of the engine's design, so the two can disagree.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cpstep::oracle {

// Moves of the segment (0,0)-(u,v), 0 <= v <= u, from the closed form: the minor
// position after move i is floor((2*v*i + u) / (2*u)) (Bresenham, ties up);
// '1' where it advances. u = 0 gives "".
std::string closed_form(uint64_t u, uint64_t v);

// The same line with every step doubled k times: closed_form(u << k, v << k).
std::string doubled(uint64_t u, uint64_t v, unsigned k);

// One row of the register table: x, y, M1 and M2 after a loop iteration.
struct Iteration {
  uint64_t x, y;
  std::string m1, m2;
};

// The Castle–Pitteway string algorithm exactly as SPEC §1 writes it, with plain
// strings; `table`, if given, receives a row per loop iteration.
std::string castle_pitteway(uint64_t u, uint64_t v, std::vector<Iteration>* table = nullptr);

}  // namespace cpstep::oracle

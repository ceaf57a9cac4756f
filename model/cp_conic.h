// SPDX-License-Identifier: MIT
// cp_conic — cycle-accurate, bit-exact model of rtl/cp_conic.v: the combined-step
// conic engine of seed 001 (docs/CONIC.md).
//
// Written from docs/CONIC.md, not from the RTL. Same ports as the RTL; the bench
// sets `in`, reads outputs() (combinational in the current state and inputs),
// then calls tick() for the rising edge.
//
// The curve is G(x, y) = A x^2 + B xy + C y^2 + D x + E y + F = 0 in absolute step
// coordinates; the engine walks from the start node to the end node with one move
// (dx, dy), each in {-1, 0, 1}, per clock, keeping G and its gradient at the
// current node by additions only.
#pragma once

#include <cstdint>

#include "model/bits.h"

namespace cpstep::model {

using bits::i128;  // wide enough for every width the parameters allow (<= 120 bits)

struct CpConicParams {
  unsigned qw = 16;        // signed width accepted for A, B, C
  unsigned lw = 32;        // signed width accepted for D, E
  unsigned fw = 48;        // signed width accepted for F
  unsigned pw = 20;        // signed width accepted for the start and end coordinates
  uint32_t nmax = 1048575; // most moves of one request (then END_MISSED)

  unsigned nw() const;  // width of the move counter, clog2(NMAX + 1)
  unsigned xw() const;  // width of the walk's position, max(PW, NW + 1) + 1
  unsigned iw() const;  // width of G, its gradient and the evaluations
  int64_t pmax() const { return (int64_t(1) << (pw - 1)) - 1; }
};

struct CpConicIn {
  bool rst = false;
  bool in_valid = false;
  // Coefficients as 64-bit two's-complement words (the port is 64 bits wide).
  int64_t in_a = 0, in_b = 0, in_c = 0, in_d = 0, in_e = 0, in_f = 0;
  // Start and end node, 32-bit two's-complement words.
  int32_t in_x0 = 0, in_y0 = 0, in_x1 = 0, in_y1 = 0;
  bool in_cw = false;  // 1: clockwise (G > 0 on the left of travel), 0: counter-clockwise
  bool move_ready = false;
};

struct CpConicOut {
  bool in_ready = false;
  bool err = false;
  uint32_t err_code = 0;
  bool move_valid = false;
  int move_dx = 0, move_dy = 0;  // in {-1, 0, 1}; 0 while not valid
  bool move_last = false;
  int64_t move_x = 0, move_y = 0;  // the node the move arrives at; 0 while not valid
};

enum class ConicError : uint32_t {
  none = 0,
  coef_range = 1,    // a coefficient outside its width (QW, LW, FW)
  point_range = 2,   // a start or end coordinate outside PW bits
  degenerate = 3,    // the gradient of G is zero at the start node
  start_off = 4,     // the start node is not on the curve (docs/CONIC.md "On the curve")
  end_off = 5,       // the end node is not on the curve
  end_missed = 6,    // NMAX moves made without reaching the end node (after the last move)
};

class CpConic {
 public:
  using Params = CpConicParams;
  using In = CpConicIn;
  using Out = CpConicOut;

  explicit CpConic(CpConicParams params = {});

  CpConicIn in;

  CpConicOut outputs() const;
  void tick();

  const CpConicParams& params() const { return p_; }

  // The move the walk makes from a node, from G and its gradient there (the
  // combinational rule of docs/CONIC.md "The rule"); shared by the engine and
  // by the host, which runs the same walk to know every node.
  struct Coeffs {
    i128 a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  };
  struct Node {
    i128 g = 0, gx = 0, gy = 0;  // G, dG/dx, dG/dy at the node
  };
  static void rule(const Coeffs& k, const Node& n, bool cw, int& dx, int& dy);
  static Node advance(const Coeffs& k, const Node& n, int dx, int dy);
  // G and its gradient at node (x, y), evaluated directly (the engine reaches the
  // start node's values bit-serially; the host and the benches start walks here).
  static Node at(const Coeffs& k, int64_t x, int64_t y);
  // The eight-point test: does the curve pass through the unit square centred on
  // the node (some of the 8 boundary points E + (i/2, j/2) on each side, or on it)?
  static bool on_curve(const Coeffs& k, const Node& n);

 private:
  enum class State { idle, eval_start, eval_end, check, walk };
  struct Regs {
    // Control (reset).
    State state = State::idle;
    bool out_valid = false;
    bool err = false;
    // Datapath.
    uint32_t err_code = 0;
    Coeffs k;
    int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool cw = false;
    unsigned bit = 0;                     // eval: index of the coordinate bit
    i128 q = 0, ux = 0, uy = 0, l = 0;    // eval: quadratic part, its gradient, linear part
    int64_t x = 0, y = 0;                 // walk: the current node
    Node n;                               // walk: G and gradient there
    uint32_t count = 0;                   // walk: moves issued
    int out_dx = 0, out_dy = 0;
    int64_t out_x = 0, out_y = 0;
    bool out_last = false, out_miss = false;
  };
  Regs next() const;

  CpConicParams p_;
  Regs r_;
};

}  // namespace cpstep::model

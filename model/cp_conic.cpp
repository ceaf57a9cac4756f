// SPDX-License-Identifier: MIT
#include "cp_conic.h"

#include <algorithm>
#include <stdexcept>

namespace cpstep::model {
namespace {

unsigned clog2(uint64_t x) {
  unsigned b = 0;
  while ((uint64_t(1) << b) < x) ++b;
  return b;
}

bool fits(int64_t v, unsigned bits) {
  if (bits >= 64) return true;
  const int64_t lim = int64_t(1) << (bits - 1);
  return v >= -lim && v < lim;
}

int bit_of(int64_t v, unsigned i) { return int((uint64_t(v) >> i) & 1); }

}  // namespace

unsigned CpConicParams::nw() const { return clog2(uint64_t(nmax) + 1); }
unsigned CpConicParams::xw() const { return std::max(pw, nw() + 1) + 1; }
unsigned CpConicParams::iw() const {
  return std::max({fw, lw + xw(), qw + 2 * xw()}) + 6;
}

CpConic::CpConic(CpConicParams params) : p_(params) {
  if (p_.qw < 2 || p_.qw > 32) throw std::invalid_argument("cp_conic: QW must be 2 to 32");
  if (p_.lw < 2 || p_.lw > 48) throw std::invalid_argument("cp_conic: LW must be 2 to 48");
  if (p_.fw < 2 || p_.fw > 64) throw std::invalid_argument("cp_conic: FW must be 2 to 64");
  if (p_.pw < 2 || p_.pw > 30) throw std::invalid_argument("cp_conic: PW must be 2 to 30");
  if (p_.nmax < 1 || p_.nmax > (1u << 30)) throw std::invalid_argument("cp_conic: NMAX must be 1 to 2^30");
  if (p_.iw() > 120) throw std::invalid_argument("cp_conic: internal width over 120 bits");
}

// docs/CONIC.md "The rule". Travel direction T: (-gy, gx) counter-clockwise,
// (gy, -gx) clockwise; the square ahead is the quadrant (sx, sy) of T (a zero
// component counts as +). L = P + (sx/2, sy), M = P + (sx, sy/2); 4G there:
//   eL = 4g + 2 sx gx + 4 sy gy + A + 2 sx sy B + 4C
//   eM = 4g + 4 sx gx + 2 sy gy + 4A + 2 sx sy B + C
// A half-grid point is on the left of travel when G > 0 there (clockwise) or
// G < 0 (counter-clockwise). Walking the square's far boundary from its left end
// to its right end, the first midpoint on the right decides: none on the left:
// step to the left end; the first only: diagonal; both: step to the right end.
void CpConic::rule(const Coeffs& k, const Node& n, bool cw, int& dx, int& dy) {
  const i128 tx = cw ? n.gy : -n.gy;
  const i128 ty = cw ? -n.gx : n.gx;
  // A zero component is a quadrant change: the curve turns towards its concave
  // side, where G decreases when the second derivative along T (2A T_x^2 for
  // T = (T_x, 0), 2C T_y^2 for T = (0, T_y)) is positive.
  const int sx = tx > 0 ? 1 : tx < 0 ? -1 : ((k.c > 0) == (n.gx > 0) ? -1 : 1);
  const int sy = ty > 0 ? 1 : ty < 0 ? -1 : ((k.a > 0) == (n.gy > 0) ? -1 : 1);
  const int sxy = sx * sy;
  const i128 el = 4 * n.g + 2 * sx * n.gx + 4 * sy * n.gy + k.a + 2 * sxy * k.b + 4 * k.c;
  const i128 em = 4 * n.g + 4 * sx * n.gx + 2 * sy * n.gy + 4 * k.a + 2 * sxy * k.b + k.c;
  const bool left_l = cw ? el > 0 : el < 0;
  const bool left_m = cw ? em > 0 : em < 0;
  // sx sy > 0: the far boundary runs Y=(0,sy), L, corner, M, X=(sx,0) from left to right;
  // sx sy < 0: X, M, corner, L, Y.
  const bool first = sxy > 0 ? left_l : left_m;
  const bool second = sxy > 0 ? left_m : left_l;
  if (!first) {
    dx = sxy > 0 ? 0 : sx;
    dy = sxy > 0 ? sy : 0;
  } else if (!second) {
    dx = sx;
    dy = sy;
  } else {
    dx = sxy > 0 ? sx : 0;
    dy = sxy > 0 ? 0 : sy;
  }
}

// G(P + d) = G + d.grad + A dx^2 + B dx dy + C dy^2; the gradient moves by the
// constant second differences.
CpConic::Node CpConic::at(const Coeffs& k, int64_t x, int64_t y) {
  const i128 X = x, Y = y;
  Node n;
  n.g = k.a * X * X + k.b * X * Y + k.c * Y * Y + k.d * X + k.e * Y + k.f;
  n.gx = 2 * k.a * X + k.b * Y + k.d;
  n.gy = k.b * X + 2 * k.c * Y + k.e;
  return n;
}

CpConic::Node CpConic::advance(const Coeffs& k, const Node& n, int dx, int dy) {
  Node m;
  m.g = n.g + dx * n.gx + dy * n.gy + dx * dx * k.a + dx * dy * k.b + dy * dy * k.c;
  m.gx = n.gx + 2 * dx * k.a + dy * k.b;
  m.gy = n.gy + dx * k.b + 2 * dy * k.c;
  return m;
}

// 4G at P + (i/2, j/2) = 4g + 2i gx + 2j gy + i^2 A + ij B + j^2 C, i, j in {-1, 0, 1},
// (i, j) != (0, 0): on the curve unless all eight are > 0 or all are < 0.
bool CpConic::on_curve(const Coeffs& k, const Node& n) {
  bool pos = false, neg = false;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j) {
      if (i == 0 && j == 0) continue;
      const i128 v = 4 * n.g + 2 * i * n.gx + 2 * j * n.gy + i * i * k.a + i * j * k.b + j * j * k.c;
      if (v >= 0) pos = true;
      if (v <= 0) neg = true;
    }
  return pos && neg;
}

CpConic::Regs CpConic::next() const {
  const Regs& q = r_;
  Regs d = q;
  d.err = false;
  if (q.out_valid && in.move_ready) {
    d.out_valid = false;
    if (q.out_miss) {  // the NMAX-th move left without reaching the end
      d.err = true;
      d.err_code = uint32_t(ConicError::end_missed);
    }
  }
  const auto refuse = [&](ConicError e) {
    d.err = true;
    d.err_code = uint32_t(e);
    d.state = State::idle;
  };
  // One bit of the serial evaluation (docs/CONIC.md "Setup"): (x, y) <- (2x + bx, 2y + by).
  const auto eval_bit = [&](int64_t px, int64_t py) {
    const bool sign = q.bit == p_.pw - 1;
    const int bx = sign ? -bit_of(px, q.bit) : bit_of(px, q.bit);
    const int by = sign ? -bit_of(py, q.bit) : bit_of(py, q.bit);
    d.q = 4 * q.q + 2 * bx * q.ux + 2 * by * q.uy + bx * bx * q.k.a + bx * by * q.k.b + by * by * q.k.c;
    d.ux = 2 * q.ux + 2 * bx * q.k.a + by * q.k.b;
    d.uy = 2 * q.uy + bx * q.k.b + 2 * by * q.k.c;
    d.l = 2 * q.l + bx * q.k.d + by * q.k.e;
    d.bit = q.bit - 1;
  };

  switch (q.state) {
    case State::idle: {
      if (!(in.in_valid && q.state == State::idle && !q.out_valid)) break;
      if (!fits(in.in_a, p_.qw) || !fits(in.in_b, p_.qw) || !fits(in.in_c, p_.qw) ||
          !fits(in.in_d, p_.lw) || !fits(in.in_e, p_.lw) || !fits(in.in_f, p_.fw)) {
        refuse(ConicError::coef_range);
        break;
      }
      if (!fits(in.in_x0, p_.pw) || !fits(in.in_y0, p_.pw) || !fits(in.in_x1, p_.pw) ||
          !fits(in.in_y1, p_.pw)) {
        refuse(ConicError::point_range);
        break;
      }
      d.k = {in.in_a, in.in_b, in.in_c, in.in_d, in.in_e, in.in_f};
      d.x0 = in.in_x0;
      d.y0 = in.in_y0;
      d.x1 = in.in_x1;
      d.y1 = in.in_y1;
      d.cw = in.in_cw;
      d.bit = p_.pw - 1;
      d.q = d.ux = d.uy = d.l = 0;
      d.state = State::eval_start;
      break;
    }
    case State::eval_start:
      eval_bit(q.x0, q.y0);
      if (q.bit == 0) {
        d.x = q.x0;
        d.y = q.y0;
        d.n = {d.q + d.l + q.k.f, d.ux + q.k.d, d.uy + q.k.e};
        d.bit = p_.pw - 1;
        d.q = d.ux = d.uy = d.l = 0;
        d.state = State::eval_end;
      }
      break;
    case State::eval_end:
      eval_bit(q.x1, q.y1);
      if (q.bit == 0) d.state = State::check;
      break;
    case State::check: {
      const Node end{q.q + q.l + q.k.f, q.ux + q.k.d, q.uy + q.k.e};
      if (q.n.gx == 0 && q.n.gy == 0) refuse(ConicError::degenerate);
      else if (!on_curve(q.k, q.n)) refuse(ConicError::start_off);
      else if (!on_curve(q.k, end)) refuse(ConicError::end_off);
      else {
        d.count = 0;
        d.state = State::walk;
      }
      break;
    }
    case State::walk: {
      if (q.out_valid && !in.move_ready) break;
      int dx = 0, dy = 0;
      rule(q.k, q.n, q.cw, dx, dy);
      d.n = advance(q.k, q.n, dx, dy);
      d.x = q.x + dx;
      d.y = q.y + dy;
      d.count = q.count + 1;
      const bool at_end = d.x == q.x1 && d.y == q.y1;
      const bool miss = !at_end && d.count == p_.nmax;
      d.out_valid = true;
      d.out_dx = dx;
      d.out_dy = dy;
      d.out_x = d.x;
      d.out_y = d.y;
      d.out_last = at_end || miss;
      d.out_miss = miss;
      if (d.out_last) d.state = State::idle;
      break;
    }
  }
  return d;
}

CpConicOut CpConic::outputs() const {
  const Regs& q = r_;
  CpConicOut o;
  o.in_ready = q.state == State::idle && !q.out_valid;
  o.err = q.err;
  o.err_code = q.err ? q.err_code : 0;
  o.move_valid = q.out_valid;
  if (q.out_valid) {
    o.move_dx = q.out_dx;
    o.move_dy = q.out_dy;
    o.move_last = q.out_last;
    o.move_x = q.out_x;
    o.move_y = q.out_y;
  }
  return o;
}

void CpConic::tick() {
  Regs d = next();
  if (in.rst) {  // synchronous reset of control state only, as in the RTL
    d.state = State::idle;
    d.out_valid = d.err = false;
  }
  r_ = d;
}

}  // namespace cpstep::model

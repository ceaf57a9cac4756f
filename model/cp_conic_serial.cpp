// SPDX-License-Identifier: MIT
#include "cp_conic_serial.h"

#include <stdexcept>

namespace cpstep::model {
namespace {

__extension__ typedef unsigned __int128 u128;

// v modulo 2^w, as a signed w-bit value.
i128 wrap(i128 v, unsigned w) {
  const u128 m = (u128(1) << w) - 1;
  const u128 sign = u128(1) << (w - 1);
  const u128 u = u128(v) & m;
  return static_cast<i128>(u ^ sign) - static_cast<i128>(sign);
}

int64_t wrap64(int64_t v, unsigned w) { return int64_t(wrap(v, w)); }

bool fits_w(i128 v, unsigned w) { return wrap(v, w) == v; }

// 4G at L = P + (sx/2, sy) and at M = P + (sx, sy/2), exactly.
void evaluations(const CpConic::Coeffs& k, const CpConic::Node& n, int sx, int sy, i128& el, i128& em) {
  const int sxy = sx * sy;
  el = 4 * n.g + 2 * sx * n.gx + 4 * sy * n.gy + k.a + 2 * sxy * k.b + 4 * k.c;
  em = 4 * n.g + 4 * sx * n.gx + 2 * sy * n.gy + 4 * k.a + 2 * sxy * k.b + k.c;
}

}  // namespace

CpConicSerial::CpConicSerial(CpConicSerialParams params) : p_(params) {
  if (p_.qw < 2 || p_.qw > 32) throw std::invalid_argument("cp_conic_serial: QW must be 2 to 32");
  if (p_.iw < p_.qw + 4 || p_.iw > 120) throw std::invalid_argument("cp_conic_serial: IW must be QW + 4 to 120");
  if (p_.xw < 2 || p_.xw > 32) throw std::invalid_argument("cp_conic_serial: XW must be 2 to 32");
}

// docs/CONIC.md "The rule"; the quadrant from the signs of the gradient, each
// evaluation taken modulo 2^iw before its sign is read.
void CpConicSerial::rule(const CpConic::Coeffs& k, const CpConic::Node& n, bool cw, unsigned iw, int& dx,
                         int& dy) {
  const bool gx_pos = n.gx > 0, gy_pos = n.gy > 0;
  const bool nsx = n.gy == 0 ? (k.c > 0) == gx_pos : (cw ? n.gy < 0 : gy_pos);
  const bool nsy = n.gx == 0 ? (k.a > 0) == gy_pos : (cw ? gx_pos : n.gx < 0);
  const int sx = nsx ? -1 : 1, sy = nsy ? -1 : 1;
  i128 el = 0, em = 0;
  evaluations(k, n, sx, sy, el, em);
  el = wrap(el, iw);
  em = wrap(em, iw);
  const bool left_l = cw ? el > 0 : el < 0;
  const bool left_m = cw ? em > 0 : em < 0;
  const bool same = sx == sy;
  const bool first = same ? left_l : left_m;
  const bool second = same ? left_m : left_l;
  // Left end (axial): Y when sx sy > 0, X otherwise; the corner; the right end.
  const bool step_x = first ? (!second || same) : !same;
  const bool step_y = first ? (!second || !same) : same;
  dx = step_x ? sx : 0;
  dy = step_y ? sy : 0;
}

bool CpConicSerial::fits(const CpConic::Coeffs& k, const CpConic::Node& n, unsigned iw) {
  if (!fits_w(n.g, iw) || !fits_w(n.gx, iw) || !fits_w(n.gy, iw)) return false;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) {
      i128 el = 0, em = 0;
      evaluations(k, n, sx, sy, el, em);
      if (!fits_w(el, iw) || !fits_w(em, iw)) return false;
    }
  return true;
}

CpConicSerialOut CpConicSerial::outputs() const {
  const Regs& q = r_;
  CpConicSerialOut o;
  o.busy = q.pass || q.pend;
  o.move_valid = q.ov;
  if (q.ov) {
    o.move_dx = q.odx;
    o.move_dy = q.ody;
    o.move_end = q.oend;
  }
  return o;
}

void CpConicSerial::tick() {
  const Regs& q = r_;
  Regs d = q;
  const bool last_bit = q.pass && q.i == p_.iw - 1;
  const bool issue = q.pend && (!q.ov || in.move_ready);
  const int64_t du_n = wrap64(q.du - q.mdx, p_.xw), dv_n = wrap64(q.dv - q.mdy, p_.xw);
  const bool at_end = du_n == 0 && dv_n == 0;

  // Datapath.
  if (in.load) {
    d.k = {wrap(in.a, p_.qw), wrap(in.b, p_.qw), wrap(in.c, p_.qw), 0, 0, 0};
    d.n = {wrap(in.g, p_.iw), wrap(in.gx, p_.iw), wrap(in.gy, p_.iw)};
    d.cw = in.cw;
    d.du = wrap64(in.du, p_.xw);
    d.dv = wrap64(in.dv, p_.xw);
    d.mdx = d.mdy = 0;
    d.i = 0;
  } else if (q.pass) {
    d.i = last_bit ? 0 : q.i + 1;
    if (last_bit) {  // the pass's arithmetic, seen whole at its last bit
      const CpConic::Node m = CpConic::advance(q.k, q.n, q.mdx, q.mdy);
      d.n = {wrap(m.g, p_.iw), wrap(m.gx, p_.iw), wrap(m.gy, p_.iw)};
      rule(q.k, d.n, q.cw, p_.iw, d.mdx, d.mdy);
    }
  }
  if (issue && !in.load) {
    d.odx = q.mdx;
    d.ody = q.mdy;
    d.oend = at_end;
    d.du = du_n;
    d.dv = dv_n;
  }

  // Control.
  if (in.rst || (in.clear && !in.load)) {
    d.pass = d.pend = d.ov = false;
  } else if (in.load) {
    d.pass = true;
    d.pend = d.ov = false;
  } else {
    if (q.ov && in.move_ready) d.ov = false;
    if (last_bit) {
      d.pass = false;
      d.pend = true;
    }
    if (issue) {
      d.pend = false;
      d.ov = true;
      d.pass = !at_end;
    }
  }
  r_ = d;
}

}  // namespace cpstep::model

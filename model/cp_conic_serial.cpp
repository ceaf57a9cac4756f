// SPDX-License-Identifier: MIT
#include "cp_conic_serial.h"

#include <stdexcept>

#include "model/bits.h"

namespace cpstep::model {
namespace {

using bits::u128;

// v modulo 2^w, as a signed w-bit value.
i128 wrap(i128 v, unsigned w) {
  const u128 m = (u128(1) << w) - 1;
  const u128 sign = u128(1) << (w - 1);
  const u128 u = u128(v) & m;
  return static_cast<i128>(u ^ sign) - static_cast<i128>(sign);
}

int64_t wrap64(int64_t v, unsigned w) { return int64_t(wrap(v, w)); }

// A shift register j clocks into a pass: the new value's low j bits on top of the
// old value's high IW - j (the RTL shifts right, new bits entering at the top).
i128 mix(i128 old_v, i128 new_v, unsigned j, unsigned w) {
  if (j == 0) return old_v;
  if (j >= w) return new_v;
  const u128 m = (u128(1) << w) - 1;
  const u128 o = u128(old_v) & m, n = u128(new_v) & m;
  return wrap(i128((o >> j) | ((n & ((u128(1) << j) - 1)) << (w - j))), w);
}

bool fits_w(i128 v, unsigned w) { return wrap(v, w) == v; }

// 4G at L = P + (sx/2, sy) and at M = P + (sx, sy/2), exactly.
void evaluations(const CpConic::Coeffs& k, const CpConic::Node& n, int sx, int sy, i128& el, i128& em) {
  const int sxy = sx * sy;
  el = 4 * n.g + 2 * sx * n.gx + 4 * sy * n.gy + k.a + 2 * sxy * k.b + 4 * k.c;
  em = 4 * n.g + 4 * sx * n.gx + 2 * sy * n.gy + 4 * k.a + 2 * sxy * k.b + k.c;
}

}  // namespace

CpConicSerial::CpConicSerial(CpConicSerialParams params)
    : p_(params), div_(CpDivParams{params.iw < 26 ? 26 : params.iw > 61 ? 61 : params.iw, 27, 5, 32}) {
  if (p_.qw < 2 || p_.qw > 16) throw std::invalid_argument("cp_conic_serial: QW must be 2 to 16");
  if (p_.iw < p_.qw + 4 || p_.iw > 120) throw std::invalid_argument("cp_conic_serial: IW must be QW + 4 to 120");
  if (p_.xw < 2 || p_.xw > 24) throw std::invalid_argument("cp_conic_serial: XW must be 2 to 24");
  if (p_.len && (p_.iw < 26 || p_.iw > 61)) throw std::invalid_argument("cp_conic_serial: IW must be 26 to 61 with LEN");
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

std::array<uint32_t, 7> CpConicSerial::words(const CpConic::Coeffs& k, const CpConic::Node& start, bool cw,
                                             int64_t du, int64_t dv) {
  const auto lo16 = [](i128 v) { return uint32_t(uint64_t(v) & 0xFFFF); };
  const auto lo32 = [](i128 v) { return uint32_t(uint64_t(v)); };
  return {lo16(k.b) << 16 | lo16(k.a), uint32_t(cw) << 31 | lo16(k.c), lo32(start.g), lo32(start.gx),
          lo32(start.gy), uint32_t(du) & 0xFFFFFF, uint32_t(dv) & 0xFFFFFF};
}

void CpConicSerial::rule_divisor(const CpConic::Node& n, unsigned iw, uint64_t& d, bool& inc) {
  const uint64_t m = (iw >= 64) ? ~uint64_t{0} : (uint64_t{1} << iw) - 1;
  const uint64_t gx = uint64_t(n.gx) & m, gy = uint64_t(n.gy) & m;
  const bool sx = n.gx < 0, sy = n.gy < 0;
  const uint64_t ax = (sx ? 0 - gx : gx) & m, ay = (sy ? 0 - gy : gy) & m;
  const bool sel = ay > ax;
  inc = sel ? sy : sx;
  d = (sel ? gy : gx) ^ (inc ? m : 0);
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
  if (p_.len) o.len = uint32_t(div_.outputs().q);
  return o;
}

void CpConicSerial::tick() {
  const Regs& q = r_;
  Regs d = q;
  const bool last_bit = q.pass && q.i == p_.iw - 1;
  const bool out_free = !q.ov || in.move_ready;
  const CpDivOut dv = div_.outputs();
  // len: the decided move is presented in the clock its length's division is done;
  // the division starts once it could be presented.
  const bool issue = q.pend && out_free && (!p_.len || dv.done);
  const bool len_start = p_.len && q.pend && !dv.busy && !dv.done && out_free && in.len_go;
  const int64_t du_n = wrap64(q.du - q.mdx, p_.xw), dv_n = wrap64(q.dv - q.mdy, p_.xw);
  const bool at_end = du_n == 0 && dv_n == 0;

  // Datapath. A word is taken only while not busy (no pass running, no move decided).
  if (in.wr && !q.pass && !q.pend) {
    const int32_t w32 = int32_t(in.wr_data);
    const int64_t lo16 = int16_t(in.wr_data & 0xFFFF), hi16 = int16_t(in.wr_data >> 16);
    const int64_t w24 = int64_t(int32_t(in.wr_data << 8) >> 8);
    switch (in.wr_sel) {
      case 0: d.k.a = wrap(lo16, p_.qw); d.k.b = wrap(hi16, p_.qw); break;
      case 1: d.k.c = wrap(lo16, p_.qw); d.cw = (in.wr_data >> 31) != 0; break;
      case 2: d.n.g = wrap(w32, p_.iw); break;
      case 3: d.n.gx = wrap(w32, p_.iw); break;
      case 4: d.n.gy = wrap(w32, p_.iw); break;
      case 5: d.du = wrap64(w24, p_.xw); break;
      case 6: d.dv = wrap64(w24, p_.xw); break;
      default: break;
    }
  }
  // The node a running pass arrives at; a pass cut short (start, clear or reset)
  // leaves its shift registers part turned: mix().
  CpConic::Node after;
  if (q.pass) {
    const CpConic::Node m = CpConic::advance(q.k, q.n, q.mdx, q.mdy);
    after = {wrap(m.g, p_.iw), wrap(m.gx, p_.iw), wrap(m.gy, p_.iw)};
  }
  const auto part_turned = [&](unsigned j) {
    d.n = {mix(q.n.g, after.g, j, p_.iw), mix(q.n.gx, after.gx, j, p_.iw), mix(q.n.gy, after.gy, j, p_.iw)};
  };
  const bool cut = in.rst || (in.clear && !in.start);  // the control stops any pass
  if (in.start) {
    if (q.pass) part_turned(q.i);
    if (!in.cont) d.mdx = d.mdy = 0;
    d.i = 0;
  } else if (q.pass) {
    d.i = last_bit ? 0 : q.i + 1;
    if (last_bit) {  // the pass's arithmetic, seen whole at its last bit
      d.n = after;
      rule(q.k, d.n, q.cw, p_.iw, d.mdx, d.mdy);
    } else if (cut) {
      part_turned(q.i + 1);
    }
  }
  // len: the comparisons of a pass, whole at its last bit (whatever else this clock does).
  if (p_.len && last_bit) rule_divisor(after, p_.iw, d.ld, d.linc);
  if (p_.len) {
    div_.in.rst = in.rst || in.clear;
    div_.in.start = len_start;
    div_.in.k = in.len_k & ((1u << 27) - 1);
    div_.in.s = in.len_k >> 27;
    div_.in.d = q.ld;
    div_.in.d_inc = q.linc;
    div_.tick();
  }
  if (issue && !in.start) {
    d.odx = q.mdx;
    d.ody = q.mdy;
    d.oend = at_end;
    d.du = du_n;
    d.dv = dv_n;
  }

  // Control.
  if (in.rst || (in.clear && !in.start)) {
    d.pass = d.pend = d.ov = false;
  } else if (in.start) {
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

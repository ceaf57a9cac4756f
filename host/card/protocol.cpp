// SPDX-License-Identifier: MIT
#include "card/protocol.h"

#include <bit>
#include <cmath>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>

namespace cpstep::card {

uint32_t axis_form(const WireSegment& s) {
  uint32_t sent = 0, major = 0;
  for (size_t a = 0; a < s.v.size() && a < 8; ++a) {
    if (s.v[a] == 0) continue;
    if (major == 0 && s.v[a] == s.u) major = 0x8u | uint32_t(a);
    else sent |= 1u << a;
  }
  return 0x8000u | major << 8 | sent;
}

void encode_segment(const WireSegment& s, std::vector<uint32_t>& out, bool every_axis) {
  bool add2 = false;
  for (const WireChunk& c : s.chunks) add2 = add2 || c.add2 != 0;
  if (s.length) add2 = false;
  const uint32_t form = s.length && !every_axis ? axis_form(s) : 0;
  const uint32_t nchunks = s.length ? form : uint32_t(s.chunks.size() & 0xFFFF);
  if (s.conic)
    out.push_back(0x5u << 28 | uint32_t(s.end) << 27 | uint32_t(s.conic->cw) << 26 | (s.conic->axis_u & 7u) << 23 |
                  uint32_t(add2) << 22 | (s.conic->axis_v & 7u) << 19 | uint32_t(s.conic->cont) << 18 |
                  uint32_t(s.torch) << 16 | nchunks);
  else
    out.push_back(0x1u << 28 | uint32_t(s.end) << 27 | (s.k & 0xFu) << 23 | uint32_t(add2) << 22 |
                  uint32_t(s.torch) << 16 | nchunks);
  uint32_t dirs = 0;
  for (size_t a = 0; a < s.dir_positive.size(); ++a) dirs |= uint32_t(s.dir_positive[a]) << a;
  out.push_back(dirs << 24 | (s.u & 0xFFFFFF));
  for (size_t a = 0; a < s.v.size(); ++a)
    if (form == 0 || (a < 8 && (form >> a & 1))) out.push_back(s.v[a] & 0xFFFFFF);
  if (s.conic)
    for (size_t i = s.conic->cont ? 5 : 0; i < 7; ++i)
      out.push_back(i == 1 ? s.conic->words[1] & 0xFFFF : s.conic->words[i]);
  if (s.length) {
    out.push_back(*s.length);
    return;
  }
  for (const WireChunk& c : s.chunks) {
    out.push_back(c.interval);
    out.push_back(uint32_t(uint16_t(c.add)) << 16 | c.count);
    if (add2) out.push_back(uint16_t(c.add2));
  }
}

void encode_conic(const WireConic& s, std::vector<uint32_t>& out) {
  bool add2 = false;
  for (const WireChunk& c : s.chunks) add2 = add2 || c.add2 != 0;
  out.push_back(0x5u << 28 | uint32_t(s.end) << 27 | uint32_t(s.cw) << 26 | (s.axis_u & 7u) << 23 |
                uint32_t(add2) << 22 | (s.axis_v & 7u) << 19 | uint32_t(s.cont) << 18 |
                uint32_t(s.torch) << 16 | uint32_t(s.chunks.size() & 0xFFFF));
  uint32_t dirs = 0;
  for (size_t a = 0; a < s.dir_positive.size(); ++a) dirs |= uint32_t(s.dir_positive[a]) << a;
  out.push_back(dirs << 24 | (s.t & 0xFFFFFF));
  for (uint32_t v : s.v) out.push_back(v & 0xFFFFFF);
  if (!s.cont) {
    out.push_back(uint32_t(uint16_t(s.b)) << 16 | uint16_t(s.a));
    out.push_back(uint16_t(s.c));
    out.push_back(uint32_t(s.g));
    out.push_back(uint32_t(s.gx));
    out.push_back(uint32_t(s.gy));
  }
  out.push_back(uint32_t(s.du) & 0xFFFFFF);
  out.push_back(uint32_t(s.dv) & 0xFFFFFF);
  for (const WireChunk& c : s.chunks) {
    out.push_back(c.interval);
    out.push_back(uint32_t(uint16_t(c.add)) << 16 | c.count);
    if (add2) out.push_back(uint16_t(c.add2));
  }
}

void encode_phase(const WirePhase& p, std::vector<uint32_t>& out) {
  out.push_back(0x6u << 28 | (p.kind & 0xFu) << 24 | (p.ticks & 0xFFFFFF));
  out.push_back(uint32_t(p.u));
  if (p.kind & 1) {
    out.push_back(uint32_t(p.r_top));
    out.push_back(uint32_t(p.r_top >> 32));
  }
  if (p.kind & 8) {
    out.push_back(uint32_t(uint64_t(p.s)));
    out.push_back(uint32_t(uint64_t(p.s) >> 32));
    out.push_back(uint32_t(uint64_t(p.h)));
    out.push_back(uint32_t(uint64_t(p.h) >> 32));
  }
}

void encode_config(unsigned axis, ConfigField field, uint32_t value, std::vector<uint32_t>& out) {
  out.push_back(0x2u << 28 | (axis & 0xFu) << 24 | uint32_t(field) << 20 | (value & 0xFFFF));
}

uint32_t watchdog_units(double seconds, uint32_t clock_hz) {
  const double units = std::ceil(seconds * double(clock_hz) / kWatchdogUnit);
  if (!(seconds >= 0) || units > 0xFFFF)
    throw std::invalid_argument(fmt::format(
        "the watchdog timeout {} s is outside 0 .. {:.3f} s, the longest the card's field holds (65,535 "
        "units of {} clocks at {} Hz)",
        seconds, 0xFFFF * double(kWatchdogUnit) / double(clock_hz), kWatchdogUnit, clock_hz));
  return uint32_t(units);
}

void encode_watchdog(double seconds, uint32_t clock_hz, std::vector<uint32_t>& out) {
  encode_config(0, ConfigField::watchdog, watchdog_units(seconds, clock_hz), out);
}

void encode_control(bool start, bool abort, bool clear, std::vector<uint32_t>& out) {
  out.push_back(0x3u << 28 | uint32_t(clear) << 2 | uint32_t(abort) << 1 | uint32_t(start));
}

void encode_drivers(bool on, std::vector<uint32_t>& out) {
  out.push_back(0x3u << 28 | (on ? 1u << 3 : 1u << 4));
}

void encode_read(Register r, unsigned axis, std::vector<uint32_t>& out) {
  const uint32_t reg = uint32_t(r) + (r == Register::position0 ? axis : 0);
  out.push_back(0x4u << 28 | (reg & 0xFF));
}

size_t command_words(uint32_t first, unsigned axes, bool ptimer) {
  const uint32_t op = first >> 28;
  if (ptimer && op == 0x6) return 2 + ((first >> 24 & 1) ? 2 : 0) + ((first >> 27 & 1) ? 4 : 0);
  if (op != 0x1 && op != 0x5) return 1;
  const size_t k_words = op != 0x5 ? 0 : (first >> 18 & 1) ? 2 : 7;   // a continuation: K5, K6
  if (ptimer) {
    // The axis form: every axis's v, or (H0[15]) those of the mask H0[7:0]; then L.
    const size_t v_words = (first >> 15 & 1) ? size_t(std::popcount(first & 0xFFu)) : axes;
    return 2 + v_words + k_words + 1;
  }
  return 2 + axes + k_words + ((first >> 22 & 1) ? 3 : 2) * size_t(first & 0xFFFF);
}

Status decode_status(uint32_t w) {
  return {bool(w & 1), bool(w >> 1 & 1), bool(w >> 2 & 1), bool(w >> 3 & 1),
          w >> 8 & 0xFF, w >> 16 & 0xFF, w >> 24 & 0xFF, bool(w >> 4 & 1), bool(w >> 6 & 1), bool(w >> 7 & 1)};
}

ErrorName error_name(uint32_t code) {
  static const ErrorName names[] = {
      {"NONE", "no fault"},
      {"SEG_U", "U = 0 or U > UMAX"},
      {"SEG_V_GT_U", "some v_i > U"},
      {"SEG_K", "k > KMAX"},
      {"SEG_CHUNKS", "no chunk, or more than the chunk queue holds"},
      {"SEG_CHUNK_ZERO", "a chunk with interval 0 or count 0"},
      {"SEG_DELAY", "a chunk's delay interval + j*add + add2*j*(j-1)/2 outside 1..2^32-1"},
      {"SEG_COUNT_SUM", "the chunk counts do not sum to U*2^k"},
      {"SEG_PATTERN", "some U/gcd(U, v_i) exceeds the pattern capacity W"},
      {"UNDERRUN", "a segment without the end flag ended and no complete segment followed"},
      {"ESTOP", "the E-stop input"},
      {"ABORT", "CONTROL abort"},
      {"BAD_OPCODE", "an unknown command opcode"},
      {"CONFIG_BUSY", "CONFIG while running or while a STEP pulse is on a pin"},
      {"CONFIG_VALUE", "a step high or step low time of 0, a timing value too wide, an axis past N or a "
                       "field past 5"},
      {"SEG_ADD2", "a chunk whose increment add + j*add2 changes sign"},
      {"CONIC_AXES", "a conic segment's plane axes equal or not axes, or a v of theirs not 0"},
      {"CONIC_END", "a conic's walk arrived at its end before its last move, or not on it"},
      {"CONIC_CONTINUE", "a conic continuing a walk that does not follow a conic on its axes and way"},
      {"WATCHDOG", "no frame from the host for the watchdog's timeout"},
      {"LIMIT", "a segment moved an axis toward its active limit switch"},
      {"SEG_LENGTH", "a segment's length per move is 0 (phase-timer builds)"},
      {"SEG_FORM", "a segment's axis form H0[15:0] is neither 0 nor a compact form of axes the card has, "
                   "or sends the major axis (phase-timer builds)"},
  };
  if (code < std::size(names)) return names[code];
  return {"UNKNOWN", "an error code this program does not know"};
}

}  // namespace cpstep::card

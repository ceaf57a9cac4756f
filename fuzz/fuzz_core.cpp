// SPDX-License-Identifier: MIT
// Fuzz target: the golden model of the motion core (model/cp_core.h, with its
// command parser model/cp_cmd.h) fed command words, at the "small" build's
// parameters (rtl/builds.json: 2 axes, W = 32, UMAX = 4095, KMAX = 3, 8 chunks) so
// that queues fill and patterns overflow within short inputs.
//
// The input is a list of operations: a SEGMENT built from the bytes (near-valid
// by construction, with any field possibly out of range), a CONFIG, a CONTROL, a
// READ, a raw word, idle cycles (the reply port possibly stalled), the E-stop input
// held for a while, the limit and probe pins set (with CONFIG field 10, the seek), a
// reset, an URGENT feed HOLD / RESUME / OVERRIDE (the small build has FEED and INPUTS).
// Checked every cycle (docs/CORE.md):
//   - the status word is the live outputs (running, fault, stretched, E-stop,
//     drivers, code), fault <=> code != 0, bit 5 (torch) zero, bit 6 held as the
//     HOLD and RESUME sent say; held and no longer ramping, no move fires; the read port shows
//     the status, positions and the id; no reply data while no reply is valid; no
//     command taken while a reply waits;
//   - a latched code changes only through CLEAR (or reset); E-stop in t latches a
//     fault at t+1 (code 10 if none was latched) and drivers are off at t+1;
//   - while a fault is latched no segment is added to the queues;
//   - counters (moves, segments, stretches) never go down, positions move at most
//     one step a cycle;
//   - WATCHDOG (19) latches only after 4096 clocks or more with no word offered (each
//     stands for the frame that brought it: the watchdog's kick);
// and for each SEGMENT sent on an idle core with no fault, at a command boundary:
//   - the code it latches is the first failing check of CORE.md "Validation
//     order", computed here from the fields (0: none), or 8: the builder's
//     pattern check, which may fail for this segment or for an earlier one still
//     being built;
//   - a refused segment adds nothing to the queues; an accepted one adds one
//     segment and its chunks (all but the one the timer may take on loading it).
//     A watchdog that runs out meanwhile masks the verdict.
#include <cstdint>
#include <vector>

#include "cpstep/builds.h"
#include "fuzz_util.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"

using namespace cpstep;

namespace {

constexpr unsigned kMaxCycles = 6000;  // per input

struct Seg {
  uint32_t k = 0, u = 0, nchunks = 0;
  bool end = false, add2 = false;
  uint32_t dirs = 0;
  std::vector<uint32_t> v;
  struct Chunk {
    uint32_t interval = 0, count = 0;
    int32_t add = 0, add2 = 0;
  };
  std::vector<Chunk> chunks;

  std::vector<uint32_t> words() const {
    std::vector<uint32_t> w;
    w.push_back(1u << 28 | uint32_t(end) << 27 | (k & 0xF) << 23 | uint32_t(add2) << 22 | (nchunks & 0xFFFF));
    w.push_back(dirs << 24 | (u & 0xFFFFFF));
    for (uint32_t x : v) w.push_back(x & 0xFFFFFF);
    for (const Chunk& c : chunks) {
      w.push_back(c.interval);
      w.push_back(uint32_t(uint16_t(c.add)) << 16 | (c.count & 0xFFFF));
      if (add2) w.push_back(uint16_t(c.add2));
    }
    return w;
  }
};

// The code the core must latch for `s` (docs/CORE.md "Validation order"), 0 if none.
uint32_t expected_code(const Seg& s, const model::CpCoreParams& p) {
  if (s.k > p.kmax) return 3;
  if (s.nchunks == 0 || s.nchunks > (1u << p.caw)) return 4;
  if (s.u == 0 || s.u > p.umax) return 1;
  for (uint32_t v : s.v)
    if (v > s.u) return 2;
  uint64_t sum = 0;
  for (const Seg::Chunk& c : s.chunks) {
    if (c.interval == 0 || c.count == 0) return 5;
    const int64_t count = c.count, add = c.add, add2 = s.add2 ? c.add2 : 0;
    const int64_t last_inc = add + (count >= 2 ? (count - 2) * add2 : 0);
    if (add2 != 0 && ((add > 0 && last_inc < 0) || (add < 0 && last_inc > 0))) return 15;
    const int64_t q = (count - 1) * (add + last_inc);
    const int64_t last_delay = int64_t(c.interval) + q / 2;
    if (last_delay < 1 || last_delay > int64_t(0xFFFFFFFF)) return 6;
    sum += c.count;
  }
  if (sum != uint64_t(s.u) << s.k) return 7;
  return 0;
}

Seg make_segment(fuzz::Bytes& in, const model::CpCoreParams& p) {
  Seg s;
  const uint8_t shape = in.u8();
  s.u = (shape & 1) ? 1 + in.u16() % p.umax : 1 + in.u8() % 40;
  s.k = in.u8() % (p.kmax + 1);
  s.end = in.flag();
  s.dirs = in.u8();
  for (unsigned a = 0; a < p.n; ++a) {
    const uint8_t m = in.u8();
    s.v.push_back(m < 64 ? s.u : m < 128 ? 0 : in.u16() % (s.u + 1));
  }
  s.nchunks = 1 + in.u8() % 4;
  s.add2 = (shape & 2) != 0;
  uint64_t left = uint64_t(s.u) << s.k;
  for (uint32_t c = 0; c < s.nchunks; ++c) {
    Seg::Chunk ch;
    const uint32_t count = c + 1 == s.nchunks ? uint32_t(left) : uint32_t(std::max<uint64_t>(1, left / (s.nchunks - c)));
    ch.count = count & 0xFFFF;
    left -= std::min<uint64_t>(left, count);
    ch.interval = (shape & 4) ? in.u32() : 1 + in.u8();
    ch.add = (shape & 8) ? int16_t(in.u16()) : int8_t(in.u8()) / 8;
    ch.add2 = s.add2 ? ((shape & 16) ? int16_t(in.u16()) : int8_t(in.u8()) / 16) : 0;
    s.chunks.push_back(ch);
  }
  // One field possibly pushed out of its range.
  switch (in.u8() % 24) {
    case 0: s.k = p.kmax + 1 + in.u8() % (15 - p.kmax); break;
    case 1: s.nchunks = 0; s.chunks.clear(); break;
    case 2: {
      s.nchunks = (1u << p.caw) + 1 + in.u8() % 3;
      while (s.chunks.size() < s.nchunks) s.chunks.push_back({1, 1, 0, 0});
      break;
    }
    case 3: s.u = 0; break;
    case 4: s.u = p.umax + 1 + in.u8(); break;
    case 5: s.v[in.u8() % p.n] = s.u + 1 + in.u8(); break;
    case 6: s.chunks[in.u8() % s.chunks.size()].interval = 0; break;
    case 7: s.chunks[in.u8() % s.chunks.size()].count = 0; break;
    case 8: s.chunks[in.u8() % s.chunks.size()].count += 1; break;
    case 9: s.chunks[in.u8() % s.chunks.size()].interval = 0xFFFFFFFF - in.u8(); break;
    default: break;
  }
  return s;
}

struct Harness {
  model::CpCoreParams p = model::core_params(builds::small);
  model::CpCore core{p};
  unsigned cycles = 0;
  bool estop = false, rsp_ready = true;
  uint32_t rd_addr = 0;
  model::CpCoreOut prev{};
  bool have_prev = false, prev_estop = false, prev_clear = false, prev_rst = false;
  bool aligned = true;  // the parser is at a command boundary (as far as we know)
  uint64_t since_kick = 0;  // clocks since the last word offered (the watchdog's kick)
  uint32_t feed = 0;        // this clock's URGENT feed bits: 1 HOLD, 2 RESUME, 4 OVERRIDE (value in [31:16])
  bool held = false;        // HOLD sent and no RESUME since (nor reset)
  uint32_t pins = 0;        // the input pins: [1:0] limit min, [3:2] limit max, [4] probe

  bool out_of_time() const { return cycles >= kMaxCycles; }

  // One clock with `word` offered (or none); true when it was taken.
  bool step(bool valid, uint32_t word, bool rst = false) {
    core.in.rst = rst;
    core.in.cmd_valid = valid;
    core.in.cmd_data = word;
    core.in.rsp_ready = rsp_ready;
    core.in.estop = estop;
    core.in.lim_min = pins & 3;
    core.in.lim_max = pins >> 2 & 3;
    core.in.probe = (pins >> 4 & 1) != 0;
    // A word handed over stands for a frame that brought it: the watchdog's kick
    // (CONFIG field 5 may set a timeout; idle spans may outlast it).
    core.in.kick = valid;
    core.in.ctl_hold = feed & 1;
    core.in.ctl_resume = feed >> 1 & 1;
    core.in.ctl_ovr = feed >> 2 & 1;
    core.in.ctl_ovr_val = feed >> 16;
    static constexpr uint32_t kRegs[] = {0x00, 0x10, 0x11, 0x1F, 0x01, 0x02, 0x03};
    core.in.rd_addr = kRegs[rd_addr++ % std::size(kRegs)];
    const model::CpCoreOut o = core.outputs();
    check(o);
    const bool taken = valid && o.cmd_ready && !rst;
    // WATCHDOG latches only after a whole timeout (4096 clocks at least) with no kick.
    if (o.err_code == 19 && !(have_prev && prev.err_code == 19))
      FUZZ_CHECK(since_kick >= 4096, "WATCHDOG after %llu clocks without a kick", (unsigned long long)since_kick);
    since_kick = valid ? 0 : since_kick + 1;
    prev = o;
    have_prev = true;
    prev_estop = estop;
    prev_rst = rst;
    if (rst) held = false;
    if (!rst && (feed & 2)) held = false;
    if (!rst && (feed & 1)) held = true;
    feed = 0;
    prev_clear = taken && word >> 28 == 3 && (word >> 2 & 1);
    core.tick();
    ++cycles;
    return taken;
  }

  void check(const model::CpCoreOut& o) const {
    const uint32_t st = o.status;
    FUZZ_CHECK((st & 1) == o.running && (st >> 1 & 1) == o.fault && (st >> 2 & 1) == o.stretched &&
                   (st >> 3 & 1) == estop && (st >> 4 & 1) == o.enable && (st >> 5 & 1) == 0 &&
                   (st >> 8 & 0xFF) == o.err_code,
               "status 0x%08x vs the outputs", st);
    FUZZ_CHECK(o.fault == (o.err_code != 0), "fault %d with code %u", o.fault, o.err_code);
    const uint32_t a = core.in.rd_addr;
    if (a == 0x00) FUZZ_CHECK(o.rd_data == o.status, "read port status 0x%08x vs 0x%08x", o.rd_data, o.status);
    if (a == 0x10 || a == 0x11)
      FUZZ_CHECK(o.rd_data == uint32_t(o.position[a - 0x10]), "read port position %u", a - 0x10);
    if (a == 0x1F) FUZZ_CHECK(o.rd_data == 0x43505331u, "id 0x%08x", o.rd_data);
    if (a == 0x01) FUZZ_CHECK(o.rd_data == o.stretch_count, "read port stretch");
    if (a == 0x02) FUZZ_CHECK(o.rd_data == o.moves_done, "read port moves");
    if (a == 0x03) FUZZ_CHECK(o.rd_data == o.segments_done, "read port segments");
    if (!o.rsp_valid) FUZZ_CHECK(o.rsp_data == 0 && o.rsp_addr == 0, "reply data without a reply");
    if (o.rsp_valid) FUZZ_CHECK(!o.cmd_ready, "a command taken while a reply waits");
    if (!have_prev || prev_rst) return;
    if (prev.fault && !prev_clear) FUZZ_CHECK(o.err_code == prev.err_code, "code %u became %u without CLEAR",
                                              prev.err_code, o.err_code);
    if (prev_estop) {
      FUZZ_CHECK(o.fault && !o.enable, "E-stop: fault %d drivers %d", o.fault, o.enable);
      if (!prev.fault) FUZZ_CHECK(o.err_code == 10, "E-stop latched code %u", o.err_code);
    }
    if (prev.fault && !prev_clear)
      FUZZ_CHECK((o.status >> 16 & 0xFF) <= (prev.status >> 16 & 0xFF), "segments queued %u -> %u with a fault",
                 prev.status >> 16 & 0xFF, o.status >> 16 & 0xFF);
    FUZZ_CHECK((o.status >> 6 & 1) == held, "status held %u, but HOLD/RESUME say %d", o.status >> 6 & 1, held);
    // Held and at a stand (the scale 0): nothing falls due.
    if ((prev.status >> 6 & 3) == 1)
      FUZZ_CHECK(o.moves_done == prev.moves_done, "a move fired while held at a stand");
    FUZZ_CHECK(o.moves_done >= prev.moves_done && o.segments_done >= prev.segments_done &&
                   o.stretch_count >= prev.stretch_count,
               "a counter went down");
    for (unsigned i = 0; i < p.n; ++i) {
      const int64_t d = o.position[i] - prev.position[i];
      FUZZ_CHECK(d >= -1 && d <= 1, "axis %u moved %lld in a cycle", i, (long long)d);
    }
  }

  // Offers the words in order; false when one was not taken within `patience` cycles.
  bool send(const std::vector<uint32_t>& words, unsigned patience = 400) {
    for (uint32_t w : words) {
      unsigned waited = 0;
      while (!step(true, w)) {
        if (++waited >= patience || out_of_time()) return false;
      }
    }
    return true;
  }

  void idle(unsigned n) {
    for (unsigned i = 0; i < n && !out_of_time(); ++i) step(false, 0);
  }

  void segment(fuzz::Bytes& in) {
    const Seg s = make_segment(in, p);
    const model::CpCoreOut before = core.outputs();
    const bool judge = aligned && !before.fault && !before.running && !estop;
    const uint32_t want = expected_code(s, p);
    bool stayed_idle = true;
    const std::vector<uint32_t> w = s.words();
    unsigned waited = 0;
    bool ok = true;
    for (size_t i = 0; i < w.size() && ok;) {
      if (step(true, w[i])) {
        ++i;
        waited = 0;
      } else if (++waited >= 400 || out_of_time()) {
        ok = false;
      }
      stayed_idle = stayed_idle && !prev.running;
    }
    if (!ok) {
      aligned = false;  // the parser is inside the segment
      return;
    }
    // The last chunk's check: 51 clocks (docs/CORE.md "Command port"), the commit on
    // the last; then the status shows it (14 clocks of margin). The wait was 48
    // clocks for the 34-clock check before it became bit-serial (issue 11), and the
    // target then stopped short of the commit and called an accepted segment lost.
    for (unsigned i = 0; i < 51 + 14 && !out_of_time(); ++i) {
      step(false, 0);
      stayed_idle = stayed_idle && !prev.running;
    }
    if (!judge || !stayed_idle || out_of_time()) return;
    const model::CpCoreOut after = core.outputs();
    if (after.err_code == 19) return;  // the watchdog ran out meanwhile: its latch masks the verdict
    const uint32_t q0 = before.status >> 16 & 0xFF, q1 = after.status >> 16 & 0xFF;
    const uint32_t c0 = before.status >> 24, c1 = after.status >> 24;
    if (want != 0) {
      // 8 is the builder's: an earlier segment's pattern may overflow W while this one arrives.
      FUZZ_CHECK(after.err_code == want || after.err_code == 8, "segment refused with code %u, expected %u",
                 after.err_code, want);
      FUZZ_CHECK(q1 <= q0 && c1 <= c0, "a refused segment queued: segments %u -> %u, chunks %u -> %u", q0, q1, c0,
                 c1);
    } else {
      FUZZ_CHECK(after.err_code == 0 || after.err_code == 8, "a valid segment latched code %u", after.err_code);
      if (after.err_code == 0)
        // The timer may take the first chunk of a loaded segment (chunks queued do not count it).
        FUZZ_CHECK(q1 == q0 + 1 && c1 <= c0 + s.nchunks && c1 + 1 >= c0 + s.nchunks,
                   "an accepted segment: segments %u -> %u, chunks %u -> %u (+%u)", q0, q1, c0, c1, s.nchunks);
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  Harness h;
  h.step(false, 0, true);
  while (!in.empty() && !h.out_of_time()) {
    const uint8_t op = in.u8();
    switch (op % 10) {
      case 0:
      case 1:
      case 2: h.segment(in); break;
      case 3: {  // CONFIG: axis, field, value
        // Fields 0..10: pulse timing, polarity, the watchdog, the inputs, the feed ramp's
        // tick, the seek (docs/CORE.md; the small build has FEED and INPUTS).
        const uint32_t w = 2u << 28 | (in.u8() % 3u) << 24 | (in.u8() % 11u) << 20 | in.u16();
        h.send({w});
        break;
      }
      case 4: {  // CONTROL: start, abort, clear, drivers on, off; with bits 7:5, URGENT feed bits instead
        const uint8_t b = in.u8();
        if (b & 0xE0) {
          h.feed = uint32_t(b >> 5) | uint32_t(b & 0x1F) << 26;  // OVERRIDE values 0..0x7C00
          h.idle(1);
        } else {
          h.send({3u << 28 | b});
        }
        break;
      }
      case 5: {  // READ
        h.send({4u << 28 | in.u8()});
        break;
      }
      case 6: {  // any word
        const uint32_t w = in.u32();
        if (h.send({w}) && w >> 28 == 1) h.aligned = false;  // inside a segment now
        break;
      }
      case 7: {  // idle, the reply port maybe stalled
        h.rsp_ready = !(op & 0x80);
        h.idle(1 + in.u8() * 4u);
        h.rsp_ready = true;
        break;
      }
      case 8: {  // E-stop held; with bit 7, the limit and probe pins set instead
        if (op & 0x80) {
          h.pins = in.u8() & 0x1F;
          h.idle(1 + in.u8() % 32u);
          break;
        }
        h.estop = true;
        h.idle(1 + in.u8() % 16u);
        h.estop = false;
        break;
      }
      default:
        h.step(false, 0, true);
        h.aligned = true;
        break;
    }
  }
  return 0;
}

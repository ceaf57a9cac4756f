// SPDX-License-Identifier: MIT
// The motion core's bench: host-like random jobs, and a harness that runs them on
// RTL and model in lockstep with the independent pin checker watching.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <verilated.h>

#include "card/protocol.h"
#include "common/lockstep.h"
#include "core/core_checker.h"
#include "sim/core_driver.h"

namespace cpstep::tb {

// A Verilated core that has had one clock edge in reset when constructed. Outputs
// before the first reset edge are not part of the contract (docs/CORE.md): the
// benches whose cores start from other power-up states than x-initial 0 (random
// initial values, a synthesized netlist) run from that edge on.
template <class V>
class AfterOneResetEdge : public V {
 public:
  explicit AfterOneResetEdge(VerilatedContext* ctx, const char* name = "TOP") : V(ctx, name) {
    this->rst = 1;
    this->clk = 0;
    this->eval();
    this->clk = 1;
    this->eval();
    this->clk = 0;
    this->eval();
  }
};

inline uint64_t core_seed(uint64_t fallback) {
  const char* s = std::getenv("CPSTEP_SEED");
  return s ? std::strtoull(s, nullptr, 0) : fallback;
}

struct AxisTiming {
  uint32_t high = 1, low = 1, setup = 1, hold = 1;
  bool step_pol = true, dir_pol = true;
};

// What a job generator may produce.
struct JobShape {
  uint32_t max_moves = 3000;  // largest U·2^k of a segment
  uint32_t max_delay = 40;    // typical delays are 1..max_delay
  uint32_t max_timing = 50;   // pulse timing fields up to this
  unsigned max_chunks = 16;   // chunks per segment
  double add2 = 0.4;          // chance a segment's chunks carry add2 (three words each)
};

// Random jobs the way a host makes them (docs/CORE.md, "Command port").
class JobGen {
 public:
  JobGen(const model::CpCoreParams& p, uint64_t seed) : p_(p), rng_(seed) {}

  uint32_t uniform(uint32_t lo, uint32_t hi) { return std::uniform_int_distribution<uint32_t>(lo, hi)(rng_); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  std::mt19937_64& rng() { return rng_; }

  AxisTiming timing(uint32_t max_timing) {
    AxisTiming t;
    auto pick = [&](uint32_t lo) {
      const uint32_t r = uniform(0, 9);
      return r < 4 ? uniform(lo, std::min<uint32_t>(3, max_timing)) : uniform(lo, max_timing);
    };
    t.high = pick(1);
    t.low = pick(1);
    t.setup = pick(0);
    t.hold = pick(0);
    t.step_pol = chance(0.5);
    t.dir_pol = chance(0.5);
    return t;
  }

  // Integer deltas per axis, then what the host sends for them: major = first index
  // of max |d|, k = min(KMAX, common trailing zeros), U = T >> k, v_i = |d_i| >> k.
  card::WireSegment segment(const JobShape& shape, bool end) {
    for (;;) {
      const std::vector<int64_t> d = deltas(shape);
      card::WireSegment s;
      if (!from_deltas(d, s)) continue;
      s.end = end;
      s.chunks = chunks(uint64_t(s.u) << s.k, shape, chance(shape.add2));
      // The torch output (docs/CORE.md "Torch") on a quarter of the segments, from
      // what was drawn (so the random streams of the benches stay as they were).
      s.torch = ((s.u ^ uint32_t(s.chunks.size())) & 3) == 1;
      return s;
    }
  }

  // The host's reduction; false if the segment is empty or would not fit the card.
  bool from_deltas(const std::vector<int64_t>& d, card::WireSegment& s) const {
    uint64_t t = 0, common = 0;
    for (int64_t x : d) {
      const uint64_t m = uint64_t(x < 0 ? -x : x);
      t = std::max(t, m);
      common |= m;
    }
    if (t == 0) return false;
    const unsigned k = std::min<unsigned>(p_.kmax, unsigned(std::countr_zero(common)));
    s.u = uint32_t(t >> k);
    s.k = k;
    if (s.u > p_.umax) return false;
    s.v.clear();
    s.dir_positive.clear();
    for (int64_t x : d) {
      const uint32_t v = uint32_t(uint64_t(x < 0 ? -x : x) >> k);
      if (s.u / std::gcd(s.u, v) > p_.w) return false;
      s.v.push_back(v);
      s.dir_positive.push_back(x > 0 || (x == 0 && (std::hash<uint64_t>{}(t) & 1)));
    }
    return true;
  }

  std::vector<int64_t> deltas(const JobShape& shape) {
    const unsigned r = uniform(0, 99);
    uint32_t moves = r < 15   ? uniform(1, 4)
                     : r < 55 ? uniform(5, 60)
                     : r < 90 ? uniform(60, 400)
                              : uniform(400, 3000);
    moves = std::min(moves, shape.max_moves);
    unsigned m = 0;  // doubling
    if (chance(0.35)) m = uniform(0, std::min<unsigned>(p_.kmax + 1, unsigned(std::bit_width(moves)) - 1));
    const uint32_t base = std::max<uint32_t>(1, moves >> m);
    std::vector<int64_t> d(p_.n);
    const unsigned major = uniform(0, p_.n - 1);
    for (unsigned a = 0; a < p_.n; ++a) {
      uint32_t mag;
      const unsigned c = uniform(0, 99);
      if (a == major) mag = base;
      else if (c < 20) mag = 0;
      else if (c < 30) mag = base;                                // ties with the major
      else if (c < 40 && a > 0) mag = uint32_t(std::abs(d[a - 1]) >> m);  // equal axes
      else if (c < 55) mag = base / uniform(1, 8) * uniform(0, 1);  // simple ratios
      else mag = uniform(0, base);
      mag = std::min(mag, base);
      d[a] = int64_t(uint64_t(mag) << m) * (chance(0.5) ? 1 : -1);
    }
    return d;
  }

  // Chunks whose counts sum to `moves`, every delay in 1..2^32-1: constant runs,
  // ramps either way, runs of delay 1 (stretches), now and then long waits; with
  // `add2`, also curved runs (quadratic_chunk) and some add2 where it changes nothing.
  std::vector<card::WireChunk> chunks(uint64_t moves, const JobShape& shape, bool add2 = false) {
    const unsigned most = unsigned(std::min<uint64_t>(shape.max_chunks, moves));
    unsigned n = chance(0.5) ? 1 : uniform(1, most);
    if (add2 && moves >= 8 && chance(0.5)) n = std::max(n, unsigned(std::min<uint64_t>(most, moves / 40 + 1)));
    n = std::max<unsigned>(n, unsigned((moves + 65534) / 65535));
    std::vector<uint64_t> cut = {0, moves};
    while (cut.size() < n + 1) {
      const uint64_t c = std::uniform_int_distribution<uint64_t>(1, moves - 1)(rng_);
      if (std::find(cut.begin(), cut.end(), c) == cut.end()) cut.push_back(c);
    }
    std::sort(cut.begin(), cut.end());
    std::vector<card::WireChunk> out;
    for (size_t i = 0; i + 1 < cut.size(); ++i) {
      card::WireChunk c;
      c.count = uint16_t(cut[i + 1] - cut[i]);
      const unsigned style = uniform(0, 9);
      const uint32_t top = style == 0 ? 2 : style == 1 ? 4 * shape.max_delay : shape.max_delay;
      const int64_t first = uniform(1, top), last = uniform(1, top);
      int64_t add = c.count > 1 ? (last - first) / int64_t(c.count - 1) : int64_t(uniform(0, 200)) - 100;
      add = std::clamp<int64_t>(add, -32768, 32767);
      if (first + int64_t(c.count - 1) * add < 1) add = 0;
      c.interval = uint32_t(first);
      c.add = int16_t(add);
      // add2 on a chunk of 1 or 2 moves changes no delay (only a third move would see it).
      if (add2 && c.count <= 2 && chance(0.3)) c.add2 = int16_t(int32_t(uniform(0, 65535)) - 32768);
      if (add2 && c.count >= 3 && c.count <= 48 && chance(0.7)) c = quadratic_chunk(c.count, shape);
      out.push_back(c);
    }
    return out;
  }

  // A chunk of `count` >= 3 moves with add2 != 0 and every increment
  // add + i·add2 (i = 0..count-2) of one sign (or 0): delays rising or falling,
  // the increments' magnitudes growing or shrinking, the smallest delay often 1.
  card::WireChunk quadratic_chunk(uint32_t count, const JobShape& shape) {
    const int64_t s = chance(0.5) ? 1 : -1;             // the increments' sign
    const bool grows = chance(0.5);                     // |increment| grows along the chunk
    const int64_t b = count <= 6 && chance(0.3) ? uniform(1, 500) : uniform(1, 2);
    const int64_t e = chance(0.5) ? 0 : uniform(0, 5);  // the smallest |increment|
    const int64_t m = count - 1;                        // increments
    auto inc = [&](int64_t i) { return s * (e + b * (grows ? i : m - 1 - i)); };
    const int64_t total = s * (m * e + b * m * (m - 1) / 2);  // sum of the increments
    const int64_t smallest = chance(0.4) ? 1 : uniform(1, shape.max_delay);
    card::WireChunk c;
    c.count = uint16_t(count);
    c.interval = uint32_t(s > 0 ? smallest : smallest - total);  // delay 0 or the last delay
    c.add = int16_t(inc(0));
    c.add2 = int16_t(inc(1) - inc(0));
    return c;
  }

  // Cycles the parser takes after a chunk's last word before it takes the next word
  // (docs/CORE.md, "Cycle behaviour"): the bit-serial check's clocks, whatever the
  // chunk's values.
  static constexpr uint64_t kCheckCycles = 51;
  static uint64_t check_cycles(const card::WireChunk&) { return kCheckCycles; }
  // Cycles the parser needs for a segment.
  uint64_t parse_cycles(const card::WireSegment& s) const {
    bool three = false;
    for (const auto& ch : s.chunks) three = three || ch.add2 != 0;
    uint64_t c = 2 + p_.n;
    for (const auto& ch : s.chunks) c += (three ? 3 : 2) + check_cycles(ch);
    return c;
  }
  static uint64_t programmed_cycles(const card::WireSegment& s) {
    uint64_t t = 0;
    for (const auto& c : s.chunks)
      for (int64_t j = 0; j < c.count; ++j)
        t += uint64_t(int64_t(c.interval) + j * c.add + int64_t(c.add2) * j * (j - 1) / 2);
    return t;
  }

  // A job: segments long enough, each, for the next one to arrive in time (the host
  // keeps the card fed), the last with the end flag.
  std::vector<card::WireSegment> job(unsigned segments, const JobShape& shape) {
    std::vector<card::WireSegment> j;
    for (unsigned i = 0; i < segments; ++i) j.push_back(segment(shape, i + 1 == segments));
    for (unsigned i = 0; i + 1 < j.size(); ++i) {
      const uint64_t need = 3 * parse_cycles(j[i + 1]) + 60;
      const uint64_t have = programmed_cycles(j[i]);
      if (have < need) {
        // A dwell before the segment's first move (a host would plan it as a pause).
        card::WireChunk& c = j[i].chunks.front();
        c.interval += uint32_t(need - have);
      }
    }
    return j;
  }

 private:
  model::CpCoreParams p_;
  std::mt19937_64 rng_;
};

// One lockstep pair, its driver and the checker; a fresh one per batch.
template <class P>
class CoreHarness {
 public:
  using Dut = Lockstep<P>;

  CoreHarness(const std::string& name, uint64_t seed)
      : params(P::model_params()),
        gen(params, seed),
        ls(name),
        chk(params),
        drv(ls, [this](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut& o) {
          chk.observe(c, in, o);
          rsp_contract.check(c, o.rsp_valid, in.rsp_ready, o.rsp_data);
          last_in = in;
          ++cycles;
          if (hook) hook(c, in, o);
        }) {
    drv.reset();
  }

  model::CpCoreParams params;
  JobGen gen;
  Dut ls;
  CoreChecker chk;
  StreamContract rsp_contract{"rsp (reply stream)"};
  sim::CoreDriver<Dut> drv;
  model::CpCoreIn last_in;
  uint64_t cycles = 0;
  double word_gap = 0.1;   // chance of an idle cycle before a command word
  double rsp_stall = 0.3;  // chance rsp_ready is low in a cycle
  bool expecting = true;   // segment() tells the checker (off once a fault drops them)
  uint32_t stretch_slack = 0;  // moves counted late that never fired (a fault cut them)
  uint64_t late_at_clear = 0;  // late moves seen before the last CLEAR (it drops the flag)
  // Called after the checker on every cycle (fault injection, edge timing).
  std::function<void(uint64_t, const model::CpCoreIn&, const model::CpCoreOut&)> hook;

  // Words in with valid/ready, now and then an idle cycle in between; returns the
  // cycle in which the last word was taken.
  uint64_t send(const std::vector<uint32_t>& words, uint64_t max_wait = 2'000'000) {
    uint64_t taken = 0;
    for (uint32_t w : words) {
      while (gen.chance(word_gap)) drv.step({});
      model::CpCoreIn in;
      in.cmd_valid = true;
      in.cmd_data = w;
      for (uint64_t n = 0;; ++n) {
        if (n > max_wait) throw std::runtime_error("cp_core did not take a command word");
        const uint64_t c = ls.cycle();
        if (drv.step(in).cmd_ready) {
          taken = c;
          break;
        }
      }
    }
    return taken;
  }
  uint32_t read(card::Register r, unsigned axis = 0) {
    std::vector<uint32_t> w;
    card::encode_read(r, axis, w);
    send(w);
    for (int n = 0; n < 1000; ++n) {
      model::CpCoreIn in;
      in.rsp_ready = !gen.chance(rsp_stall);
      const auto o = drv.step(in);
      if (o.rsp_valid && in.rsp_ready) return o.rsp_data;
    }
    ADD_FAILURE() << "no reply to READ " << uint32_t(r);
    return 0;
  }
  card::Status status() { return card::decode_status(read(card::Register::status)); }

  void configure(unsigned axis, const AxisTiming& t) {
    std::vector<uint32_t> w;
    card::encode_config(axis, card::ConfigField::step_high, t.high, w);
    card::encode_config(axis, card::ConfigField::step_low, t.low, w);
    card::encode_config(axis, card::ConfigField::dir_setup, t.setup, w);
    card::encode_config(axis, card::ConfigField::dir_hold, t.hold, w);
    card::encode_config(axis, card::ConfigField::polarity, uint32_t(t.step_pol) | uint32_t(t.dir_pol) << 1, w);
    send(w);
  }
  void configure_all(const AxisTiming& t) {
    for (unsigned a = 0; a < params.n; ++a) configure(a, t);
  }
  // CONFIG is refused while a STEP pulse is on a pin (docs/CORE.md, code 13): a
  // host configures between jobs only once the last pulse has ended.
  void configure_random(uint32_t max_timing) {
    for (uint64_t n = 0; chk.pulse_high() && n < 100000; ++n) idle(1);
    for (unsigned a = 0; a < params.n; ++a) configure(a, gen.timing(max_timing));
  }
  uint64_t control(bool start, bool abort, bool clear) {
    std::vector<uint32_t> w;
    card::encode_control(start, abort, clear, w);
    const uint64_t taken = send(w);
    if (clear) late_at_clear = chk.late_moves();  // (a CLEAR refused under E-stop is followed by another)
    return taken;
  }
  // The out-of-band ACK (docs/PROTOCOL.md "Out of band"): one cycle of ctl_ack_i.
  void ack() {
    model::CpCoreIn in;
    in.ctl_ack = true;
    drv.step(in);
    late_at_clear = chk.late_moves();
  }
  // A segment the core must run (expect) or must refuse/drop (!expect).
  uint64_t segment(const card::WireSegment& s, bool expect = true) {
    std::vector<uint32_t> w;
    card::encode_segment(s, w);
    if (expect && expecting) chk.expect(s);
    return send(w);
  }
  void idle(uint64_t n) { drv.idle(n); }
  // Steps until the core is stopped and the checker has seen every expected move.
  void finish(uint64_t max_cycles = 20'000'000) {
    for (uint64_t n = 0; n < max_cycles; ++n) {
      if (!drv.last().running && chk.queue_empty() && n > 0) return;
      drv.step({});
    }
    ADD_FAILURE() << "the core did not finish its segments in " << max_cycles << " cycles";
  }

  // A random job streamed to a running core: a few segments before START (within
  // what the queues hold), the rest while it runs.
  void play(const std::vector<card::WireSegment>& job) {
    const unsigned cap = 1u << params.caw;
    size_t i = 0, chunks = 0;
    while (i < job.size() && i < 4 && chunks + job[i].chunks.size() <= cap) {
      chunks += job[i].chunks.size();
      segment(job[i++]);
    }
    control(true, false, false);
    for (; i < job.size(); ++i) segment(job[i]);
    finish();
  }

  // Steps until pred(outputs) holds; false after max_cycles.
  template <class Pred>
  bool wait_for(Pred pred, uint64_t max_cycles) {
    for (uint64_t n = 0; n < max_cycles; ++n)
      if (pred(drv.step({}))) return true;
    return false;
  }

  // Counters and positions agree with what the pins showed.
  void expect_counters(const std::string& where) {
    EXPECT_TRUE(chk.errors().empty()) << where << ": the pin checker found\n" << chk.report();
    EXPECT_EQ(read(card::Register::moves_done), uint32_t(chk.moves()))
        << where << ": moves done (register) vs move events seen on the pins";
    EXPECT_EQ(read(card::Register::segments_done), uint32_t(chk.segments_done()))
        << where << ": segments done (register) vs segments the pins completed";
    const uint32_t stretches = read(card::Register::stretch_count);
    EXPECT_GE(stretches, uint32_t(chk.late_moves())) << where << ": stretch counter vs moves seen late";
    EXPECT_LE(stretches, uint32_t(chk.late_moves()) + stretch_slack)
        << where << ": stretch counter vs moves the checker saw late";
    for (unsigned a = 0; a < params.n; ++a)
      EXPECT_EQ(int32_t(read(card::Register::position0, a)), int32_t(chk.position(a)))
          << where << ": position register of axis " << a << " vs pulses on its pins";
  }
  // After a clean run: stopped, no fault, queues empty, flag and counters right.
  void expect_consistent(const std::string& where) {
    const card::Status st = status();
    EXPECT_FALSE(st.fault) << where << ": fault code " << st.err_code;
    EXPECT_FALSE(st.running) << where;
    EXPECT_EQ(st.segments_queued, 0u) << where << ": segments left queued";
    EXPECT_EQ(st.chunks_queued, 0u) << where << ": chunks left queued";
    EXPECT_EQ(st.stretched, chk.late_moves() > late_at_clear) << where << ": stretched flag";
    expect_counters(where);
  }
};

}  // namespace cpstep::tb

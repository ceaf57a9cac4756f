// SPDX-License-Identifier: MIT
// bench_core — motion core figures for docs/BENCHMARKS.md (run by scripts/bench).
// Everything runs on the Verilated cp_core at its defaults (4 axes, W = 1024) with
// the tightest pulse timing (STEP high 1, low 1, DIR setup 1, hold 1). Cycle
// counts are read off the pins and are exact; speeds are wall-clock.
#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "Vcp_core_hx8k.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"

using namespace cpstep;

namespace {

constexpr unsigned kAxes = 4;
struct CoreRtl : sim::CorePortBase<Vcp_core_hx8k, kAxes> {};
using Dut = sim::RtlDut<CoreRtl>;
using Driver = sim::CoreDriver<Dut>;

// Leading STEP edges per axis, by cycle (STEP active high).
struct Pins {
  uint32_t prev = 0;
  std::array<std::vector<uint64_t>, kAxes> rises;
  void operator()(uint64_t cycle, const model::CpCoreIn&, const model::CpCoreOut& o) {
    const uint32_t r = o.step & ~prev;
    for (unsigned a = 0; a < kAxes; ++a)
      if (r >> a & 1) rises[a].push_back(cycle);
    prev = o.step;
  }
};

// A fresh core with the tightest pulse timing, and its pin log.
struct Bench {
  Dut dut;
  Pins pins;
  Driver drv{dut, std::ref(pins)};
  Bench() {
    drv.reset();
    std::vector<uint32_t> w;
    for (unsigned a = 0; a < kAxes; ++a)
      for (auto f : {card::ConfigField::step_high, card::ConfigField::step_low,
                     card::ConfigField::dir_setup, card::ConfigField::dir_hold})
        card::encode_config(a, f, 1, w);
    drv.send(w);
  }
  void send(const card::WireSegment& s) {
    std::vector<uint32_t> w;
    card::encode_segment(s, w);
    drv.send(w);
  }
  void start() {
    std::vector<uint32_t> w;
    card::encode_control(true, false, false, w);
    drv.send(w);
  }
  // Idles until the core is not running (it may have stopped already, e.g. on a fault).
  void finish(uint64_t max_cycles) {
    drv.step({});
    for (uint64_t n = 0; drv.last().running; ++n) {
      if (n == max_cycles) throw std::runtime_error("cp_core still running");
      drv.step({});
    }
  }
  uint32_t stretches() { return drv.read(card::Register::stretch_count); }
  uint32_t error() { return card::decode_status(drv.read(card::Register::status)).err_code; }
};

// A segment of `moves` = u * 2^k moves in chunks of at most 65535 moves, all
// with the same interval.
card::WireSegment segment(uint32_t u, unsigned k, std::array<uint32_t, kAxes> v, uint32_t interval,
                          bool end) {
  card::WireSegment s;
  s.u = u;
  s.k = k;
  s.end = end;
  s.dir_positive.assign(kAxes, true);
  s.v.assign(v.begin(), v.end());
  for (uint64_t left = uint64_t(u) << k; left > 0;) {
    const uint16_t n = uint16_t(std::min<uint64_t>(left, 65535));
    s.chunks.push_back({interval, n, 0});
    left -= n;
  }
  return s;
}

const char* kAxisName[] = {"x", "y", "z", "a"};

// ---------------------------------------------------------------- step rate
void step_rate() {
  fmt::print("### Maximum step rate\n\n");
  fmt::print("One segment of 4096 moves (U = 1024, k = 2), built before START, every chunk "
             "with the given interval. Rate = (steps − 1) / (cycles from the first to the last "
             "leading STEP edge).\n\n");
  fmt::print("| axes stepping | interval | steps (all axes) | cycles first..last edge | steps per clock | "
             "stretch count |\n|---|---:|---:|---:|---:|---:|\n");
  const auto run = [](std::array<uint32_t, kAxes> v, uint32_t interval, const std::string& label) {
    Bench b;
    b.send(segment(1024, 2, v, interval, true));
    b.drv.idle(2000);
    b.start();
    b.finish(1'000'000);
    uint64_t steps = 0, first = UINT64_MAX, last = 0;
    unsigned stepping = 0;
    for (const auto& r : b.pins.rises) {
      if (r.empty()) continue;
      ++stepping;
      steps += r.size();
      first = std::min(first, r.front());
      last = std::max(last, r.back());
    }
    // Every stepping axis steps at every move: the span covers (moves − 1) periods.
    const double per_clock = double(steps - stepping) / double(last - first);
    fmt::print("| {} | {} | {} | {} | {:.3f} | {} |\n", label, interval, steps, last - first, per_clock,
               b.stretches());
  };
  for (unsigned a = 0; a < kAxes; ++a) {
    std::array<uint32_t, kAxes> v{};
    v[a] = 1024;
    for (uint32_t interval : {1u, 2u}) run(v, interval, kAxisName[a]);
  }
  for (uint32_t interval : {1u, 2u}) run({1024, 1024, 1024, 1024}, interval, "x y z a (aggregate)");
  fmt::print("\nWith STEP high 1 and low 1 a pulse occupies 2 cycles, so one axis steps at most every "
             "other clock; at interval 1 every move after the first is delayed by a cycle and counted "
             "as a stretch (SPEC §2: delayed, never dropped).\n\n");
}

// ---------------------------------------------------------------- back to back
struct StreamResult {
  uint64_t moves = 0, span = 0, gap_min = UINT64_MAX, gap_max = 0, inner_max = 0;
  uint32_t stretches = 0, error = 0, segments_done = 0;
};

// `count` segments of u moves (x steps at every move, y once per segment: the
// pattern u/gcd = u is the longest), `preload` of them sent before START.
StreamResult stream(uint32_t u, unsigned count, unsigned preload, uint32_t interval) {
  Bench b;
  const auto seg = [&](unsigned i) { return segment(u, 0, {u, 1, 0, 0}, interval, i + 1 == count); };
  unsigned sent = 0;
  for (; sent < std::min(preload, count); ++sent) b.send(seg(sent));
  b.drv.idle(3000);
  b.start();
  for (; sent < count; ++sent) b.send(seg(sent));
  b.finish(10'000'000);
  StreamResult r;
  const auto& x = b.pins.rises[0];
  r.moves = x.size();
  r.span = x.empty() ? 0 : x.back() - x.front();
  for (size_t i = 1; i < x.size(); ++i) {
    const uint64_t d = x[i] - x[i - 1];
    if (i % u == 0) {
      r.gap_min = std::min(r.gap_min, d);
      r.gap_max = std::max(r.gap_max, d);
    } else {
      r.inner_max = std::max(r.inner_max, d);
    }
  }
  r.stretches = b.stretches();
  r.error = b.error();
  r.segments_done = b.drv.read(card::Register::segments_done);
  return r;
}

// How many segments the card queues before START. When its queues (segment queue,
// built lanes) are full it still takes one more segment's words, then holds that
// one in the command parser, which blocks the port (START included): that last
// one does not count.
// Also the command port's pace for one-chunk segments of 8 moves while the queue
// has room: cycles from taking one segment's first word to the next one's.
struct Capacity {
  unsigned segments;
  double cycles_per_segment;
};
Capacity queue_capacity() {
  Bench b;
  std::vector<uint64_t> taken;  // cycle each segment's sending began
  for (unsigned n = 0;; ++n) {
    std::vector<uint32_t> w;
    card::encode_segment(segment(8, 0, {8, 1, 0, 0}, 2, false), w);
    taken.push_back(b.dut.cycle());
    try {
      b.drv.send(w, 5000);
    } catch (const std::runtime_error&) {
      // Segments 0..n-2 were queued; n-1 was held; its successor n never went in.
      return {n - 1, double(taken[n - 1] - taken[0]) / double(n - 1)};
    }
  }
}

void back_to_back() {
  fmt::print("### Back-to-back segments\n\n");
  fmt::print("Segments of U moves (v = U, 1, 0, 0: x steps at every move, the y pattern is U long), "
             "every chunk with interval 1 (as fast as the pulses allow) or 2 (the pulse limit, no "
             "stretch). *Gap* = cycles from the last move of a segment to the first of the next "
             "(leading STEP edges of x); inside a segment the spacing is at most the *inner* column. "
             "*Preloaded*: every segment queued and built before START (the card's own seam); "
             "*streamed*: as many as fit queued before START, the rest sent while running, one word per cycle "
             "as fast as the command port takes them.\n\n");
  const Capacity cap = queue_capacity();
  const unsigned preload = cap.segments;
  fmt::print("Before START the card queues {} segments (one more is taken but held in the "
             "command parser, which then blocks the port, START included, until motion frees "
             "room). While it has room, the command port takes a one-chunk segment (8 words, "
             "count 8) every {:.2f} cycles.\n\n", preload, cap.cycles_per_segment);
  fmt::print("| U | interval | mode | segments | moves | cycles first..last move | cycles per move | "
             "gap min | gap max | inner max | stretch count | fault |\n"
             "|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  const auto row = [](uint32_t u, uint32_t interval, const char* mode, unsigned count, unsigned pre) {
    const StreamResult r = stream(u, count, pre, interval);
    const auto gap = [&](uint64_t g) { return g == UINT64_MAX ? std::string("–") : std::to_string(g); };
    fmt::print("| {} | {} | {} | {} | {} | {} | {:.3f} | {} | {} | {} | {} | {} |\n", u, interval, mode,
               r.segments_done, r.moves, r.span, r.moves > 1 ? double(r.span) / double(r.moves - 1) : 0.0,
               gap(r.gap_min), gap(r.gap_max), u > 1 ? std::to_string(r.inner_max) : std::string("–"),
               r.stretches, r.error == 0 ? std::string("none") : fmt::format("code {}", r.error));
  };
  for (uint32_t u : {1u, 2u, 8u, 64u, 1024u}) {
    for (uint32_t interval : {1u, 2u}) row(u, interval, "preloaded", preload, preload);
    const unsigned count = std::max(8u, 8192u / u);
    row(u, 1, "streamed", std::min(count, 256u), preload);
  }
  fmt::print("\nA fault in the *streamed* rows is code 9, UNDERRUN: the segment ran out before the "
             "next one was complete on the command port (a segment with one chunk is 8 words).\n\n");

  fmt::print("Smallest interval at which a stream of 64 short segments (7 queued before START, "
             "the rest sent while running) runs without underrun:\n\n");
  fmt::print("| U | smallest interval | cycles per segment |\n|---:|---:|---:|\n");
  for (uint32_t u : {1u, 2u, 4u}) {
    for (uint32_t interval = 2; interval <= 64; ++interval) {
      const StreamResult r = stream(u, 64, preload, interval);
      if (r.error != 0) continue;
      fmt::print("| {} | {} | {} |\n", u, interval, u * interval);
      break;
    }
  }
  fmt::print("\n");
}

// ---------------------------------------------------------------- build latency
void build_latency() {
  fmt::print("### Build latency per segment\n\n");
  fmt::print("The card is started with an empty queue; then one segment (x: v = U; y: the given v; "
             "one chunk, interval 1, count U) is sent. Latency = cycles from the cycle the segment's "
             "last command word is taken to the cycle of its first leading STEP edge. After that word "
             "the card checks the chunk's last delay, one cycle per bit of count − 1 (*check bits*); "
             "the builder then takes the four axes in turn (docs/CORE.md \"Builder\"): a constant "
             "pattern (v = 0 or v = U) costs 1 cycle, any other 2·U/gcd + 1 (the engine's build, "
             "then its first period copied into the bank), so *build* = 3 + that of y; the rest is "
             "the core's fixed path (commit, segment queue, builder start, load, replay, pulse).\n\n");
  fmt::print("| U | v (y) | U/gcd | check bits | build (cycles) | latency (cycles) | "
             "latency − build − check bits |\n"
             "|---:|---:|---:|---:|---:|---:|---:|\n");
  const auto row = [](uint32_t u, uint32_t vy) {
    Bench b;
    b.start();
    b.drv.idle(4);
    b.send(segment(u, 0, {u, vy, 0, 0}, 1, true));
    const uint64_t last_word = b.dut.cycle() - 1;
    b.finish(100'000);
    const int64_t latency = int64_t(b.pins.rises[0].front() - last_word);
    const uint32_t n = u / std::gcd(u, vy);
    const int bits = std::bit_width(u - 1);
    const int64_t build = 3 + (vy == u || vy == 0 ? 1 : 2 * int64_t(n) + 1);
    fmt::print("| {} | {} | {} | {} | {} | {} | {} |\n", u, vy, n, bits, build, latency,
               latency - build - bits);
  };
  for (uint32_t u : {1u, 2u, 8u, 64u, 1024u}) row(u, 1);
  for (uint32_t u : {64u, 1024u}) row(u, u);  // a constant pattern
  row(51, 11);                                // the paper's line
  row(1024, 512);                             // u/gcd = 2
  fmt::print("\n");
}

// ---------------------------------------------------------------- simulation speed
void sim_speed() {
  fmt::print("### Simulation speed (Verilated cp_core, one core, wall clock)\n\n");
  Bench b;
  // 262144 moves, every axis stepping with its own pattern, a move every 4 cycles.
  b.send(segment(1024, 8, {1024, 633, 311, 1}, 4, true));
  b.drv.idle(2000);
  b.start();
  const uint64_t c0 = b.dut.cycle();
  const auto t0 = std::chrono::steady_clock::now();
  b.finish(10'000'000);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const uint64_t cycles = b.dut.cycle() - c0;
  uint64_t steps = 0;
  for (const auto& r : b.pins.rises) steps += r.size();
  fmt::print("| run | cycles | seconds | cycles per second | steps per second |\n|---|---:|---:|---:|---:|\n");
  fmt::print("| one segment U = 1024, k = 8 (262144 moves), v = 1024, 633, 311, 1, interval 4 | {} | "
             "{:.2f} | {:.3g} | {:.3g} |\n\n",
             cycles, s, cycles / s, steps / s);
}

}  // namespace

int main() {
  step_rate();
  back_to_back();
  build_latency();
  sim_speed();
  return 0;
}

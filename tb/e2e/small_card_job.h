// SPDX-License-Identifier: MIT
// The small card (2 axes, a 32-word buffer, a chunk queue of 8) behind its pins,
// the Verilated RTL and the fast engine in lockstep every cycle
// (sim::TwinCardDut), driven by the host's client, for the machine-control benches
// (test_out_of_band.cpp, test_watchdog.cpp): a job of simple segments whose end is
// summed from its own segments, and the pins watched (steps signed by DIR, the
// shortest STEP pulse, the ENABLE pin's fall, CS rises).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "Vcp_card_small.h"
#include "card/card_client.h"
#include "card/frame.h"
#include "card/protocol.h"
#include "cpstep/builds.h"
#include "sim/card_configs.h"
#include "sim/sim_link.h"
#include "sim/spi_master.h"
#include "sim/twin_card.h"

namespace cpstep::tb::small_card {

using CardSmall = sim::CardOf<builds::small, Vcp_card_small>;
using Twin = sim::TwinCardDut<CardSmall>;

constexpr uint32_t kStepHigh = 3, kStepLow = 3;

// Segments of 8 moves, `delay` cycles a move; no START in the words; x up (or down).
struct Job {
  std::vector<uint32_t> setup, segments;
  int32_t x = 0, y = 0;
  uint32_t moves = 0;
};
inline Job make_job(unsigned n, uint32_t delay, bool x_up = true) {
  Job j;
  card::encode_drivers(true, j.setup);
  for (unsigned a = 0; a < 2; ++a) {
    card::encode_config(a, card::ConfigField::step_high, kStepHigh, j.setup);
    card::encode_config(a, card::ConfigField::step_low, kStepLow, j.setup);
  }
  // x always 8 steps on (up or down); y 2..6 steps, its direction turning every third segment.
  for (unsigned s = 0; s < n; ++s) {
    const uint32_t vy = 2 + s % 5;
    const bool y_up = (s / 3) % 2 == 0;
    card::WireSegment w;
    w.u = 8;
    w.v = {8, vy};
    w.dir_positive = {x_up, y_up};
    w.chunks = {{delay, 4, 0, 0}, {delay, 4, 0, 0}};
    w.end = s + 1 == n;
    card::encode_segment(w, j.segments);
    j.x += x_up ? 8 : -8;
    j.y += y_up ? int32_t(vy) : -int32_t(vy);
    j.moves += 8;
  }
  return j;
}

// The card, its pins watched: leading STEP edges per axis (signed by DIR) and the
// shortest STEP active time.
struct Card {
  Twin twin;
  sim::SpiMaster<Twin> spi{twin};
  sim::SimLink<Twin> link{spi, 48e6};
  std::array<int64_t, 2> pins{};
  uint64_t shortest_high = UINT64_MAX;
  std::array<uint64_t, 2> rose{};
  uint64_t last_step = 0;   // the cycle of the last leading STEP edge, any axis
  std::vector<uint64_t> move_cycles;  // the cycles with a leading STEP edge (a move event each)
  uint64_t enable_fell = 0; // the cycle the ENABLE pin last went low (0: never)
  uint64_t cs_rose = 0;     // the cycle CS last went high (a frame's end)
  uint32_t prev = 0;        // STEP pins active, last seen
  bool enable = false, cs_n = true;
  Card() {
    // The small card's pins after reset: STEP active low, DIR low = positive.
    spi.set_span_observer([this](uint64_t c, uint64_t, const sim::CardIn& in, const sim::CardOut& o) {
      const uint32_t active = ~o.step & 3;
      for (unsigned a = 0; a < 2; ++a) {
        const bool now = active >> a & 1, was = prev >> a & 1;
        if (now && !was) {
          pins[a] += (o.dir >> a & 1) ? -1 : 1;
          rose[a] = c;
          if (move_cycles.empty() || move_cycles.back() != c) move_cycles.push_back(c);
          last_step = c;
        }
        if (!now && was) shortest_high = std::min(shortest_high, c - rose[a]);
      }
      prev = active;
      if (enable && !o.enable) enable_fell = c;
      enable = o.enable;
      if (!cs_n && in.cs_n) cs_rose = c;
      cs_n = in.cs_n;
    });
    spi.reset();
  }
  // The steps the STEP pins made, signed by DIR, as the reply's positions.
  std::vector<int32_t> steps() const { return {int32_t(pins[0]), int32_t(pins[1])}; }
  card::ClientOptions options() const {
    card::ClientOptions o;
    o.axes = 2;
    o.poll_interval_s = 4000 / 48e6;
    return o;
  }
};

// The job ran whole: no fault, its moves, its end on the counters and on the pins.
inline void expect_job_done(card::CardClient& c, const Card& card, const Job& j) {
  const card::Reply r = c.poll();
  EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault";
  EXPECT_EQ(r.moves, j.moves);
  EXPECT_EQ(r.positions, (std::vector<int32_t>{j.x, j.y}));
  EXPECT_EQ(card.pins[0], j.x);
  EXPECT_EQ(card.pins[1], j.y);
}

// The card latched the fault `code` (its name for messages) and its run is off.
inline void expect_stopped_by(const card::Reply& r, uint32_t code, const char* name) {
  const card::Status st = card::decode_status(r.status);
  EXPECT_TRUE(st.fault) << name;
  EXPECT_EQ(st.err_code, code) << name;
  EXPECT_FALSE(st.running) << name;
}

// Sends the job's segments from `w` on while each fits the card's free words (one
// frame a segment, after a POLL); returns the index of the first not sent.
inline size_t send_what_fits(card::CardClient& c, const Job& j, size_t w) {
  while (w < j.segments.size()) {
    const size_t len = card::command_words(j.segments[w], 2);
    c.settle();
    if (c.poll().free_words < len) break;
    if (c.send(std::span(j.segments).subspan(w, len)) != len) break;
    w += len;
  }
  return w;
}

// Feeds the job's segments from `w` on as they fit while the card runs for `cycles`
// clocks (in steps of `chunk`); returns the index of the first not sent.
inline size_t feed_for(card::CardClient& c, Card& card, const Job& j, size_t w, uint64_t cycles,
                       uint64_t chunk = 2000) {
  const uint64_t until = card.twin.cycle() + cycles;
  while (card.twin.cycle() < until) {
    w = send_what_fits(c, j, w);
    card.spi.idle(chunk);
  }
  return w;
}

// Drivers, pulse timing, the input filter (a sample every `filter` clocks) and both
// axes' limits: active high, enabled.
inline std::vector<uint32_t> limits_setup(const Job& j, uint32_t filter) {
  std::vector<uint32_t> w = j.setup;
  card::encode_config(0, card::ConfigField::input_filter, filter, w);
  for (unsigned a = 0; a < 2; ++a)
    card::encode_config(a, card::ConfigField::limits,
                        card::limit_bits::min_active_high | card::limit_bits::max_active_high |
                            card::limit_bits::min_enabled | card::limit_bits::max_enabled,
                        w);
  return w;
}

// A new job `next` (its segments, START out of band) runs from where the card stood
// at `before`: no fault, its moves counted on, its end on the counters and pins.
// (`before` is taken by value: CardClient::poll() returns a reference to its latest
// reply, which the polls here would change.)
inline void expect_next_job_runs_exactly(card::CardClient& c, const Card& card, const Job& next,
                                         const card::Reply before) {
  const std::vector<int32_t> at = before.positions;
  ASSERT_EQ(c.send(next.segments), next.segments.size());
  ASSERT_TRUE(c.urgent(card::urgent::start));
  ASSERT_TRUE(c.wait_until_stopped());
  const card::Reply r = c.poll();
  EXPECT_EQ(r.status & 0xFF02, 0u) << "no fault";
  EXPECT_EQ(r.moves, before.moves + next.moves);
  EXPECT_EQ(r.positions, (std::vector<int32_t>{at[0] + next.x, at[1] + next.y}));
  EXPECT_EQ(card.pins[0], at[0] + next.x);
  EXPECT_EQ(card.pins[1], at[1] + next.y);
}

}  // namespace cpstep::tb::small_card

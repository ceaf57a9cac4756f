// SPDX-License-Identifier: MIT
// The torch output (docs/CORE.md "Torch"), RTL and model in lockstep every cycle:
// each segment carries the torch's level (H0[16]); the pin takes it in the cycle
// the segment before shows its last STEP edge, a pause segment keeps it, the run's
// end, an E-stop and an ABORT drop it. Expected cycles come from the pins (the
// STEP edges) and the chunks sent, not from the core's code.
#include <gtest/gtest.h>

#include <vector>

#include "Vcp_core_hx8k.h"
#include "card/protocol.h"
#include "common/lockstep.h"
#include "cpstep/builds.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"

namespace cpstep::tb {
namespace {

struct CoreHx8k : sim::CorePortBase<Vcp_core_hx8k, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() { return model::core_params(builds::hx8k); }
};

// Leading STEP edges of every axis and the torch's changes, by cycle.
struct Pins {
  uint32_t prev_step = 0;
  bool torch = false;
  std::vector<uint64_t> step_edges;             // cycles with a leading edge on some axis
  std::vector<std::pair<uint64_t, bool>> torch_edges;
  void operator()(uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
    if (o.step & ~prev_step) step_edges.push_back(c);
    prev_step = o.step;
    if (o.torch != torch) torch_edges.push_back({c, o.torch});
    torch = o.torch;
  }
};

card::WireSegment line_x(uint32_t moves, bool torch, std::vector<card::WireChunk> chunks) {
  card::WireSegment s;
  s.u = moves;
  s.torch = torch;
  s.dir_positive = {true, true, true, true};
  s.v = {moves, moves / 3, 0, 0};
  s.chunks = std::move(chunks);
  return s;
}

// The core in lockstep with its model, the pins watched, after reset.
struct Bench {
  Lockstep<CoreHx8k> ls;
  Pins pins;
  sim::CoreDriver<Lockstep<CoreHx8k>> drv{ls, std::ref(pins)};
  Bench() { drv.reset(); }
  // Sends one CONTROL word; the cycle the core took it.
  uint64_t control(bool start, bool abort) {
    std::vector<uint32_t> c;
    card::encode_control(start, abort, false, c);
    drv.send(c);
    return ls.cycle() - 1;
  }
};

std::vector<uint32_t> timing_words() {
  std::vector<uint32_t> w;
  for (unsigned a = 0; a < 4; ++a) {
    card::encode_config(a, card::ConfigField::step_high, 2, w);
    card::encode_config(a, card::ConfigField::step_low, 2, w);
  }
  return w;
}

TEST(CoreTorch, SwitchesAtTheMoveBoundaryAndHoldsThroughAPause) {
  Bench b;
  auto& [ls, pins, drv] = b;
  std::vector<uint32_t> w = timing_words();
  // A rapid (torch off), a pierce as pause moves (torch on, no step), the cut (on,
  // its first move 500 cycles after the pause), more cut, the rapid away (off).
  card::encode_segment(line_x(20, false, {{10, 20, 0}}), w);
  card::WireSegment pause = line_x(4, true, {{100, 4, 0}});
  pause.v = {0, 0, 0, 0};
  card::encode_segment(pause, w);
  card::encode_segment(line_x(10, true, {{500, 1, 0}, {12, 9, 0}}), w);
  card::encode_segment(line_x(9, true, {{15, 9, 0}}), w);
  card::WireSegment away = line_x(6, false, {{30, 6, 0}});
  away.end = true;
  card::encode_segment(away, w);
  card::encode_control(true, false, false, w);
  drv.send(w);
  drv.run_until_stopped(100000);
  ASSERT_FALSE(drv.last().fault) << drv.last().err_code;
  ASSERT_EQ(pins.step_edges.size(), 20u + 10u + 9u + 6u);
  ASSERT_EQ(pins.torch_edges.size(), 2u);
  // On with the rapid's last STEP edge; the cut's first move 4 x 100 + 500 cycles on.
  EXPECT_TRUE(pins.torch_edges[0].second);
  EXPECT_EQ(pins.torch_edges[0].first, pins.step_edges[19]);
  EXPECT_EQ(pins.step_edges[20] - pins.torch_edges[0].first, 4u * 100u + 500u);
  // Off with the cut's last STEP edge (move 39), before the first move away.
  EXPECT_FALSE(pins.torch_edges[1].second);
  EXPECT_EQ(pins.torch_edges[1].first, pins.step_edges[38]);
  EXPECT_EQ(drv.last().status >> 5 & 1, 0u);
}

TEST(CoreTorch, OnFromStartAndOffAtTheRunsEnd) {
  Bench b;
  auto& [ls, pins, drv] = b;
  std::vector<uint32_t> w = timing_words();
  card::WireSegment s = line_x(12, true, {{40, 12, 0}});
  s.end = true;
  card::encode_segment(s, w);
  drv.send(w);
  drv.idle(200);
  EXPECT_TRUE(pins.torch_edges.empty()) << "a loaded segment must not switch the torch before START";
  const uint64_t start_cycle = b.control(true, false);
  drv.run_until_stopped(100000);
  ASSERT_EQ(pins.torch_edges.size(), 2u);
  EXPECT_EQ(pins.torch_edges[0].first, start_cycle + 1) << "on in the cycle after START is taken";
  EXPECT_EQ(pins.step_edges.front() - pins.torch_edges[0].first, 40u);
  EXPECT_EQ(pins.torch_edges[1].first, pins.step_edges.back()) << "off with the run's last STEP edge";
}

// E-stop and ABORT: the torch is off in the cycle after the core sees them.
TEST(CoreTorch, EstopAndAbortDropItAtOnce) {
  for (bool estop : {true, false}) {
    SCOPED_TRACE(estop ? "E-stop" : "ABORT");
    Bench b;
    auto& [ls, pins, drv] = b;
    std::vector<uint32_t> w = timing_words();
    card::WireSegment s = line_x(2000, true, {{20, 2000, 0}});
    s.end = true;
    card::encode_segment(s, w);
    card::encode_control(true, false, false, w);
    drv.send(w);
    drv.idle(5000);  // the pattern's build (2 x 1000 + 1 cycles), then moves
    ASSERT_TRUE(drv.last().torch) << drv.last().err_code;
    EXPECT_EQ(drv.last().status >> 5 & 1, 1u) << "status bit 5 reads the torch";
    uint64_t when = 0;
    if (estop) {
      drv.set_estop(true);
      when = ls.cycle();
      drv.idle(1);
    } else {
      when = b.control(false, true);
    }
    drv.idle(3);
    ASSERT_EQ(pins.torch_edges.size(), 2u);
    EXPECT_FALSE(pins.torch_edges[1].second);
    EXPECT_EQ(pins.torch_edges[1].first, when + 1);
    EXPECT_EQ(drv.last().err_code, estop ? 10u : 11u);
  }
}

}  // namespace
}  // namespace cpstep::tb

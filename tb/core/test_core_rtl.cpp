// SPDX-License-Identifier: MIT
// cp_core on its own (RTL): the paper's line as a 4-axis segment, from the pins.
#include <gtest/gtest.h>

#include "Vcp_core_hx8k.h"
#include "model/oracle.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"

namespace cpstep::tb {
namespace {

struct CoreRtl : sim::CorePortBase<Vcp_core_hx8k, 4> {};

// Watches the pins: leading STEP edges per axis, and which axes stepped together.
struct PinLog {
  uint32_t prev_step = 0;
  std::array<int64_t, 4> pulses{};
  std::string minor_moves;  // per x leading edge: '1' if y stepped in the same cycle
  void operator()(uint64_t, const model::CpCoreIn&, const model::CpCoreOut& o) {
    const uint32_t rise = o.step & ~prev_step;
    for (int a = 0; a < 4; ++a)
      if (rise >> a & 1) pulses[a] += (o.dir >> a & 1) ? 1 : -1;
    if (rise & 1) minor_moves.push_back((rise >> 1 & 1) ? '1' : '0');
    prev_step = o.step;
  }
};

TEST(CoreRtl, PaperLineAsA4AxisSegment) {
  sim::RtlDut<CoreRtl> dut;
  PinLog pins;
  sim::CoreDriver<sim::RtlDut<CoreRtl>> drv(dut, std::ref(pins));
  drv.reset();
  std::vector<uint32_t> w;
  for (unsigned a = 0; a < 4; ++a) {
    card::encode_config(a, card::ConfigField::step_high, 2, w);
    card::encode_config(a, card::ConfigField::step_low, 2, w);
    card::encode_config(a, card::ConfigField::dir_setup, 3, w);
    card::encode_config(a, card::ConfigField::dir_hold, 3, w);
  }
  card::WireSegment s;
  s.u = 51;
  s.end = true;
  s.dir_positive = {true, false, true, true};
  s.v = {51, 11, 0, 0};
  s.chunks = {{10, 20, 1}, {40, 31, -1}};  // delays 10..29, then 40 down to 10
  card::encode_segment(s, w);
  card::encode_control(true, false, false, w);
  drv.send(w);
  drv.run_until_stopped(100000);
  EXPECT_FALSE(drv.last().fault) << drv.last().err_code;
  EXPECT_EQ(drv.last().position[0], 51);
  EXPECT_EQ(drv.last().position[1], -11);
  EXPECT_EQ(drv.last().position[2], 0);
  EXPECT_EQ(pins.pulses[0], 51);
  EXPECT_EQ(pins.pulses[1], -11);
  EXPECT_EQ(pins.minor_moves, oracle::closed_form(51, 11));
  EXPECT_EQ(drv.read(card::Register::moves_done), 51u);
  EXPECT_EQ(drv.read(card::Register::id), card::kCardId);
  EXPECT_EQ(int32_t(drv.read(card::Register::position0, 1)), -11);
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// cp_core CONFIG around STEP pulses (docs/CORE.md "Cycle behaviour", CONFIG): refused
// with CONFIG_BUSY (13) while running or while any axis's STEP pin is active — after
// ABORT, E-stop or the end of a run a pulse already high completes its high time, and
// a polarity (or timing) write then must not cut it into a runt; and a polarity written
// right after a pulse moves the raw pins only under the pulse timing rules
// (docs/PULSE.md). RTL vs model in lockstep, the pin checker (raw pins) on.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/core_bench.h"
#include "core/core_small.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

constexpr uint32_t kConfigBusy = 13;

template <class C>
card::WireSegment one_axis_segment(int64_t steps, uint32_t delay) {
  const model::CpCoreParams p = C::model_params();
  std::vector<int64_t> d(p.n, 0);
  d[0] = steps;
  card::WireSegment s;
  JobGen g(p, 0);
  if (!g.from_deltas(d, s)) throw std::runtime_error("bench error: segment does not fit");
  s.chunks = {{delay, uint16_t(steps < 0 ? -steps : steps), 0}};
  s.end = true;
  return s;
}

// The raw STEP and DIR pin edges of one axis, cycle by cycle.
struct PinEdges {
  std::vector<uint64_t> step, dir;
  bool have = false;
  uint32_t prev_step = 0, prev_dir = 0;
  void see(uint64_t c, const model::CpCoreOut& o, unsigned axis) {
    const uint32_t s = o.step >> axis & 1, d = o.dir >> axis & 1;
    if (have && s != prev_step) step.push_back(c);
    if (have && d != prev_dir) dir.push_back(c);
    prev_step = s;
    prev_dir = d;
    have = true;
  }
};

enum class Stop { abort, estop, end_of_run };

const char* name_of(Stop s) {
  return s == Stop::abort ? "ABORT" : s == Stop::estop ? "E-stop" : "the end of the run";
}

// A long pulse on axis 0; it is stopped (ABORT, E-stop: then CLEAR, so a new fault can
// latch) or the run ends with it, and while STEP is still high CONFIG words arrive: a
// polarity write to `axis`, then a step_high write to axis 0. Both are refused with
// CONFIG_BUSY, the pulse completes its full high time (no runt), and nothing was
// written; once STEP is inactive the same polarity write is taken.
template <class C>
void config_while_pulse_high(Stop how, unsigned axis) {
  const std::string where = std::string(name_of(how)) + ", CONFIG to axis " + std::to_string(axis);
  SCOPED_TRACE(where);
  CoreHarness<C> h("config_busy", 1);
  h.word_gap = 0;
  h.rsp_stall = 0;
  AxisTiming t;
  t.high = 200;  // < 2^TW of every build
  t.low = 3;
  t.setup = 2;
  t.hold = 4;
  t.step_pol = C::model_params().step_pol_reset;
  t.dir_pol = C::model_params().dir_pol_reset;
  h.configure_all(t);
  const uint32_t active = t.step_pol ? 1 : 0;  // axis 0's STEP pin level while a pulse is high
  h.segment(one_axis_segment<C>(how == Stop::end_of_run ? 1 : 5, 20));
  PinEdges e0, ea;
  h.hook = [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) {
    e0.see(c, o, 0);
    ea.see(c, o, axis);
  };
  h.control(true, false, false);
  ASSERT_TRUE(h.wait_for([&](const model::CpCoreOut& o) { return (o.step & 1) == active; }, 1000));
  h.idle(5);
  switch (how) {
    case Stop::abort:
      h.control(false, true, false);
      h.chk.abandon();
      h.expecting = false;
      h.control(false, false, true);  // CLEAR: code 11 dropped, the next fault latches
      h.idle(1);
      break;
    case Stop::estop:
      h.drv.set_estop(true);
      h.idle(2);
      h.chk.abandon();
      h.expecting = false;
      h.drv.set_estop(false);
      h.idle(1);
      h.ack();  // E-stop released and acknowledged out of band: code 10 dropped
      h.idle(1);
      break;
    case Stop::end_of_run: break;  // the segment's only move fired: not running any more
  }
  ASSERT_FALSE(h.drv.last().running);
  ASSERT_FALSE(h.drv.last().fault) << "code " << h.drv.last().err_code;
  ASSERT_EQ(h.drv.last().step & 1, active) << "the pulse is still high";
  const size_t e0_dir = e0.dir.size(), ea_step = ea.step.size(), ea_dir = ea.dir.size();
  std::vector<uint32_t> w;
  card::encode_config(axis, card::ConfigField::polarity,
                      uint32_t(!t.step_pol) | uint32_t(!t.dir_pol) << 1, w);  // both flipped
  card::encode_config(0, card::ConfigField::step_high, 1, w);
  h.send(w);
  EXPECT_EQ(h.drv.last().step & 1, active) << "the CONFIG words were taken while STEP was high";
  h.idle(t.high + 20);
  EXPECT_TRUE(h.chk.errors().empty()) << h.chk.report();
  EXPECT_EQ(e0.step.size(), 2u) << "one pulse on axis 0's raw STEP pin, and nothing else";
  if (e0.step.size() >= 2) {
    EXPECT_EQ(e0.step[1] - e0.step[0], t.high) << "the pulse completes its high time: no runt";
  }
  EXPECT_EQ(e0.dir.size(), e0_dir);
  EXPECT_EQ(ea.step.size(), ea_step + (axis == 0 ? 1 : 0)) << "a refused polarity write moves no pin";
  EXPECT_EQ(ea.dir.size(), ea_dir) << "a refused polarity write moves no pin";
  card::Status st = h.status();
  EXPECT_TRUE(st.fault);
  EXPECT_EQ(st.err_code, kConfigBusy) << "CONFIG while a STEP pulse is high";
  // STEP inactive: the same write is taken, and moves the pins under the timing rules.
  h.control(false, false, true);
  const size_t step_before = ea.step.size(), dir_before = ea.dir.size();
  h.send(w);
  h.idle(50);
  st = h.status();
  EXPECT_FALSE(st.fault) << "CONFIG with every STEP pin inactive: code " << st.err_code;
  EXPECT_EQ(ea.step.size(), step_before + 1) << "the new STEP polarity's idle level";
  EXPECT_EQ(ea.dir.size(), dir_before + 1) << "the same direction in the new DIR polarity";
  EXPECT_TRUE(h.chk.errors().empty()) << h.chk.report();
  h.hook = nullptr;
}

TEST(CoreConfig, AbortMidPulseThenConfigIsRefusedAndThePulseCompletes) {
  config_while_pulse_high<sim::CoreDefault>(Stop::abort, 0);
  config_while_pulse_high<sim::CoreSmall>(Stop::abort, 0);
}

TEST(CoreConfig, EstopMidPulseThenConfigIsRefusedAndThePulseCompletes) {
  config_while_pulse_high<sim::CoreDefault>(Stop::estop, 0);
  config_while_pulse_high<sim::CoreSmall>(Stop::estop, 0);
}

TEST(CoreConfig, ConfigAfterTheLastMoveIsRefusedWhileItsPulseIsHigh) {
  config_while_pulse_high<sim::CoreDefault>(Stop::end_of_run, 0);
  // Any axis's pulse blocks CONFIG, to any axis.
  config_while_pulse_high<sim::CoreDefault>(Stop::end_of_run, 3);
  config_while_pulse_high<sim::CoreSmall>(Stop::end_of_run, 1);
}

// Both polarities flipped by a CONFIG taken in the first cycle after a run's last
// trailing edge: the raw DIR pin moves no earlier than dir_hold after that trailing
// edge, the STEP pin's new idle level no earlier than step_low after it, and the next
// run's first leading edge waits dir_setup after the DIR edge and step_low after the
// STEP polarity edge (the pin checker; the figures asserted here too).
template <class C>
void polarity_right_after_a_run(AxisTiming t) {
  SCOPED_TRACE("H=" + std::to_string(t.high) + " L=" + std::to_string(t.low) + " S=" + std::to_string(t.setup) +
               " D=" + std::to_string(t.hold));
  CoreHarness<C> h("config_polarity", 1);
  h.word_gap = 0;
  h.rsp_stall = 0;
  t.step_pol = C::model_params().step_pol_reset;
  t.dir_pol = C::model_params().dir_pol_reset;
  h.configure_all(t);
  PinEdges e;
  h.hook = [&](uint64_t c, const model::CpCoreIn&, const model::CpCoreOut& o) { e.see(c, o, 0); };
  bool step_pol = t.step_pol, dir_pol = t.dir_pol;
  h.segment(one_axis_segment<C>(3, 1));
  h.control(true, false, false);
  h.finish();
  for (int flip = 0; flip < 4; ++flip) {
    // The run's last pulse is high; wait for its trailing edge.
    const uint32_t idle = step_pol ? 0 : 1;
    ASSERT_TRUE(h.wait_for([&](const model::CpCoreOut& o) { return (o.step & 1) == idle; }, 1000));
    const uint64_t trailing = h.ls.cycle() - 1;  // the first cycle at the inactive level
    const size_t s0 = e.step.size(), d0 = e.dir.size();
    step_pol = !step_pol;
    dir_pol = !dir_pol;
    std::vector<uint32_t> w;
    card::encode_config(0, card::ConfigField::polarity, uint32_t(step_pol) | uint32_t(dir_pol) << 1, w);
    h.send(w);
    ASSERT_EQ(h.ls.cycle() - 1, trailing + 1) << "bench timing: CONFIG taken right after the trailing edge";
    h.segment(one_axis_segment<C>(2, 1));  // the same (positive) direction
    h.control(true, false, false);
    h.finish();
    h.idle(t.high + 1);
    ASSERT_EQ(e.dir.size(), d0 + 1) << "the DIR pin moves once: a polarity flip is no reversal";
    ASSERT_EQ(e.step.size(), s0 + 5) << "a STEP polarity edge, then 2 pulses";
    const uint64_t dir_edge = e.dir[d0], pol_edge = e.step[s0], lead = e.step[s0 + 1];
    EXPECT_GE(dir_edge - trailing, std::max(t.hold, 1u)) << "trailing edge to DIR edge";
    EXPECT_GE(pol_edge - trailing, t.low) << "trailing edge to STEP polarity edge";
    EXPECT_GE(lead - dir_edge, std::max(t.setup, 1u)) << "DIR edge to the next leading edge";
    EXPECT_GE(lead - pol_edge, t.low) << "STEP polarity edge to the next leading edge";
    EXPECT_TRUE(h.chk.errors().empty()) << h.chk.report();
    if (::testing::Test::HasFailure()) return;
    h.segment(one_axis_segment<C>(1, 1));  // a pulse to end the next trailing edge on
    h.control(true, false, false);
    h.finish();
  }
  h.idle(t.high + 1);
  EXPECT_EQ(h.chk.position(0), 3 + 4 * 3);
  h.expect_consistent("polarity right after a run");
}

TEST(CoreConfig, PolarityRightAfterARunKeepsThePulseTimingOnTheRawPins) {
  for (AxisTiming t : {AxisTiming{2, 4, 3, 6}, AxisTiming{1, 1, 1, 1}, AxisTiming{5, 2, 7, 2}})
    polarity_right_after_a_run<sim::CoreDefault>(t);
  polarity_right_after_a_run<sim::CoreSmall>({3, 5, 4, 4});
}

}  // namespace
}  // namespace cpstep::tb

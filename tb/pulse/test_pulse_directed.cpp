// Directed cp_pulse tests: the figures docs/PULSE.md derives from the contract
// (maximum step rate, DIR reversal latency), saturation and wrap at TW = 4, PW = 8,
// reset, ignored requests, busy_o; and the pin checker's own self-test. All run in
// lockstep with the pin checker on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

#include "pulse_bench.h"

namespace cpstep::tb {
namespace {

struct Timing {
  uint32_t high, low, setup, hold;
};

template <class P>
void configure(PulseBench<P>& b, Timing t, bool step_pol = true, bool dir_pol = true) {
  b.in.cfg_step_high = t.high;
  b.in.cfg_step_low = t.low;
  b.in.cfg_dir_setup = t.setup;
  b.in.cfg_dir_hold = t.hold;
  b.in.cfg_step_pol = step_pol;
  b.in.cfg_dir_pol = dir_pol;
}

// A core that fires whenever ready: `pulses` leading edges, at the maximum rate.
template <class P>
void fire_at_max_rate(PulseBench<P>& b, size_t pulses) {
  const size_t want = b.leading.size() + pulses;
  while (b.leading.size() < want) {
    b.in.step = b.peek_outputs().ready;
    b.cycle();
  }
}

// --- the maximum step rate: period H + L ---------------------------------------

template <class P>
void max_rate(Timing t) {
  SCOPED_TRACE("H=" + std::to_string(t.high) + " L=" + std::to_string(t.low));
  PulseBench<P> b;
  configure(b, t);
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 20);
  b.run(t.high + 1);
  for (size_t i = 1; i < b.leading.size(); ++i)
    EXPECT_EQ(b.leading[i] - b.leading[i - 1], t.high + t.low) << "pulse " << i;
  for (size_t i = 0; i < b.trailing.size(); ++i) EXPECT_EQ(b.trailing[i] - b.leading[i], t.high);
  EXPECT_EQ(b.last.position, 20u);
  b.expect_pins_clean();
}

TEST(PulseDirected, MaxStepRateIsOneStepPerHighPlusLowCycles) {
  for (Timing t : {Timing{1, 1, 0, 0}, Timing{1, 2, 1, 1}, Timing{2, 1, 0, 0}, Timing{3, 5, 9, 9},
                   Timing{7, 1, 1, 1}, Timing{100, 37, 3, 3}})
    max_rate<sim::PulseDefault>(t);
  // The extremes of a 4-bit field: saturated counters still reach 15.
  max_rate<sim::PulseSmall>({15, 15, 15, 15});
  max_rate<sim::PulseSmall>({1, 15, 0, 0});
  max_rate<sim::PulseSmall>({15, 1, 0, 0});
}

TEST(PulseDirected, MaxStepRateAtTheSmallestConfigurationIsHalfAStepPerClock) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {1, 1, 0, 0});
  b.in.dir = true;
  b.reset();
  const uint64_t fired = b.until_ready(true);
  for (int i = 0; i < 999; ++i) {
    b.in.step = b.peek_outputs().ready;
    b.cycle();
  }
  // The 1000 cycles from the first leading edge hold 500 pulses: STEP toggles every cycle.
  ASSERT_EQ(b.leading.size(), 500u);
  EXPECT_EQ(b.leading.front(), fired + 1);
  for (size_t i = 1; i < b.leading.size(); ++i) EXPECT_EQ(b.leading[i] - b.leading[i - 1], 2u);
  b.expect_pins_clean();
}

TEST(PulseDirected, LargestTimingValuesAtTW16) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {65535, 65535, 65535, 65535});
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 2);
  b.run(65536);
  ASSERT_EQ(b.leading.size(), 2u);
  EXPECT_EQ(b.leading[1] - b.leading[0], 131070u);
  EXPECT_EQ(b.trailing[1] - b.leading[1], 65535u);
  b.expect_pins_clean();
}

// --- DIR reversal: max(D,1) to the DIR edge, then max(S,1), at least L -----------

template <class P>
void reversal(Timing t) {
  SCOPED_TRACE("H=" + std::to_string(t.high) + " L=" + std::to_string(t.low) +
               " S=" + std::to_string(t.setup) + " D=" + std::to_string(t.hold));
  PulseBench<P> b;
  configure(b, t);
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 3);
  const uint64_t d = std::max(t.hold, 1u), s = std::max(t.setup, 1u);
  for (int rev = 0; rev < 4; ++rev) {
    // The last move of a segment just fired; the next segment goes the other way.
    b.in.dir = !b.in.dir;
    const size_t n = b.leading.size(), e = b.dir_edges.size();
    fire_at_max_rate(b, 3);
    ASSERT_EQ(b.dir_edges.size(), e + 1);
    const uint64_t c = b.trailing[n - 1];  // trailing edge of the last pulse before reversing
    const uint64_t a = b.dir_edges[e], lead = b.leading[n];
    EXPECT_EQ(a - c, d) << "trailing edge to DIR edge";
    EXPECT_EQ(lead - c, std::max<uint64_t>(d + s, t.low)) << "trailing edge to leading edge";
    if (t.hold >= 1 && t.setup >= 1 && t.hold + t.setup >= t.low) {
      EXPECT_EQ(lead - c, uint64_t(t.hold) + t.setup) << "the reversal latency D + S";
    }
    EXPECT_EQ(b.leading[n + 1] - lead, t.high + t.low) << "back to the maximum rate";
  }
  b.run(t.high + 1);
  EXPECT_EQ(b.last.position, 3u);  // +3 -3 +3 -3 +3
  b.expect_pins_clean();
}

TEST(PulseDirected, ReversalLatencyIsHoldPlusSetup) {
  for (Timing t : {Timing{1, 1, 1, 1}, Timing{2, 2, 2, 3}, Timing{4, 1, 5, 7}, Timing{1, 3, 1, 2},
                   Timing{3, 2, 40, 25}})
    reversal<sim::PulseDefault>(t);
  reversal<sim::PulseSmall>({15, 15, 15, 15});
  reversal<sim::PulseSmall>({2, 1, 15, 15});
}

TEST(PulseDirected, ReversalWithZeroSetupOrHoldStillTakesACycleEach) {
  for (Timing t : {Timing{1, 1, 0, 0}, Timing{2, 1, 0, 3}, Timing{2, 1, 3, 0}}) reversal<sim::PulseDefault>(t);
}

TEST(PulseDirected, ReversalWaitsForStepLowWhenItIsLonger) {
  for (Timing t : {Timing{1, 10, 2, 3}, Timing{2, 9, 0, 0}, Timing{1, 5, 2, 3}})
    reversal<sim::PulseDefault>(t);
}

// --- wrap and saturation at TW = 4, PW = 8 -----------------------------------------

TEST(PulseDirected, PositionWrapsAtPW8) {
  PulseBench<sim::PulseSmall> b;
  configure(b, {1, 1, 0, 0});
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 127);
  b.run(2);
  EXPECT_EQ(b.last.position, 127u);
  fire_at_max_rate(b, 1);
  b.run(2);
  EXPECT_EQ(b.last.position, 128u);  // -128 as int8: the signed count wrapped
  fire_at_max_rate(b, 300 - 128);
  b.run(2);
  EXPECT_EQ(b.last.position, 300u % 256);
  b.in.dir = false;
  fire_at_max_rate(b, 350);
  b.run(2);
  EXPECT_EQ(b.last.position, 256u - 50);  // -50 mod 2^8
  EXPECT_EQ(int8_t(b.last.position), -50);
  b.expect_pins_clean();  // the checker compared position_o mod 2^8 on every cycle
}

TEST(PulseDirected, CountersSaturateAtTW4AndStayReady) {
  PulseBench<sim::PulseSmall> b;
  configure(b, {3, 15, 15, 15});
  b.in.dir = true;
  b.reset();
  const uint64_t first = b.until_ready(false);  // DIR 0 -> 1 at once, then setup 15
  EXPECT_EQ(b.dir_edges.size(), 1u);
  EXPECT_EQ(first - b.dir_edges[0], 14u) << "setup_cnt = 15 in the ready cycle";
  b.run(200);  // far past 15: the counters sit at 15 and the axis stays ready
  EXPECT_TRUE(b.peek_outputs().ready);
  b.in.step = true;
  b.run(2);
  EXPECT_EQ(b.leading.size(), 1u);
  b.expect_pins_clean();
}

// --- reset -----------------------------------------------------------------------

template <class P>
void reset_mid_motion() {
  const bool sp = P::model_params().step_pol_reset, dp = P::model_params().dir_pol_reset;
  for (bool step_pol : {false, true})
    for (bool dir_pol : {false, true}) {
      PulseBench<P> b;
      configure(b, {5, 2, 1, 1}, step_pol, dir_pol);
      b.in.dir = true;
      b.reset();
      fire_at_max_rate(b, 3);
      b.run(2);  // in the middle of the third pulse
      ASSERT_EQ(b.last.step, step_pol) << "STEP is active";
      b.in.rst = true;
      const auto o = b.cycle();
      EXPECT_EQ(o.step, !sp) << "STEP at its idle level for the reset polarity";
      EXPECT_EQ(o.dir, !dp) << "DIR at logical 0 for the reset polarity";
      EXPECT_FALSE(o.ready);
      b.in.step = true;  // ignored in reset
      b.cycle();
      b.in.rst = false;
      const auto after = b.cycle();
      EXPECT_EQ(after.position, 0u);
      EXPECT_EQ(after.step, !step_pol) << "no pulse comes out of a reset";
      EXPECT_EQ(after.dir, !dir_pol);
      EXPECT_TRUE(after.busy) << "dir_i = 1, DIR pin shows 0: a DIR change is pending";
      b.run(3);
      EXPECT_EQ(b.leading.size(), 3u);
      b.expect_pins_clean();
    }
}

TEST(PulseDirected, ResetMidPulsePutsPinsIdleAndCountersToZero) {
  reset_mid_motion<sim::PulseDefault>();  // reset polarities 1
  reset_mid_motion<sim::PulseSmall>();    // reset polarities 0
}

TEST(PulseDirected, ReadyAtOnceAfterResetWhenDirectionIsZero) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {2, 4000, 4000, 4000});
  b.in.dir = false;
  b.reset();
  EXPECT_TRUE(b.peek_outputs().ready) << "saturated counters: the history is long ago";
  b.in.step = true;
  b.cycle();
  b.run(3);
  EXPECT_EQ(b.last.position, uint64_t(0xffffffff));  // -1
  b.expect_pins_clean();
}

// --- requests that break the contract, and busy_o ---------------------------------

TEST(PulseDirected, StepWhileNotReadyIsIgnored) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {4, 6, 3, 5});
  b.in.dir = true;
  b.reset();
  b.until_ready(true);
  // Hammer step_i through the pulse, its low time, a pending DIR change and the setup.
  b.in.dir = false;
  for (int i = 0; i < 40; ++i) {
    const bool ready = b.peek_outputs().ready;
    b.in.step = !ready;
    b.cycle();
  }
  EXPECT_EQ(b.leading.size(), 1u);
  EXPECT_EQ(b.last.position, 1u);
  b.expect_pins_clean();
}

TEST(PulseDirected, BusyWhileStepActiveOrDirPending) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {3, 2, 2, 4});
  b.in.dir = false;
  b.reset();
  EXPECT_FALSE(b.peek_outputs().busy);
  b.in.step = true;
  EXPECT_FALSE(b.cycle().busy);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(b.cycle().busy) << "STEP active";
  EXPECT_FALSE(b.cycle().busy) << "trailing edge, nothing pending";
  b.in.dir = true;
  // Hold 4 from the trailing edge: low_cnt is 2, 3, 4 in the next three cycles and
  // DIR changes at the edge after low_cnt = 4.
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(b.cycle().busy) << "DIR change pending";
  const auto o = b.cycle();
  EXPECT_FALSE(o.busy) << "DIR shows dir_i";
  EXPECT_FALSE(o.ready) << "but setup time is still running";
  EXPECT_TRUE(b.cycle().ready);
  b.expect_pins_clean();
}

// --- the checker catches what it claims to -----------------------------------------

struct Trace {
  model::CpPulseIn cfg;
  std::vector<std::pair<bool, bool>> pins;  // (STEP logical, DIR logical), polarity 1
  std::vector<uint64_t> position;
};

std::vector<std::string> check_trace(const Trace& t) {
  PinChecker c(8, true, true);
  int64_t pos = 0;
  bool prev = false;
  for (size_t i = 0; i < t.pins.size(); ++i) {
    model::CpPulseOut o;
    o.step = t.pins[i].first;
    o.dir = t.pins[i].second;
    if (o.step && !prev) pos += o.dir ? 1 : -1;
    prev = o.step;
    o.position = i < t.position.size() ? t.position[i] : uint64_t(pos) & 0xff;
    c.check(i, t.cfg, o);
  }
  return c.errors();
}

Trace make(std::string step, std::string dir, Timing tm) {
  Trace t;
  t.cfg.cfg_step_high = tm.high;
  t.cfg.cfg_step_low = tm.low;
  t.cfg.cfg_dir_setup = tm.setup;
  t.cfg.cfg_dir_hold = tm.hold;
  for (size_t i = 0; i < step.size(); ++i) t.pins.push_back({step[i] == '1', dir[i] == '1'});
  return t;
}

TEST(PulsePinChecker, AcceptsALegalTraceAndCatchesEachViolation) {
  const Timing tm{2, 2, 2, 2};
  EXPECT_TRUE(check_trace(make("0110011000000110", "0000000001111111", tm)).empty());
  const auto has = [](const std::vector<std::string>& e, const std::string& what) {
    for (const auto& s : e)
      if (s.find(what) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has(check_trace(make("0111000", "0000000", tm)), "STEP active for 3"));
  EXPECT_TRUE(has(check_trace(make("0100000", "0000000", tm)), "STEP active for 1"));
  EXPECT_TRUE(has(check_trace(make("0110110", "0000000", tm)), "inactive for 1 cycles"));
  EXPECT_TRUE(has(check_trace(make("0110000110", "0000001111", tm)), "before a leading edge"));
  EXPECT_TRUE(has(check_trace(make("0110000110", "0000111111", tm)), "after a trailing edge"));
  EXPECT_TRUE(has(check_trace(make("0110000", "0010000", tm)), "while STEP is active"));
  EXPECT_TRUE(has(check_trace(make("0000110", "0000110", tm)), "at a STEP leading edge"));
  Trace bad_pos = make("0110000", "1111111", tm);
  bad_pos.position = {0, 0, 1, 1};
  EXPECT_TRUE(has(check_trace(bad_pos), "position_o"));
}

}  // namespace
}  // namespace cpstep::tb

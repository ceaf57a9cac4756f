// SPDX-License-Identifier: MIT
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
  configure(b, {3, 15, 15, 15}, false, false);  // PulseSmall's reset polarities: no polarity edge
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
      EXPECT_EQ(after.step, !sp) << "the pins stay at the reset idle levels after the reset";
      EXPECT_EQ(after.dir, !dp);
      EXPECT_FALSE(after.busy);
      b.run(3);
      EXPECT_EQ(b.leading.size(), 3u) << "no pulse comes out of a reset";
      // Then the pins move to the configured levels under the timing rules (the
      // checker), and the next pulse counts from 0.
      fire_at_max_rate(b, 1);
      b.run(6);
      EXPECT_EQ(b.last.step, !step_pol) << "STEP idle in the configured polarity";
      EXPECT_EQ(b.last.dir, dir_pol) << "DIR shows positive in the configured polarity";
      EXPECT_EQ(b.last.position, 1u);
      EXPECT_EQ(b.step_pol_edges.size(), 2 * size_t(step_pol != sp)) << "after each of the two resets";
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

// busy_o is exactly "the STEP pin is at its active level": not a pending DIR change,
// not step-low or setup time running (the core refuses CONFIG while it is high).
TEST(PulseDirected, BusyExactlyWhileStepActive) {
  PulseBench<sim::PulseDefault> b;
  configure(b, {3, 2, 2, 4});
  b.in.dir = false;
  b.reset();
  EXPECT_FALSE(b.peek_outputs().busy);
  b.in.step = true;
  EXPECT_FALSE(b.cycle().busy);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(b.cycle().busy) << "STEP active";
  EXPECT_FALSE(b.cycle().busy) << "trailing edge";
  b.in.dir = true;
  // Hold 4 from the trailing edge: low_cnt is 2, 3, 4 in the next three cycles and
  // DIR changes at the edge after low_cnt = 4.
  for (int i = 0; i < 3; ++i) {
    const auto o = b.cycle();
    EXPECT_FALSE(o.busy) << "a DIR change pending is not busy";
    EXPECT_FALSE(o.ready) << "but it is not ready";
  }
  const auto o = b.cycle();
  EXPECT_EQ(b.dir_edges.size(), 1u);
  EXPECT_FALSE(o.busy);
  EXPECT_FALSE(o.ready) << "setup time is still running";
  EXPECT_TRUE(b.cycle().ready);
  b.expect_pins_clean();
}

// --- polarity changes: the rules hold on the raw pins ------------------------------

// DIR polarity flipped right after a step: the physical DIR pin moves as in a
// reversal, no earlier than max(D,1) cycles after the trailing edge, and the next step
// waits max(S,1) after it. `when`: 0 from the first cycle after the trailing edge (the
// earliest a core CONFIG can do it), 1 while the pulse is still active (the core never
// does that; the pulse block copes anyway), 2 long after the last pulse.
template <class P>
void dir_polarity_flip(Timing t, int when) {
  SCOPED_TRACE("H=" + std::to_string(t.high) + " L=" + std::to_string(t.low) + " S=" +
               std::to_string(t.setup) + " D=" + std::to_string(t.hold) + " when=" + std::to_string(when));
  PulseBench<P> b;
  configure(b, t, P::model_params().step_pol_reset, P::model_params().dir_pol_reset);
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 2);
  const uint64_t d = std::max(t.hold, 1u), s = std::max(t.setup, 1u);
  for (int flip = 0; flip < 4; ++flip) {
    // The last cycle run is the first active cycle of the pulse fired last.
    const size_t n = b.leading.size(), e = b.dir_edges.size();
    if (when != 1) {
      while (b.trailing.size() < n) b.cycle();  // up to its trailing edge's cycle
      if (when == 2) b.run(t.low + t.hold + t.setup + 5);
    }
    const uint64_t at = b.now();
    b.in.cfg_dir_pol = !b.in.cfg_dir_pol;  // from cycle `at` on
    fire_at_max_rate(b, 2);
    if (b.dir_edges.size() != e + 1) {
      ADD_FAILURE() << "one physical DIR edge per polarity flip, " << b.dir_edges.size() - e << " seen";
      return b.expect_pins_clean();
    }
    const uint64_t c = b.trailing[n - 1], a = b.dir_edges[e], lead = b.leading[n];
    ASSERT_LT(c, lead);
    // The pin moves at the first edge after `at` where STEP has been inactive for D.
    EXPECT_EQ(a, std::max(at + 1, c + d)) << "DIR edge: trailing edge " << c << ", flip " << at;
    EXPECT_GE(a - c, d) << "trailing edge to DIR edge: at least hold";
    EXPECT_EQ(lead, std::max(a + s, c + t.low)) << "the next leading edge";
    EXPECT_GE(lead - a, s) << "DIR edge to leading edge: at least setup";
  }
  b.run(t.high + 1);
  EXPECT_EQ(b.last.position, 10u) << "every pulse positive: a polarity flip is no reversal";
  b.expect_pins_clean();
}

TEST(PulseDirected, DirPolarityFlipRightAfterAStepKeepsHoldAndSetup) {
  for (int when : {0, 1, 2}) {
    for (Timing t : {Timing{1, 1, 1, 1}, Timing{2, 2, 2, 3}, Timing{4, 1, 5, 7}, Timing{1, 3, 0, 0},
                     Timing{3, 9, 2, 2}})
      dir_polarity_flip<sim::PulseDefault>(t, when);
    dir_polarity_flip<sim::PulseSmall>({15, 15, 15, 15}, when);
  }
}

// Direction and DIR polarity flipped in the same cycle: the pin level wanted is the
// same, so the pin does not move and no hold or setup is spent; the count reverses.
TEST(PulseDirected, DirAndDirPolarityFlippedTogetherMoveNoPin) {
  PulseBench<sim::PulseDefault> b;
  const Timing t{2, 2, 6, 6};
  configure(b, t);
  b.in.dir = true;
  b.reset();
  fire_at_max_rate(b, 3);
  const size_t n = b.leading.size(), e = b.dir_edges.size();
  b.in.dir = false;
  b.in.cfg_dir_pol = false;
  fire_at_max_rate(b, 3);
  EXPECT_EQ(b.dir_edges.size(), e) << "the DIR pin does not move";
  EXPECT_EQ(b.leading[n] - b.leading[n - 1], t.high + t.low) << "no DIR time spent";
  b.run(t.high + 1);
  EXPECT_EQ(b.last.position, 0u) << "+3 then -3";
  b.expect_pins_clean();
}

// STEP polarity flipped while the pin is inactive: the pin moves to the new inactive
// level only once it has been inactive for step_low (so the old level is no runt), and
// the next pulse waits step_low after that edge (so the new level is no runt either).
// No STEP edge starts in the flip's first cycle (cfg_new): the edge is at max(f+2, c+L).
template <class P>
void step_polarity_flip(Timing t, bool right_after) {
  SCOPED_TRACE("H=" + std::to_string(t.high) + " L=" + std::to_string(t.low) + " S=" +
               std::to_string(t.setup) + " D=" + std::to_string(t.hold) + (right_after ? " right after" : " idle"));
  PulseBench<P> b;
  configure(b, t, P::model_params().step_pol_reset, P::model_params().dir_pol_reset);
  b.in.dir = false;
  b.reset();
  fire_at_max_rate(b, 2);
  for (int flip = 0; flip < 4; ++flip) {
    const size_t n = b.leading.size(), e = b.step_pol_edges.size();
    while (b.trailing.size() < n) b.cycle();  // up to the last pulse's trailing edge
    if (!right_after) b.run(t.low + 3);
    const uint64_t at = b.now(), c = b.trailing[n - 1];
    b.in.cfg_step_pol = !b.in.cfg_step_pol;  // from cycle `at` on
    fire_at_max_rate(b, 2);
    if (b.step_pol_edges.size() != e + 1) {
      ADD_FAILURE() << "one STEP polarity edge per polarity flip, " << b.step_pol_edges.size() - e << " seen";
      return b.expect_pins_clean();
    }
    const uint64_t p = b.step_pol_edges[e], lead = b.leading[n];
    EXPECT_EQ(p, std::max(at + 2, c + t.low)) << "polarity edge: trailing edge " << c << ", flip " << at;
    EXPECT_EQ(lead - p, t.low) << "polarity edge to leading edge: step_low";
    EXPECT_EQ(b.last.step, b.in.cfg_step_pol) << "the pulses come in the new polarity";
  }
  b.run(t.high + 1);
  EXPECT_EQ(b.last.step, !b.in.cfg_step_pol);
  EXPECT_EQ(b.checker().pulses(), 10u);
  EXPECT_EQ(b.last.position, uint64_t(-10) & (0xFFFFFFFFu >> (32 - P::pw))) << "-10";
  b.expect_pins_clean();
}

TEST(PulseDirected, StepPolarityFlipNeverMakesARuntLevel) {
  for (bool right_after : {true, false}) {
    for (Timing t : {Timing{1, 1, 0, 0}, Timing{3, 2, 1, 1}, Timing{2, 7, 3, 3}, Timing{9, 4, 0, 5}})
      step_polarity_flip<sim::PulseDefault>(t, right_after);
    step_polarity_flip<sim::PulseSmall>({15, 15, 15, 15}, right_after);
  }
}

// --- the checker catches what it claims to -----------------------------------------

struct Trace {
  model::CpPulseIn cfg;
  std::vector<std::pair<bool, bool>> pins;  // raw (STEP, DIR) levels
  std::vector<uint64_t> position;           // if given, position_o per cycle
  std::string step_pol, dir_pol;            // if given, the polarities in force per cycle
};

std::vector<std::string> check_trace(const Trace& t) {
  PinChecker c(8, true, true);
  int64_t pos = 0;
  bool prev = false;
  for (size_t i = 0; i < t.pins.size(); ++i) {
    model::CpPulseIn cfg = t.cfg;
    if (i < t.step_pol.size()) cfg.cfg_step_pol = t.step_pol[i] == '1';
    if (i < t.dir_pol.size()) cfg.cfg_dir_pol = t.dir_pol[i] == '1';
    model::CpPulseOut o;
    o.step = t.pins[i].first;
    o.dir = t.pins[i].second;
    if (o.step && !prev) pos += o.dir ? 1 : -1;  // (polarity 1 traces)
    prev = o.step;
    o.position = i < t.position.size() ? t.position[i] : uint64_t(pos) & 0xff;
    c.check(i, cfg, o);
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

bool has(const std::vector<std::string>& e, const std::string& what) {
  for (const auto& s : e)
    if (s.find(what) != std::string::npos) return true;
  return false;
}

TEST(PulsePinChecker, AcceptsALegalTraceAndCatchesEachViolation) {
  const Timing tm{2, 2, 2, 2};
  EXPECT_TRUE(check_trace(make("0110011000000110", "0000000001111111", tm)).empty());
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

// The checker judges raw pins: a polarity change is no excuse for a short level.
TEST(PulsePinChecker, JudgesRawPinsAcrossPolarityChanges) {
  const Timing tm{2, 2, 2, 2};
  // Legal: a pulse, step_low, a STEP polarity edge (to active low's idle level),
  // step_low, a pulse in the new polarity; DIR low = negative throughout.
  Trace ok = make("0110011001", "0000000000", tm);
  ok.step_pol = "1111000000";  // in force from cycle 4; the pin moves at 5
  ok.position = {0, 255, 255, 255, 255, 255, 255, 254, 254, 254};
  EXPECT_TRUE(check_trace(ok).empty()) << check_trace(ok).front();
  // The DIR polarity flipped (the direction unchanged) and the raw DIR pin moving one
  // cycle after a trailing edge: a hold violation, whatever the logical level says.
  Trace dir_flip = make("0110000", "0000111", tm);
  dir_flip.dir_pol = "1111000";
  EXPECT_TRUE(has(check_trace(dir_flip), "DIR changes 1 cycles after a trailing edge, dir_hold 2"));
  // ... and a pulse one cycle after the raw DIR edge: a setup violation.
  Trace dir_setup = make("0000000110", "0000001111", tm);
  dir_setup.dir_pol = "1111110000";
  EXPECT_TRUE(has(check_trace(dir_setup), "DIR stable for 1 cycles before a leading edge"));
  // The STEP polarity flipped under a pulse: the pin drops after 1 cycle (a runt) ...
  Trace runt = make("0101111", "0000000", tm);
  runt.step_pol = "1100000";
  EXPECT_TRUE(has(check_trace(runt), "STEP active for 1 cycles, step_high 2"));
  // ... or at its trailing edge: the pin stays, the pulse is stretched.
  Trace stretched = make("0111111", "0000000", tm);
  stretched.step_pol = "1110000";
  EXPECT_TRUE(has(check_trace(stretched), "STEP active longer than step_high 2"));
  // A STEP polarity edge one cycle after a trailing edge: a 1-cycle level.
  Trace pol_early = make("01101111", "00000000", tm);
  pol_early.step_pol = "11100000";  // in force from cycle 3, the trailing edge
  EXPECT_TRUE(has(check_trace(pol_early), "STEP inactive for 1 cycles before a STEP polarity edge, step_low 2"));
  // A pulse one cycle after a STEP polarity edge.
  Trace lead_early = make("0000100", "0000000", tm);
  lead_early.step_pol = "1000000";
  EXPECT_TRUE(has(check_trace(lead_early), "STEP inactive for 1 cycles before a pulse"));
}

}  // namespace
}  // namespace cpstep::tb

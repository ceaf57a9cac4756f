// SPDX-License-Identifier: MIT
// The phase timer (rtl/cp_ptimer.v) against its model twin (model/cp_ptimer.h)
// every cycle: random phases of every kind (carry, rest, reload, timed, rest and
// timed), words written out of order and while the buffer is full, moves fired
// late, the clock held, clears and resets; and the host's phases for an S-curve
// (plan::PhaseFitter) through both, every move due at the clock the fitter says.
#include <gtest/gtest.h>

#include <deque>
#include <random>
#include <utility>

#include "Vcp_ptimer.h"
#include "common/lockstep.h"
#include "core/core_bench.h"
#include "model/cp_ptimer.h"
#include "plan/phases.h"
#include "plan/profile.h"
#include "sim/dut.h"

namespace cpstep::tb {
namespace {

#define CPSTEP_FIELD(name, expr) {name, [](const Out& o) { return uint64_t(expr); }}

struct PtimerPort {
  using Rtl = AfterOneResetEdge<Vcp_ptimer>;
  using Model = model::CpPtimer;
  using In = model::CpPtimerIn;
  using Out = model::CpPtimerOut;
  static Model::Params model_params() { return {}; }
  static void drive(Rtl& r, const In& i) {
    r.rst = i.rst;
    r.clear_i = i.clear;
    r.adv_i = i.adv;
    r.wr_i = i.wr;
    r.sel_i = i.sel;
    r.data_i = i.data;
    r.fire_i = i.fire;
    r.len_i = i.len & ((uint64_t{1} << 62) - 1);
  }
  static Out sample(const Rtl& r) {
    Out o;
    o.due = r.due_o;
    o.active = r.active_o;
    o.ready = r.ready_o;
    o.starved = r.starved_o;
    o.kind = r.kind_o;
    return o;
  }
  static const std::vector<sim::Field<Out>>& fields() {
    static const std::vector<sim::Field<Out>> f = {
        CPSTEP_FIELD("due_o", o.due),         CPSTEP_FIELD("active_o", o.active),
        CPSTEP_FIELD("ready_o", o.ready),     CPSTEP_FIELD("starved_o", o.starved),
        CPSTEP_FIELD("kind_o", o.kind),
    };
    return f;
  }
};

using Rng = std::mt19937_64;
uint64_t pick(Rng& rng, uint64_t lo, uint64_t hi) { return std::uniform_int_distribution<uint64_t>(lo, hi)(rng); }
bool chance(Rng& rng, unsigned pct) { return pick(rng, 0, 99) < pct; }

// A phase's words, W0 last: {sel, data}.
std::vector<std::pair<uint32_t, uint32_t>> phase_words(bool reload, bool rest, bool timed, uint32_t ticks, int64_t u,
                                                       uint64_t p_top, int64_t v, int64_t h) {
  std::vector<std::pair<uint32_t, uint32_t>> w;
  w.push_back({1, uint32_t(u)});
  if (reload) {
    w.push_back({2, uint32_t(p_top)});
    w.push_back({3, uint32_t(p_top >> 32)});
    w.push_back({4, uint32_t(v)});
    w.push_back({5, uint32_t(uint64_t(v) >> 32)});
    w.push_back({6, uint32_t(h)});
    w.push_back({7, uint32_t(uint64_t(h) >> 32)});
  }
  w.push_back({0, uint32_t(reload) << 31 | uint32_t(rest) << 30 | uint32_t(timed) << 29 | (ticks & 0xFFFFFF)});
  return w;
}

TEST(Ptimer, RandomPhasesMatchTheModel) {
  Rng rng(core_seed(2611));
  Lockstep<PtimerPort> ls("ptimer");
  ls.reset();
  model::CpPtimerIn in;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  uint64_t fired = 0, late = 0, starves = 0, loads[8] = {}, timed_fired = 0;
  model::CpPtimerOut last;
  uint64_t held_fire = 0;
  for (int c = 0; c < 5000000; ++c) {
    in.rst = pick(rng, 0, 399999) == 0;
    in.clear = pick(rng, 0, 199999) == 0;
    in.adv = chance(rng, 92);
    if (words.empty() && chance(rng, 30)) {
      const uint32_t r = uint32_t(pick(rng, 0, 99));
      // Kinds: reload, rest, timed, rest and timed, rest and reload (reload wins), carry.
      const bool both = r >= 40 && r < 45;
      const bool reload = r < 15 || both, rest = (r >= 15 && r < 30) || both,
                 timed = (r >= 30 && r < 40) || (r >= 25 && r < 30);
      const uint32_t ticks = chance(rng, 5) ? 0 : chance(rng, 80) ? uint32_t(pick(rng, 1, 6)) : uint32_t(pick(rng, 7, 300));
      // Steps of about 2^50..2^56 against lengths of 2^52..2^58: moves a few clocks to a few hundred apart.
      const int64_t u = chance(rng, 10) ? int64_t(int32_t(rng())) : int64_t(pick(rng, 0, 1u << 22)) - (1 << 21);
      const int64_t v = chance(rng, 5) ? int64_t(rng()) : int64_t(pick(rng, 0, uint64_t{1} << 54));
      const int64_t h = chance(rng, 5) ? int64_t(rng()) : int64_t(pick(rng, 0, uint64_t{1} << 38)) - (int64_t{1} << 37);
      auto w = phase_words(reload, rest, timed, ticks, u, rng(), v, h);
      if (chance(rng, 20)) std::shuffle(w.begin(), w.end() - 1, rng);   // W0 stays last
      if (chance(rng, 3)) std::shuffle(w.begin(), w.end(), rng);        // W0 early: later words go elsewhere or nowhere
      for (auto& x : w) words.push_back(x);
    }
    const model::CpPtimerOut& o = last;
    in.wr = false;
    if (!words.empty() && (o.ready || chance(rng, 5)) && chance(rng, 85)) {
      in.wr = true;
      in.sel = words.front().first;
      in.data = words.front().second;
      words.pop_front();
    }
    // The runner fires a due move at once, mostly; now and then it is late.
    if (o.due && held_fire == 0 && chance(rng, 3)) held_fire = pick(rng, 1, 40);
    in.fire = o.due && held_fire == 0 ? true : chance(rng, 1);
    if (held_fire > 0) --held_fire;
    if (chance(rng, 2)) in.len = pick(rng, uint64_t{1} << 52, uint64_t{1} << 58);
    if (chance(rng, 1)) in.len = rng();   // anything, beyond 62 bits too
    const model::CpPtimerOut out = ls.step(in);
    fired += out.due && in.fire;
    late += out.due && !in.fire;
    timed_fired += out.due && in.fire && (out.kind & 1);
    starves += out.starved && !last.starved;
    if (out.active && (!last.active || out.kind != last.kind)) ++loads[out.kind & 7];
    last = out;
  }
  std::printf("fired %llu, late %llu, starves %llu, timed fired %llu, loads by kind %llu %llu %llu %llu %llu %llu\n",
              (unsigned long long)fired, (unsigned long long)late, (unsigned long long)starves,
              (unsigned long long)timed_fired, (unsigned long long)loads[0], (unsigned long long)loads[1],
              (unsigned long long)loads[2], (unsigned long long)loads[3], (unsigned long long)loads[4],
              (unsigned long long)loads[6]);
  EXPECT_GT(fired, 20000u);
  EXPECT_GT(late, 1000u);
  EXPECT_GT(starves, 50u);
  EXPECT_GT(timed_fired, 50u);
  for (unsigned k : {0u, 1u, 2u, 3u, 4u, 6u}) EXPECT_GT(loads[k], 50u) << "phases of kind " << k;
}

// The host's phases for two S-curves in moves (a stop between), written to the
// timer as the buffer frees: every move due at the fitter's clock, in both.
TEST(Ptimer, TheHostsPhasesFireEveryMoveWhereTheFitterSays) {
  const plan::PhaseFormat fmt{6, 60, true, false, 0.0};
  const double tol = 40, hz = 40e6;
  plan::PhaseFitter fitter(fmt, tol);
  auto curve = [&](double L, double vmax, double start_s) {
    const auto p = plan::make_profile(L, 0, 0, vmax, 40000, 160000);
    EXPECT_TRUE(p.has_value());
    std::vector<double> t;
    for (int n = 1; n <= int(L); ++n)
      t.push_back((start_s + (n == int(L) ? p->duration : p->time_at(double(n)))) * hz);
    return t;
  };
  const auto a = curve(300, 6000, 0.0);
  const double b_start = a.back() / hz + 0.01;
  const auto b = curve(120, 3000, b_start);
  ASSERT_TRUE(fitter.push(a, {}, 0.0));
  ASSERT_TRUE(fitter.push(b, {}, b_start * hz));
  ASSERT_TRUE(fitter.finish()) << fitter.error();
  const auto& want = fitter.fire_clocks();
  ASSERT_EQ(want.size(), a.size() + b.size());

  Lockstep<PtimerPort> ls("ptimer_host");
  ls.reset();
  model::CpPtimerIn in;
  in.len = uint64_t{1} << 60;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  std::size_t next_phase = 0;
  const auto& phases = fitter.phases();
  int64_t start = -1;
  std::vector<int64_t> got;
  for (int64_t c = 0; c < int64_t(b.back()) + 1000 && got.size() < want.size(); ++c) {
    // The model tells this cycle's outputs before the inputs that depend on them
    // (the runner fires a due move in its cycle; the outputs do not depend on fire_i).
    ls.model().in = in;
    const model::CpPtimerOut now = ls.model().outputs();
    if (words.empty() && now.ready && next_phase < phases.size()) {
      const plan::TimerPhase& ph = phases[next_phase++];
      for (auto& w : phase_words(ph.reload, ph.rest, ph.timed, uint32_t(ph.ticks), ph.jerk, ph.p_top, ph.v, ph.a))
        words.push_back(w);
    }
    in.wr = !words.empty();
    if (in.wr) {
      in.sel = words.front().first;
      in.data = words.front().second;
      words.pop_front();
    }
    in.fire = now.due;
    const model::CpPtimerOut out = ls.step(in);
    if (out.active && start < 0) start = c;
    if (out.due) got.push_back(c - start);
    ASSERT_FALSE(out.starved && got.size() < want.size()) << "the timer ran out of phases at cycle " << c;
  }
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t n = 0; n < want.size(); ++n) ASSERT_EQ(got[n], want[n]) << "move " << n;
}

}  // namespace
}  // namespace cpstep::tb

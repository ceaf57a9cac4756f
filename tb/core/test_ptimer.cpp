// SPDX-License-Identifier: MIT
// The phase timer (rtl/cp_ptimer.v) against its model twin (model/cp_ptimer.h)
// every cycle: random phases of every kind (carry, rest, reload, timed, rest and
// timed), words written out of order and while the buffer is full, moves fired
// late, the clock held, lengths not yet known (owed), clears and resets; and the host's phases for an S-curve
// (plan::PhaseFitter) through both, every move due at the clock the fitter says.
#include <gtest/gtest.h>

#include <deque>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "Vcp_ptimer.h"
#include "common/lockstep.h"
#include "core/bench_random.h"
#include "core/core_bench.h"
#include "core/ptimer_words.h"
#include "model/cp_ptimer.h"
#include "cpstep/builds.h"
#include "plan/phases.h"
#include "plan/pipeline.h"
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
    r.len_valid_i = i.len_valid;
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

using unit_random::Rng;
using unit_random::pick;
using unit_random::chance;

// A random phase's words, W0 last. Kinds: carry (half the phases), else any
// combination of the four bits; a few ticks mostly; steps of about 2^50..2^56 against
// lengths of 2^48..2^56 (2^54..2^62 in r): moves a clock to a few thousand apart.
std::vector<std::pair<uint32_t, uint32_t>> random_phase(Rng& rng, unsigned long_pct = 20) {
  const uint32_t kind = chance(rng, 50) ? 0 : uint32_t(pick(rng, 1, 15));
  const uint32_t ticks = chance(rng, 5)                  ? 0
                         : chance(rng, 100 - long_pct) ? uint32_t(pick(rng, 1, 6))
                                                         : uint32_t(pick(rng, 7, 300));
  const int64_t u = chance(rng, 10) ? int64_t(int32_t(rng())) : int64_t(pick(rng, 0, 1u << 22)) - (1 << 21);
  const int64_t s = chance(rng, 5) ? int64_t(rng()) : int64_t(pick(rng, 0, uint64_t{1} << 54));
  const int64_t h = chance(rng, 5) ? int64_t(rng()) : int64_t(pick(rng, 0, uint64_t{1} << 38)) - (int64_t{1} << 37);
  // r: a fraction of a move to go (r < 0), now and then anything.
  const uint64_t r_top = chance(rng, 80) ? uint64_t(-int64_t(pick(rng, 0, uint64_t{1} << 59))) : rng();
  return phase_words(kind, ticks, u, r_top, s, h);
}

TEST(Ptimer, RandomPhasesMatchTheModel) {
  Rng rng(core_seed(2611));
  Lockstep<PtimerPort> ls("ptimer");
  ls.reset();
  model::CpPtimerIn in;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  uint64_t fired = 0, late = 0, starves = 0, loads[16] = {}, timed_fired = 0;
  model::CpPtimerOut last;
  uint64_t held_fire = 0, unknown = 0, owed_fires = 0;
  for (int c = 0; c < 5000000; ++c) {
    in.rst = pick(rng, 0, 399999) == 0;
    in.clear = pick(rng, 0, 199999) == 0;
    in.adv = chance(rng, 92);
    if (words.empty() && chance(rng, 30)) {
      auto w = random_phase(rng);
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
    // (More often while a length is not known or in a timed phase: a length owed when
    // a timed move came due must stay dropped when it becomes known before the fire.)
    if (o.due && held_fire == 0 && chance(rng, (o.kind & 2) || unknown > 0 ? 30 : 3)) held_fire = pick(rng, 1, 40);
    in.fire = o.due && held_fire == 0 ? true : chance(rng, 1);
    if (held_fire > 0) --held_fire;
    if (chance(rng, 2)) in.len = pick(rng, uint64_t{1} << 48, uint64_t{1} << 56);
    if (pick(rng, 0, 9999) < 3) in.len = rng();   // anything, beyond 62 bits too
    // Now and then the next length is not known for a while (owed).
    if (unknown == 0 && chance(rng, 1)) unknown = pick(rng, 1, 200);
    in.len_valid = unknown == 0;
    if (unknown > 0) --unknown;
    const model::CpPtimerOut out = ls.step(in);
    fired += out.due && in.fire;
    owed_fires += out.due && in.fire && !in.len_valid;
    late += out.due && !in.fire;
    timed_fired += out.due && in.fire && (out.kind & 2);
    starves += out.starved && !last.starved;
    if (out.active && (!last.active || out.kind != last.kind)) ++loads[out.kind & 15];
    last = out;
  }
  std::printf("fired %llu, late %llu, starves %llu, timed fired %llu, fired with the next length owed %llu\n",
              (unsigned long long)fired, (unsigned long long)late, (unsigned long long)starves,
              (unsigned long long)timed_fired, (unsigned long long)owed_fires);
  // What the run covers (the checks are the lockstep's, every cycle): fires, late
  // fires, starving, timed moves, loads of every kind.
  EXPECT_GT(fired, 10000u);
  EXPECT_GT(late, 1000u);
  EXPECT_GT(starves, 50u);
  EXPECT_GT(timed_fired, 50u);
  EXPECT_GT(owed_fires, 1000u);
  for (unsigned k = 0; k < 16; ++k) EXPECT_GT(loads[k], 10u) << "phases of kind " << k;
}

// Event skipping (CpPtimer::quiet_advs, skip_advs; the fast engine's PTIMER core):
// a model ticked clock by clock under random phases (fires at once, lengths owed
// now and then), and at random quiet points a copy that skips. Every clock the
// ticked one takes in a skipped span must show what the first showed (nothing due,
// no phase ending), and after the span both must hold the same r, step, H and
// outputs. And the skips must not be timid: the advance after a whole quiet span
// mostly brings the event that ended it (a move due, a phase's end).
TEST(Ptimer, SkippedAdvancesLandWhereClockedOnesDo) {
  Rng rng(core_seed(2612));
  model::CpPtimer a;
  model::CpPtimerIn in;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  uint64_t spans = 0, span_clocks = 0, whole = 0, ended = 0, owed_spans = 0, timed_spans = 0, flat_spans = 0;
  bool unknown = false;
  for (int c = 0; c < 1000000; ++c) {
    if (words.empty() && chance(rng, 30)) {
      // Now and then a rest that stays flat (u = 0: a dwell's phases), skipped whole.
      const auto w = chance(rng, 8) ? phase_words(4, uint32_t(pick(rng, 1, 3000)), 0, 0, 0, 0) : random_phase(rng, 60);
      for (auto& x : w) words.push_back(x);
    }
    a.in = {};
    model::CpPtimerOut o = a.outputs();
    if (chance(rng, 1)) unknown = !unknown;
    a.in.len_valid = !unknown;
    a.in.len = pick(rng, uint64_t{1} << 48, uint64_t{1} << 56);
    a.in.adv = chance(rng, 92);
    a.in.fire = o.due;
    if (!words.empty() && o.ready && chance(rng, 85)) {
      a.in.wr = true;
      a.in.sel = words.front().first;
      a.in.data = words.front().second;
      words.pop_front();
    }
    const uint64_t limit = pick(rng, 1, 100000);
    const std::optional<uint64_t> q = a.quiet_advs(a.in.len_valid, limit);
    if (!a.in.wr && !o.due && q && *q > 0 && *q != model::CpPtimer::kForever && chance(rng, 20)) {
      const uint64_t n = chance(rng, 50) ? *q : pick(rng, 1, *q);
      model::CpPtimer b = a;
      b.skip_advs(n);
      a.in.adv = true;
      for (uint64_t k = 0; k < n; ++k) {
        a.tick();
        ASSERT_EQ(a.outputs(), o) << "clock " << c << ": advance " << k + 1 << " of " << n << " quiet ones";
      }
      ASSERT_TRUE(a.r() == b.r() && a.step() == b.step() && a.h() == b.h()) << "clock " << c << ", " << n << " skipped";
      ASSERT_EQ(a.outputs(), b.outputs());
      ++spans;
      span_clocks += n;
      owed_spans += unknown;
      flat_spans += a.step() == 0 && a.h() == 0 && n > 64;
      timed_spans += (o.kind & 2) != 0;
      if (n == *q && n < limit) {
        // The advance after the whole span: is it an event (an output changes, or
        // the phase ends and the next one loads)?
        model::CpPtimer e = a;
        e.tick();
        ++whole;
        ended += !(e.outputs() == o) || e.loads() != a.loads();
      }
      continue;
    }
    a.tick();
  }
  std::printf("%llu spans skipped, %llu clocks, %llu of them owed, %llu timed, %llu flat over a tick; %llu of %llu "
              "whole spans ended by an event\n",
              (unsigned long long)spans, (unsigned long long)span_clocks, (unsigned long long)owed_spans,
              (unsigned long long)timed_spans, (unsigned long long)flat_spans, (unsigned long long)ended, (unsigned long long)whole);
  EXPECT_GT(spans, 5000u);
  EXPECT_GT(owed_spans, 50u);
  EXPECT_GT(timed_spans, 100u);
  EXPECT_GT(flat_spans, 100u) << "flat rests skipped more than a tick at once";
  EXPECT_GT(ended * 10, whole * 9) << "most quiet spans end where an event comes";
}

// The host's phases written to the timer (RTL and twin in lockstep) as its buffer
// frees, each move fired in its cycle with its own length (lens[n]): the clock of
// each move's due, counted from the first phase's load, and whether the timer
// ran out of phases before the last move.
void run_host_phases(const std::string& name, const std::vector<plan::TimerPhase>& phases,
                     const std::vector<uint64_t>& lens, int64_t max_cycles, std::vector<int64_t>& got) {
  Lockstep<PtimerPort> ls(name);
  ls.reset();
  model::CpPtimerIn in;
  std::deque<std::pair<uint32_t, uint32_t>> words;
  std::size_t next_phase = 0;
  int64_t start = -1;
  for (int64_t c = 0; got.size() < lens.size() && (start < 0 || c - start < max_cycles); ++c) {
    // The model tells this cycle's outputs before the inputs that depend on them
    // (the runner fires a due move in its cycle; the outputs depend on neither
    // fire_i nor len_i).
    ls.model().in = in;
    const model::CpPtimerOut now = ls.model().outputs();
    // The length of the move pending after this cycle: the next one's if it fires.
    in.len = lens[std::min(got.size() + (now.due ? 1 : 0), lens.size() - 1)];
    if (words.empty() && now.ready && next_phase < phases.size())
      for (auto& w : host_phase_words(phases[next_phase++])) words.push_back(w);
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
    ASSERT_FALSE(out.starved && got.size() < lens.size())
        << "the timer ran out of phases at cycle " << c << " after " << got.size() << " of " << lens.size()
        << " moves (phase " << next_phase << " of " << phases.size() << ")";
  }
}

// Phases of constant steps of 2^50 against moves of 2^50 (2^56 in r): a move every
// tick (64 clocks) from rest, the last in a 2-tick phase's last clock.
constexpr int64_t kEdgeStep = int64_t(1) << 50;
plan::TimerPhase edge_run() {
  plan::TimerPhase run;
  run.ticks = 2;
  run.rest = run.adjust = true;
  run.s = kEdgeStep;
  return run;
}

// The host's arithmetic for `phases` (plan::simulate_phases) is `want`, and the timer
// (RTL and twin in lockstep) fires every move at those clocks.
void expect_timer_fires_as_host(const std::string& name, const std::vector<plan::TimerPhase>& phases,
                                const std::vector<int64_t>& want, int64_t max_cycles) {
  const plan::PhaseFormat fmt{6, 60, true, false, 1.0};
  const std::vector<plan::i128> lengths(want.size(), plan::i128(kEdgeStep));
  ASSERT_EQ(plan::simulate_phases(phases, fmt, lengths), want) << "the host's arithmetic";
  std::vector<int64_t> got;
  ASSERT_NO_FATAL_FAILURE(
      run_host_phases(name, phases, std::vector<uint64_t>(want.size(), uint64_t(kEdgeStep)), max_cycles, got));
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t n = 0; n < want.size(); ++n) EXPECT_EQ(got[n], want[n]) << "move " << n;
}

// A move that comes due in the last clock of a jerk phase followed by a timed move
// (the last move of a stop): the host's arithmetic (plan::simulate_phases) fires it
// there, and so must the card, although its due shows in the timed phase's first
// clock (r came due while the step was still added). Found by the plasma example on
// the phase-timer card (`cpstep run --board hx8k_pt`), where the card, which took no
// r-due in a timed phase, fired it at the timed move's end and lost a move.
TEST(Ptimer, AMoveDueInTheLastClockBeforeATimedMoveFiresThere) {
  plan::TimerPhase timed;
  timed.ticks = 100;
  timed.timed = true;
  // Moves due at clocks 64 and 128 (the run's last), the stop's last move 100 clocks on,
  // then from rest again: two more.
  expect_timer_fires_as_host("ptimer_timed_edge", {edge_run(), timed, edge_run()}, {64, 128, 228, 292, 356}, 1000);
}

// The same where the next phase replaces r: a start from rest, and a reload of r (the
// host's r for the move after the one due). Found by a rapid on the mill
// (`cpstep run` of G0 X20 Y20 Z-5, examples/machines/mill.toml, --board hx8k_pt): its
// 10th move came due in the last clock before a reload and the card, whose r the reload
// replaced, never fired it (the job a move behind, then an underrun).
TEST(Ptimer, AMoveDueInTheLastClockBeforeARestOrAReloadFiresThere) {
  plan::TimerPhase reload;
  reload.ticks = 2;
  reload.reload = true;
  reload.s = kEdgeStep;
  reload.r_top = -(int64_t(1) << 50);   // r = -2^55: half a move (2^56 in r) to go
  expect_timer_fires_as_host("ptimer_reload_edge", {edge_run(), edge_run(), reload, edge_run()},
                             {64, 128, 192, 256, 288, 352, 448, 512}, 2000);
}

// The host's phases for two S-curves (a stop between) along a path of 1 mm moves,
// the plan's own phases given (corrected where needed), written to the timer as
// its buffer frees: every move due at the fitter's clock, in both.
TEST(Ptimer, TheHostsPhasesFireEveryMoveWhereTheFitterSays) {
  plan::PhaseFormat fmt{6, 60, true, false, 1.0};
  const double tol = 40, hz = 40e6;
  fmt.clock_hz = hz;
  plan::PhaseFitter fitter(fmt, tol);
  std::vector<double> all;
  auto curve = [&](double L, double vmax, double start_s) {
    const auto p = plan::make_profile(L, 0, 0, vmax, 40000, 160000);
    EXPECT_TRUE(p.has_value());
    std::vector<double> t;
    for (int n = 1; n <= int(L); ++n)
      t.push_back((start_s + (n == int(L) ? p->duration : p->time_at(double(n)))) * hz);
    std::vector<plan::PlanJerk> plan;
    for (const plan::Phase& ph : p->phases)
      if (ph.duration > 0) plan.push_back({(start_s + ph.t0) * hz, ph.jerk, ph.v0, ph.a0});
    const std::vector<double> lengths(t.size(), 1.0);
    EXPECT_TRUE(fitter.push(t, lengths, start_s * hz, plan)) << fitter.error();
    all.insert(all.end(), t.begin(), t.end());
    return t.back() / hz;
  };
  const double a_end = curve(300, 6000, 0.0);
  const double b_end = curve(120, 3000, a_end + 0.01);
  ASSERT_TRUE(fitter.finish()) << fitter.error();
  const auto& want = fitter.fire_clocks();
  ASSERT_EQ(want.size(), all.size());
  EXPECT_GT(fitter.stats().plan_phases, 4u) << "the plan's own phases";

  std::vector<int64_t> got;
  ASSERT_NO_FATAL_FAILURE(run_host_phases("ptimer_host", fitter.phases(),
                                          std::vector<uint64_t>(want.size(), uint64_t(plan::move_length(1.0, fmt))),
                                          int64_t(b_end * hz) + 1000, got));
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t n = 0; n < want.size(); ++n) ASSERT_EQ(got[n], want[n]) << "move " << n;
}

// An example job (tab.ngc on the default board, seed002.toml): the host's
// phases for it, the plan's own where they fit, through the RTL and its twin,
// each move's length from its card segment: every move due at the fitter's clock.
TEST(Ptimer, AnExampleJobsMovesFireWhereTheFitterSays) {
  auto loaded = plan::load_machine(std::string(CPSTEP_SOURCE_DIR) + "/examples/machines/seed002.toml");
  ASSERT_TRUE(loaded.ok());
  const builds::Build& b = *builds::find(builds::kDefaultBoard);
  plan::Machine m = *loaded;
  ASSERT_TRUE(plan::bind_card(m, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw}).empty());
  auto job = plan::load_gcode(std::string(CPSTEP_SOURCE_DIR) + "/examples/jobs/tab.ngc");
  ASSERT_TRUE(job.ok());
  plan::PhaseFormat fmt{6, 60, true, false, 0.0125};
  fmt.clock_hz = m.card.clock_hz;
  plan::PhaseFitter fitter(fmt, m.chunk_tolerance_cycles());
  std::vector<uint64_t> lens;
  plan::PlanOptions o;
  o.on_move_times = [&](std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at,
                        std::span<const plan::PlanJerk> changes) {
    for (double l : lengths_mm) lens.push_back(uint64_t(plan::move_length(l, fmt)));
    EXPECT_TRUE(fitter.push(ideal, lengths_mm, rest_at, changes)) << fitter.error();
  };
  ASSERT_TRUE(plan::plan_job(*job, m, o).ok());
  ASSERT_TRUE(fitter.finish()) << fitter.error();
  const auto& want = fitter.fire_clocks();
  ASSERT_EQ(want.size(), lens.size());
  EXPECT_GT(fitter.stats().plan_phases, fitter.stats().phases / 2);

  std::vector<int64_t> got;
  ASSERT_NO_FATAL_FAILURE(run_host_phases("ptimer_tab", fitter.phases(), lens, want.back() + 1000, got));
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t n = 0; n < want.size(); ++n) ASSERT_EQ(got[n], want[n]) << "move " << n;
}

}  // namespace
}  // namespace cpstep::tb

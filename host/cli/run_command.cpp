// SPDX-License-Identifier: MIT
#include "cli/run_command.h"

#include <unistd.h>

#include <fmt/format.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>

#include "card/caps.h"
#include "card/card_client.h"
#include "card/frame.h"
#include "card/spidev.h"
#include "cli/run_contours.h"
#include "cpstep/builds.h"
#include "run/card_job.h"
#include "run/feed_ramp.h"
#include "run/home.h"
#include "run/link_run.h"
#include "run/measure.h"
#include "run/plots.h"
#include "run/report.h"
#include "run/sim_run.h"

namespace cpstep::cli {

namespace {

namespace fs = std::filesystem;

constexpr int kExitFault = 1;
constexpr int kExitRefused = 2;
// spidev: the SCK rate the host connects at before the card has said its clock
// (clk/8 of any card clock of 8 MHz or more).
constexpr uint64_t kConnectSpiHz = 1'000'000;

void print_diagnostics(const plan::Result<run::CardJob>& r) {
  for (const plan::Diagnostic& w : r.warnings) {
    if (w.loc.line > 0)
      fmt::print(stderr, "{}:{}:{}: warning: {}\n", w.file, w.loc.line, w.loc.col, w.message);
    else
      fmt::print(stderr, "{}: warning: {}\n", w.file, w.message);
  }
  for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
}

// The capabilities of a board of rtl/builds.json, for planning without a card
// (file transport, `cpstep plan`); nullopt (message printed) for no such board.
std::optional<card::CardCaps> board_caps(const char* command, const std::string& board) {
  const std::string name = board.empty() ? std::string(builds::kDefaultBoard) : board;
  auto caps = card::board_caps(name);
  if (!caps) fmt::print(stderr, "cpstep {}: --board {}: no such board (boards: {})\n", command, name, card::board_names());
  return caps;
}

// Plans the job for the card with these capabilities (by contours when
// `contours` is active; else streamed when asked: run::CardJob::streamed); prints
// every diagnostic. nullopt when it is refused or, by contours, nothing is left
// to run.
std::optional<run::CardJob> prepare(const std::string& job, const std::string& machine,
                                    const card::CardCaps& caps, const plan::PerAxis<int64_t>& start = {},
                                    ContourRun* contours = nullptr, bool streamed = false) {
  if (const std::string why = card::unusable(caps, plan::kAxes); !why.empty()) {
    fmt::print(stderr, "cpstep: {}: cannot plan for this card\n", why);
    return std::nullopt;
  }
  auto r = contours && contours->active() ? contours->plan(caps, start)
                                          : run::prepare_job(job, machine, caps, start, streamed);
  print_diagnostics(r);
  if (!r.ok()) return std::nullopt;
  return std::move(*r.value);
}

void print_plan_summary(const run::CardJob& j) {
  const plan::PlanStats& s = j.planned.stats;
  const uint64_t chunks = j.wire_chunks();
  fmt::print("job        {}\n", j.job_file);
  fmt::print("machine    {}\n", j.machine.file);
  fmt::print("card       {}\n", card::describe(j.caps));
  const uint64_t conics = j.conic_segments();
  if (conics)
    fmt::print("segments   {} card segments, {} of them CONIC ({} step segments)\n", j.wire_segments(), conics,
               s.step_segments);
  else
    fmt::print("segments   {} card segments ({} step segments)\n", j.wire_segments(), s.step_segments);
  if (j.machine.planner.fit_arcs_mm > 0)  // planner.fit_arcs_mm: G1 chains as arcs
    fmt::print("fitted     {} arcs from {} G1 lines, {} lines from {}; within {:.4f} mm of the G-code "
               "(planner.fit_arcs_mm = {:g})\n",
               s.fit.arcs, s.fit.lines_in_arcs, s.fit.merged, s.fit.lines_in_merged, s.fit.max_deviation_mm,
               j.machine.planner.fit_arcs_mm);
  if (s.fit.curves)  // NURBS as arcs on a card that walks them
    fmt::print("nurbs      {} NURBS as {} arcs and {} lines, within {:.4f} mm of the curves (planner.arc_tolerance_mm "
               "= {:g}, the card walks arcs)\n",
               s.fit.curves, s.fit.curve_arcs, s.fit.curve_lines, s.fit.curve_max_deviation_mm,
               j.machine.planner.arc_tolerance_mm);
  if (j.caps.ciw && s.conic_arcs + s.chord_arcs > 0) {  // a card with a walker: how the arcs went
    fmt::print("arcs       {} walked by the card's conic walker ({} CONIC segments), {} as chords", s.conic_arcs,
               s.conic_segments, s.chord_arcs);
    if (s.conic_arcs)
      fmt::print("; nodes within {:.3f} step of the arcs, other axes within {:.3f}", s.conic.max_node_deviation,
                 s.conic.max_other_deviation);
    fmt::print("\n");
  }
  fmt::print("moves      {}\n", j.moves());
  if (j.caps.ptimer)
    fmt::print("phases     {} PHASE commands timing the moves on the card's phase timer (no chunks)\n", j.phases);
  else
    fmt::print("chunks     {}, {:.2f} moves per chunk\n", chunks, chunks ? double(j.moves()) / double(chunks) : 0.0);
}

std::string axis_positions(const run::CardJob& j, const plan::PerAxis<int64_t>& steps) {
  std::string s;
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = j.machine.axes[a];
    if (!ax.present) continue;
    s += fmt::format("{}{} {} steps = {:.4f} mm", s.empty() ? "" : ", ", plan::kAxisLetters[a], steps[a],
                     double(steps[a]) / ax.steps_per_mm);
  }
  return s;
}

// Percentage of moves on stderr, at most ten times a second, when it is a terminal.
class Progress {
 public:
  explicit Progress(bool on) : on_(on && ::isatty(STDERR_FILENO)) {}
  void update(uint64_t done, uint64_t total) {
    if (!on_ || total == 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (shown_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    shown_ = true;
    fmt::print(stderr, "\rcpstep run: {:3d}% of {} moves", int(100 * done / total), total);
    std::fflush(stderr);
  }
  void clear() {
    if (shown_) fmt::print(stderr, "\r{:40}\r", "");
    shown_ = false;
  }

 private:
  bool on_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

int run_file_transport(const RunOptions& o, const run::CardJob& j) {
  if (!run::write_words(o.out, j.words)) {
    fmt::print(stderr, "cpstep run: cannot write {}\n", o.out);
    return kExitFault;
  }
  print_plan_summary(j);
  fmt::print("planned    {:.6f} s\n", j.planned.stats.duration_s);
  fmt::print("sent       {} command words ({} bytes, little-endian) to {}\n", j.words.size(),
             4 * j.words.size(), o.out);
  return 0;
}

// The outputs of a run are checked before it starts: nothing is sent when one
// cannot be written. Returns 0 or kExitRefused.
int open_outputs(const RunOptions& o, std::ofstream& report_file) {
  if (!o.plots.empty() && run::find_gnuplot().empty()) {
    fmt::print(stderr, "cpstep run: --plots needs gnuplot, which is not on PATH (scripts/deps installs it)\n");
    return kExitRefused;
  }
  // Parent directories of the outputs are made for the user, as --plots makes its own.
  for (const std::string& f : {o.report, o.vcd}) {
    std::error_code ec;
    if (!f.empty() && fs::path(f).has_parent_path()) fs::create_directories(fs::path(f).parent_path(), ec);
  }
  if (!o.vcd.empty() && !std::ofstream(o.vcd, std::ios::trunc)) {
    fmt::print(stderr, "cpstep run: cannot write {}\n", o.vcd);
    return kExitRefused;
  }
  if (!o.report.empty()) {
    report_file.open(o.report, std::ios::trunc);
    if (!report_file) {
      fmt::print(stderr, "cpstep run: cannot write {}\n", o.report);
      return kExitRefused;
    }
  }
  return 0;
}

std::string link_line(const run::CardRun& r) {
  const run::LinkReport& l = r.link;
  const card::LinkStats& s = l.stats;
  const std::string where = l.sck_div ? fmt::format("SPI at clk/{} = {:.3f} MHz", l.sck_div, l.sck_hz / 1e6)
                                      : fmt::format("{} at {:.3f} MHz", l.link, l.sck_hz / 1e6);
  std::string busy;
  if (l.sck_div && r.sim_cycles)
    busy = fmt::format(", busy {:.2f}% of the time", 100.0 * double(l.busy_cycles) / double(r.sim_cycles));
  return fmt::format("{}: {} frames ({} with commands, {} polls), {} bytes{}, longest gap between frames "
                     "{:.1f} ms; {} resent, {} bad replies",
                     where, s.transfers, s.command_frames, s.polls, s.bytes, busy, 1e3 * s.longest_gap_s, s.resent,
                     s.bad_replies);
}

// A Klipper queue_step cost as the `wire` line states it.
static std::string klipper_text(const plan::QueueStepCost& c) {
  return c.error.empty() ? fmt::format("{} bytes ({} messages)", c.bytes,
                                       c.queue_step + c.set_next_step_dir + c.reset_step_clock)
                         : fmt::format("not countable: {}", c.error);
}

// The summary on stdout and the faults and warnings on stderr; returns the exit code.
int print_run(const RunOptions& o, const run::CardJob& j, const run::CardRun& run_in, run::RunMeter& meter,
              double wall_s, std::ofstream& report_file) {
  const run::RunMeasure m = meter.finish(run_in);
  run::CardRun r = run_in;
  run::add_phase_timer_fault(j, m, r);
  int rc = r.ok() ? 0 : kExitFault;
  if (report_file.is_open()) {
    report_file << run::make_report(j, r, m).dump(2) << '\n';
    report_file.close();
    if (!report_file) {
      fmt::print(stderr, "cpstep run: writing {} failed\n", o.report);
      rc = kExitFault;
    }
  }
  std::string plot_error;
  if (!o.plots.empty()) plot_error = run::write_plots(o.plots, j, meter, m);

  print_plan_summary(j);
  if (r.pins_observed) {
    fmt::print("job time   {:.6f} s = {} cycles from START to the last move (planned {:.6f} s)\n", m.job_time_s,
               m.job_time_cycles, j.planned.stats.duration_s);
    if (r.feed_scaled)
      fmt::print("timing     not compared with the plan: the feed override or hold scaled the card's time\n");
    else
      fmt::print("timing     max {:.1f} cycles ({:.3f} us) from the planner's ideal times, at move {}; "
                 "{} moves off their {} times\n",
                 m.max_timing_error_cycles, m.max_timing_error_cycles / j.clock_hz() * 1e6,
                 m.max_timing_error_move, m.moves_off_chunk_time, j.caps.ptimer ? "phase-timer" : "chunk");
    for (const run::FeedApplied& f : r.feed)
      fmt::print("feed       {} taken at {:.6f} s from START{}\n", f.what, f.taken_s,
                 f.event.kind == run::FeedEvent::Kind::toggle ? " (SIGUSR1)"
                 : f.event.at_s > 0 ? fmt::format(" (asked for {:.6f} s)", f.event.at_s) : "");
    fmt::print("checked    position_o at {} of {} card segment ends, {} off the plan\n", r.checked_segments,
               j.checkpoint_count, r.position_mismatches);
    if (m.curve.positions)
      fmt::print("curves     stepped path vs {} NURBS curve{}: max {:.5f} mm, rms {:.5f} mm over {} positions "
                 "(worst at X{:.4f} Y{:.4f}, line {})\n",
                 m.curve.curves, m.curve.curves == 1 ? "" : "s", m.curve.max_mm, m.curve.rms_mm, m.curve.positions,
                 m.curve.worst_x_mm, m.curve.worst_y_mm, m.curve.worst_loc.line);
  } else {
    fmt::print("card       {} moves, {} segments done (the card's counters over the job)\n", r.moves_done,
               r.segments_done);
  }
  if (j.machine.card.feed) {
    const plan::FeedRamp& fr = j.machine.feed.ramp;
    fmt::print("feed ramp  a tick every {} cycles, tau {:.4f} s: for a change of {:g} |ds/dt| <= {:.3f}/s, "
               "|d2s/dt2| <= {:.2f}/s^2; a hold from 100 % stands after {:.3f} s{}\n",
               fr.tick, fr.tau_s, fr.span, fr.rate_per_s(), fr.accel_per_s2(), fr.hold_s(),
               j.feed_ramp_note.empty() ? std::string() : "; " + j.feed_ramp_note);
  }
  fmt::print("stretches  {}\n", r.stretch_count);
  if (r.pins_observed)
    fmt::print("simulated  {} card cycles in {:.2f} s ({:.2f} M cycles/s, {}{})\n", r.sim_cycles, wall_s,
               wall_s > 0 ? double(r.sim_cycles) / wall_s / 1e6 : 0.0,
               r.engine == run::Engine::model      ? "the fast engine: the golden model, event to event"
               : r.engine == run::Engine::rtl      ? "the Verilated cp_card"
                                                   : "the fast engine and the Verilated cp_card in lockstep",
               r.skipped_cycles ? fmt::format("; {:.1f} % of the cycles skipped",
                                              100.0 * double(r.skipped_cycles) / double(r.sim_cycles))
                                : "");
  else
    fmt::print("ran        {:.1f} s\n", wall_s);
  fmt::print("link       {}\n", link_line(r));
  if (r.pins_observed && m.klipper)
    fmt::print("wire       {} command bytes; Klipper's queue_step for the job's steps: {} at 25 us, {} at 1 us; "
               "for the card's pin steps: {} at 25 us\n",
               4 * j.word_count(), klipper_text(m.klipper_25us), klipper_text(m.klipper_1us),
               klipper_text(m.klipper_pins_25us));
  else if (r.pins_observed)
    fmt::print("wire       {} command bytes (--klipper: Klipper's queue_step bytes for the same steps)\n",
               4 * j.word_count());
  if (r.pins_observed && r.torch_verdict.planned > 0) {
    const run::TorchVerdict& t = r.torch_verdict;
    fmt::print("torch      {} switches planned, {} on the pin{}; on {:.3f} s{}\n", t.planned, t.edges,
               !t.ok()          ? " (not as planned: see faults)"
               : r.feed_scaled ? ", in the planned order (the feed scaled the card's time: cycles not compared)"
                               : ", each at its move boundary", t.on_cycles / j.clock_hz(),
               t.min_pierce_cycles ? fmt::format("; shortest pierce (torch on to the first step) {:.3f} s",
                                                 *t.min_pierce_cycles / j.clock_hz())
                                   : "");
  }
  if (r.faults.empty()) {
    fmt::print("faults     none\n");
  } else {
    fmt::print("faults     {}\n", r.faults.size());
    for (const run::Fault& f : r.faults) fmt::print("  {} ({}): {}\n", f.name, f.code, f.message);
  }
  if (!r.pins_observed) fmt::print("start      {}\n", axis_positions(j, r.start_position));
  fmt::print("position   {}\n", axis_positions(j, r.position));
  if (r.pins_observed)
    for (int a = 0; a < plan::kAxes; ++a) {
      const plan::AxisConfig& ax = j.machine.axes[a];
      const run::AxisMeasure& am = m.axes[a];
      if (!ax.present) continue;
      fmt::print("peaks {}    v {:.2f}/{:g} mm/s, a {:.1f}/{:g} mm/s^2, j {:.0f}/{:g} mm/s^3: {}\n",
                 plan::kAxisLetters[a], am.peak.v, ax.max_velocity, am.peak.a, ax.max_accel, am.peak.j,
                 ax.max_jerk, am.within_limits ? "within limits" : "OVER LIMITS");
    }
  if (!o.vcd.empty()) fmt::print("vcd        {}\n", o.vcd);
  if (!o.report.empty()) fmt::print("report     {}\n", o.report);
  if (!o.plots.empty() && plot_error.empty())
    fmt::print("plots      {}\n", (fs::path(o.plots) / "{path,speed,accel,jerk}.png").string());
  std::fflush(stdout);
  for (const run::Fault& f : r.faults) fmt::print(stderr, "cpstep run: fault {} ({}): {}\n", f.name, f.code, f.message);
  // Over-limit kinematics are measured, not a card fault: a warning, exit unchanged.
  for (int a = 0; a < plan::kAxes && r.pins_observed; ++a) {
    const plan::AxisConfig& ax = j.machine.axes[a];
    const run::AxisMeasure& am = m.axes[a];
    if (!ax.present || am.within_limits) continue;
    const struct {
      const char* what;
      double peak, limit, tolerance;
      const char* unit;
    } q[] = {{"velocity", am.peak.v, ax.max_velocity, am.tolerance.v, "mm/s"},
             {"acceleration", am.peak.a, ax.max_accel, am.tolerance.a, "mm/s^2"},
             {"jerk", am.peak.j, ax.max_jerk, am.tolerance.j, "mm/s^3"}};
    for (const auto& e : q)
      if (e.peak > e.limit + e.tolerance)
        fmt::print(stderr, "cpstep run: warning: axis {}: realized {} {:.4g} {} exceeds the limit {:g} (+ {:.3g} "
                           "quantization)\n",
                   plan::kAxisLetters[a], e.what, e.peak, e.unit, e.limit, e.tolerance);
  }
  if (!plot_error.empty()) {
    fmt::print(stderr, "cpstep run: plots: {}\n", plot_error);
    rc = kExitFault;
  }
  return rc;
}

// --watchdog: a timeout the card's field holds at the card's clock, and at least
// four times the longest frame at `sck_hz` (a frame kicks the watchdog at its end),
// or a refusal.
bool watchdog_fits(const RunOptions& o, const run::CardJob& j, double sck_hz) {
  try {
    (void)card::watchdog_units(o.watchdog_s, uint32_t(j.clock_hz()));
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "cpstep run: --watchdog: {}; nothing was sent\n", e.what());
    return false;
  }
  const double frame_s = 8.0 * double(card::frame_bytes(j.caps.command_buffer_words())) / sck_hz;
  if (o.watchdog_s > 0 && o.watchdog_s < 4 * frame_s) {
    fmt::print(stderr,
               "cpstep run: --watchdog {} s: the card's longest frame ({} words) takes {:.6f} s at {:.0f} Hz; "
               "the watchdog needs at least four times that, {:.6f} s; nothing was sent\n",
               o.watchdog_s, j.caps.command_buffer_words(), frame_s, sck_hz, 4 * frame_s);
    return false;
  }
  return true;
}

// SIGUSR1: a HOLD, or a RESUME when held (cards with feed hold, docs/HOST.md).
volatile std::sig_atomic_t g_feed_toggles = 0;
void on_feed_toggle(int) { g_feed_toggles = g_feed_toggles + 1; }

// --override and --feed against the card and the machine file; SIGUSR1 on a card
// with feed hold. false: refused (said why), nothing sent.
template <class Options>
bool feed_options(const RunOptions& o, const run::CardJob& j, Options& so) {
  const double max_pct = j.machine.feed.max_override * 100;
  std::vector<run::FeedEvent> events;
  try {
    events = run::parse_feed_events(o.feed);
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "cpstep run: {}; nothing was sent\n", e.what());
    return false;
  }
  const bool asked = o.override_pct != 100 || !events.empty();
  if (asked && !j.caps.feed) {
    fmt::print(stderr, "cpstep run: --override/--feed: the card, {}, has no feed hold or override (a board "
               "with it: --board hx8k); nothing was sent\n", card::card_name(j.caps));
    return false;
  }
  const auto over = [&](double pct) {
    if (pct <= max_pct) return false;
    fmt::print(stderr, "cpstep run: an override of {} % is above the machine's {} % ({}: feed.max_override_pct); "
               "nothing was sent\n", pct, max_pct, o.machine);
    return true;
  };
  if (over(o.override_pct)) return false;
  for (const run::FeedEvent& e : events)
    if (e.kind == run::FeedEvent::Kind::override_pct && over(e.pct)) return false;
  so.override_pct = o.override_pct;
  so.feed = std::move(events);
  if (j.caps.feed) {
    std::signal(SIGUSR1, on_feed_toggle);
    so.feed_toggle = [seen = 0]() mutable {
      if (seen == g_feed_toggles) return false;
      ++seen;
      return true;
    };
  }
  return true;
}

int run_sim_transport(const RunOptions& o) {
  // The simulated card of the board, asked what it is, as a real one is.
  const std::string board = o.board.empty() ? std::string(builds::kDefaultBoard) : o.board;
  if (!card::board_caps(board)) {
    fmt::print(stderr, "cpstep run: --board {}: no such board (boards: {})\n", board, card::board_names());
    return kExitRefused;
  }
  const std::optional<run::Engine> engine = run::parse_engine(o.engine);
  if (!engine) {
    fmt::print(stderr, "cpstep run: --engine {}: no such engine (model, rtl, lockstep)\n", o.engine);
    return kExitRefused;
  }
  if (!o.fst.empty() && *engine == run::Engine::model) {
    fmt::print(stderr, "cpstep run: --fst traces the Verilated card: it needs --engine rtl or lockstep\n");
    return kExitRefused;
  }
  ContourRun contours(o);  // --state, --resume, --stop-after-contours
  if (const auto rc = contours.open()) return *rc;
  // Streamed: the words made again as they are sent (memory bounded by the job's segments).
  auto job = prepare(o.job, o.machine, run::connect_sim(board, *engine), {}, &contours, true);
  if (!job) return contours.nothing_left() ? 0 : kExitRefused;
  if (job->caps.feed) run::fit_feed_ramp(*job);  // the card's feed ramp, fitted to the job's fastest point
  const run::CardJob& j = *job;
  if (!watchdog_fits(o, j, j.clock_hz() / o.sck_div)) return kExitRefused;
  run::SimRunOptions so;
  if (!feed_options(o, j, so)) return kExitRefused;
  std::ofstream report_file;
  if (const int rc = open_outputs(o, report_file)) return rc;
  Progress progress(!o.no_progress);
  so.watchdog_s = o.watchdog_s;
  so.vcd = o.vcd;
  so.max_cycles = o.max_cycles;
  so.sck_div = o.sck_div;
  so.board = board;
  so.engine = *engine;
  so.fst = o.fst;
  so.progress = [&progress](uint64_t done, uint64_t total) { progress.update(done, total); };
  // The run measured as it goes: nothing kept per move (docs/SIM.md "Memory").
  run::RunMeter meter(j, o.klipper);
  so.meter = &meter;
  so.record_pins = false;
  const auto began = std::chrono::steady_clock::now();
  const run::CardRun r = contours.run_sim(j, so);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  progress.clear();
  return contours.finish(r, print_run(o, j, r, meter, wall_s, report_file));
}

int run_spidev_transport(const RunOptions& o) {
  // Connect at the rate asked for, or at a rate every card takes (its clock is
  // not known yet), read what the card is, plan for it, then run at the rate.
  const std::string device = o.device.empty() ? "/dev/spidev0.0" : o.device;
  ContourRun contours(o);  // --state, --resume: the state is read before the device is opened
  if (const auto rc = contours.open()) return *rc;
  std::unique_ptr<card::SpidevLink> link;
  std::optional<card::CardCaps> caps;
  plan::PerAxis<int64_t> at{};  // the card's position counters: the job is planned from there
  try {
    link = std::make_unique<card::SpidevLink>(device, uint32_t(o.spi_hz ? o.spi_hz : kConnectSpiHz));
    card::ClientOptions co;
    co.axes = plan::kAxes;
    card::CardClient client(*link, co);
    const card::Reply first = client.poll();
    for (int a = 0; a < plan::kAxes && size_t(a) < first.positions.size(); ++a) at[a] = first.positions[size_t(a)];
    caps = card::read_caps(client);
  } catch (const std::runtime_error& e) {
    fmt::print(stderr, "cpstep run: {}; nothing was sent\n", e.what());
    return kExitRefused;
  }
  if (!contours.card_matches(at)) return kExitRefused;
  auto job = prepare(o.job, o.machine, *caps, at, &contours, true);
  if (!job) return contours.nothing_left() ? 0 : kExitRefused;
  if (job->caps.feed) run::fit_feed_ramp(*job);  // the card's feed ramp, fitted to the job's fastest point
  const run::CardJob& j = *job;
  const uint64_t limit = uint64_t(j.clock_hz() / 8);
  const uint64_t hz = o.spi_hz ? o.spi_hz : limit;
  if (hz > limit) {
    fmt::print(stderr, "cpstep run: --spi-hz {} exceeds the card's limit clk/8 = {} Hz (docs/PROTOCOL.md)\n", hz,
               limit);
    return kExitRefused;
  }
  if (!watchdog_fits(o, j, double(hz))) return kExitRefused;
  run::LinkRunOptions lo;
  if (!feed_options(o, j, lo)) return kExitRefused;
  std::ofstream report_file;
  if (const int rc = open_outputs(o, report_file)) return rc;
  try {
    if (!o.spi_hz) link = std::make_unique<card::SpidevLink>(device, uint32_t(hz));
  } catch (const card::LinkError& e) {
    fmt::print(stderr, "cpstep run: {}\n", e.what());
    report_file.close();
    if (!o.report.empty()) fs::remove(o.report);
    return kExitRefused;
  }
  Progress progress(!o.no_progress);
  lo.sck_hz = double(hz);
  lo.ack_estop = o.ack_estop;
  lo.watchdog_s = o.watchdog_s;
  // Frames stay within spidev's transfer limit.
  lo.client.max_frame_words = (card::kSpidevMaxTransfer - card::frame_bytes(0)) / 4;
  lo.progress = [&progress](uint64_t done, uint64_t total) { progress.update(done, total); };
  const auto began = std::chrono::steady_clock::now();
  run::CardRun r;
  try {
    r = run::run_on_link(j, *link, lo);
  } catch (const card::LinkError& e) {
    progress.clear();
    fmt::print(stderr, "cpstep run: {}\n", e.what());
    return kExitFault;
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  progress.clear();
  run::RunMeter meter(j, false);  // a real card's pins are not observed: the counts only
  return contours.finish(r, print_run(o, j, r, meter, wall_s, report_file));
}

}  // namespace

CLI::App* add_run_command(CLI::App& app, RunOptions& o) {
  auto* c = app.add_subcommand("run", "Plan a G-code job and run it on the card (docs/HOST.md)");
  c->add_option("JOB", o.job, "the G-code file")->required();
  c->add_option("--machine", o.machine, "the machine file (TOML, docs/PLANNING.md)")->required();
  c->add_option("--transport", o.transport,
                "sim: the Verilated card through its SPI pins; spidev: a card on --device; file: write the "
                "command words to --out")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "spidev", "file"}));
  c->add_option("--board", o.board,
                "sim: the board whose card build is simulated; file: the board planned for (rtl/builds.json: " +
                    card::board_names() + "; default " + std::string(builds::kDefaultBoard) +
                    "). spidev asks the card.");
  c->add_option("--out", o.out, "file transport: the command stream (little-endian 32-bit words)");
  c->add_option("--engine", o.engine,
                "sim: what simulates the card: model (the golden model, event to event: fast), rtl (the "
                "Verilated card, every cycle) or lockstep (both, every output compared every cycle); "
                "docs/SIM.md")
      ->capture_default_str();
  c->add_option("--fst", o.fst, "sim, --engine rtl or lockstep: an FST waveform of every signal of the RTL card");
  c->add_option("--vcd", o.vcd, "sim: write the STEP/DIR pins to this VCD file");
  c->add_option("--report", o.report, "sim: write the JSON report here");
  c->add_option("--plots", o.plots, "sim: write path/speed/accel/jerk PNGs (gnuplot) into this directory");
  c->add_option("--max-cycles", o.max_cycles, "sim: give up after this many clock cycles (default: twice the "
                                              "planned time plus 10^7)");
  c->add_option("--sck-div", o.sck_div, "sim: clock cycles per SCK period (the card needs 8 or more)")
      ->capture_default_str()
      ->check(CLI::Range(8u, 1'000'000u));
  c->add_option("--device", o.device, "spidev: the SPI device (default /dev/spidev0.0)");
  c->add_option("--spi-hz", o.spi_hz, "spidev: the SCK rate in Hz (default and limit: the card's clock / 8)")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000)));
  c->add_flag("--no-progress", o.no_progress, "no progress display on stderr");
  c->add_flag("--klipper", o.klipper,
              "also count the bytes Klipper's queue_step messages take for the job's steps (the path's, at 25 "
              "and 1 us, and the card's pin steps, at 25 us): the wire comparison of docs/BENCHMARKS.md; costs "
              "about as much time as the simulation on jobs of short moves");
  c->add_flag("--ack-estop", o.ack_estop,
              "spidev: acknowledge an E-stop the card latched, its input released (without it such a card is "
              "refused: docs/CORE.md \"Faults\")");
  c->add_option("--watchdog", o.watchdog_s,
                "sim, spidev: the card's watchdog in seconds: no frame from the host for this long stops "
                "motion at a move boundary, drops ENABLE and latches WATCHDOG (code 19). The host sends a "
                "frame at least every quarter of it while the job runs and turns it off at the job's end; 0: "
                "off (docs/CORE.md \"Watchdog\")")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  c->add_option("--override", o.override_pct,
                "sim, spidev: the feed override in percent from the job's start (cards with feed hold: docs/CORE.md "
                "\"Feed hold and override\"); at most the machine file's feed.max_override_pct (default 100)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 200.0));
  c->add_option("--feed", o.feed,
                "sim, spidev: feed events at seconds from START (spidev: from the first reply that shows the "
                "card running), e.g. \"2.5:hold,4:resume,6:override=50\"; and while a job runs on a card with "
                "feed hold, SIGUSR1 toggles HOLD and RESUME");
  c->add_option("--state", o.state,
                "sim, spidev: after the run write its state here (JSON: contours completed, the card's "
                "position; docs/PLASMA.md \"Resume\")");
  c->add_option("--resume", o.resume,
                "sim, spidev: continue the run this state file records, from the next contour with a fresh "
                "pierce");
  c->add_option("--stop-after-contours", o.stop_after_contours,
                "sim: end the run after this contour of the job (its M5), as an operator stops between cuts")
      ->check(CLI::Range(size_t(1), size_t(1) << 40));
  return c;
}

CLI::App* add_plan_command(CLI::App& app, PlanOptions& o) {
  auto* c = app.add_subcommand("plan", "Plan a G-code job for the card and write its command stream");
  c->add_option("JOB", o.job, "the G-code file")->required();
  c->add_option("--machine", o.machine, "the machine file (TOML, docs/PLANNING.md)")->required();
  c->add_option("-o,--out", o.out, "write the command words (little-endian 32-bit) here");
  c->add_option("--board", o.board, "the board planned for (rtl/builds.json: " + card::board_names() +
                                        "; default " + std::string(builds::kDefaultBoard) + ")");
  return c;
}

namespace {

// A job with G38 moves (docs/HOST.md "Probing"): run block by block to each probe on
// the simulated card, the program going on from where each probe stopped.
int run_probing_job(const RunOptions& o) {
  if (o.transport != "sim" || !o.vcd.empty() || !o.report.empty() || !o.plots.empty() || !o.state.empty() ||
      !o.resume.empty() || o.stop_after_contours > 0 || o.override_pct != 100 || !o.feed.empty() || !o.fst.empty()) {
    fmt::print(stderr, "cpstep run: {}: a job that probes (G38) runs on --transport sim without --vcd, --report, "
                       "--plots, --fst, --state, --resume, --stop-after-contours, --override or --feed "
                       "(docs/HOST.md \"Probing\")\n",
               o.job);
    return kExitRefused;
  }
  const std::string board = o.board.empty() ? std::string("hx8k") : o.board;
  const run::SimProbeRun r = run::probe_job_on_sim(o.job, o.machine, board, o.engine);
  if (!r.error.empty()) {
    fmt::print(stderr, "cpstep run: {}\n", r.error);
    return kExitRefused;
  }
  for (const plan::Diagnostic& w : r.warnings) fmt::print(stderr, "{}\n", w.str());
  if (r.probes.empty() && !r.errors.empty()) {  // refused whole: nothing was sent
    for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
    return kExitRefused;
  }
  const plan::Machine& m = r.machine;
  const auto mm = [&](const plan::PerAxis<double>& p) {
    std::string t;
    for (int a = 0; a < plan::kAxes; ++a)
      if (m.axes[a].present) t += fmt::format("{}{}={:.4f}", t.empty() ? "" : " ", plan::kAxisLetters[a], p[a]);
    return t;
  };
  fmt::print("cpstep run: {} on the simulated {} card (engine {}): a probing job, run to each probe and on from "
             "where it stopped\n",
             o.job, board, o.engine);
  for (const run::ProbeEvent& e : r.probes)
    fmt::print("probe      {}:{} {}: {} at {} mm\n", o.job, e.loc.line, e.code, e.tripped ? "tripped" : "no trip",
               mm(e.at));
  plan::PerAxis<double> end{};
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present) end[a] = double(r.counts[a]) / m.axes[a].steps_per_mm;
  fmt::print("moves      {} move events, {:.3f} s simulated\n", r.moves, double(r.cycles) / m.card.clock_hz);
  fmt::print("position   {} mm (the card's counters; the pins {})\n", mm(end),
             r.pins == r.counts ? "equal to them" : "DIFFER");
  std::string faults;
  for (const plan::Diagnostic& e : r.errors) faults += (faults.empty() ? "" : "; ") + e.str();
  if (r.pins != r.counts) faults += std::string(faults.empty() ? "" : "; ") + "PIN_COUNT: the pins differ from the counters";
  fmt::print("faults     {}\n", faults.empty() ? "none" : faults);
  for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
  return faults.empty() ? 0 : 1;
}

}  // namespace

int run_job(const RunOptions& o) {
  // A job that probes runs its own way (docs/HOST.md "Probing").
  if (run::job_probes(o.job)) return run_probing_job(o);
  if (o.transport == "file") {
    if (o.out.empty()) {
      fmt::print(stderr, "cpstep run: --transport file needs --out FILE\n");
      return kExitRefused;
    }
    if (!o.vcd.empty() || !o.report.empty() || !o.plots.empty()) {
      fmt::print(stderr, "cpstep run: --vcd, --report and --plots need --transport sim (a file transport "
                         "runs nothing to measure)\n");
      return kExitRefused;
    }
  } else if (!o.out.empty()) {
    fmt::print(stderr, "cpstep run: --out is for --transport file\n");
    return kExitRefused;
  }
  if (o.transport == "spidev" && (!o.vcd.empty() || !o.plots.empty())) {
    fmt::print(stderr, "cpstep run: --vcd and --plots need --transport sim (a real card's pins are not seen; "
                       "--report works)\n");
    return kExitRefused;
  }
  if (o.transport != "sim" && o.sck_div != 8) {
    fmt::print(stderr, "cpstep run: --sck-div is for --transport sim (spidev: --spi-hz)\n");
    return kExitRefused;
  }
  if (o.transport != "spidev" && (o.spi_hz != 0 || !o.device.empty())) {
    fmt::print(stderr, "cpstep run: --device and --spi-hz are for --transport spidev\n");
    return kExitRefused;
  }
  if (o.transport == "spidev" && !o.board.empty()) {
    fmt::print(stderr, "cpstep run: --board is for --transport sim and file (spidev asks the card what it is)\n");
    return kExitRefused;
  }
  if (o.transport == "file" && (!o.state.empty() || !o.resume.empty())) {
    fmt::print(stderr, "cpstep run: --state and --resume need a card: --transport sim or spidev\n");
    return kExitRefused;
  }
  if (o.transport != "sim" && o.stop_after_contours > 0) {
    fmt::print(stderr, "cpstep run: --stop-after-contours is for --transport sim (on a real card, stop between "
                       "contours with its controls; --state records where)\n");
    return kExitRefused;
  }
  if (o.transport == "file" && (o.override_pct != 100 || !o.feed.empty())) {
    fmt::print(stderr, "cpstep run: --override and --feed need a card: --transport sim or spidev\n");
    return kExitRefused;
  }
  if (o.transport == "spidev") return run_spidev_transport(o);
  if (o.transport == "sim") return run_sim_transport(o);
  const auto caps = board_caps("run", o.board);
  if (!caps) return kExitRefused;
  const auto j = prepare(o.job, o.machine, *caps);
  if (!j) return kExitRefused;
  return run_file_transport(o, *j);
}

int plan_only(const PlanOptions& o) {
  const auto caps = board_caps("plan", o.board);
  if (!caps) return kExitRefused;
  const auto j = prepare(o.job, o.machine, *caps);
  if (!j) return kExitRefused;
  if (!o.out.empty() && !run::write_words(o.out, j->words)) {
    fmt::print(stderr, "cpstep plan: cannot write {}\n", o.out);
    return kExitFault;
  }
  print_plan_summary(*j);
  fmt::print("planned    {:.6f} s\n", j->planned.stats.duration_s);
  // The plan's bytes beside Klipper's for the same steps (no pins here: the plan's).
  const std::vector<plan::StepperSteps> ks = run::klipper_path_steps(*j);
  fmt::print("wire       {} command bytes; Klipper's queue_step for the job's steps: {} at 25 us, {} at 1 us\n",
             4 * j->words.size(), klipper_text(plan::queue_step_cost(ks, 25e-6 * j->clock_hz())),
             klipper_text(plan::queue_step_cost(ks, 1e-6 * j->clock_hz())));
  if (!o.out.empty())
    fmt::print("wrote      {} command words ({} bytes, little-endian) to {}\n", j->words.size(),
               4 * j->words.size(), o.out);
  else
    fmt::print("words      {} command words\n", j->words.size());
  return 0;
}

}  // namespace cpstep::cli

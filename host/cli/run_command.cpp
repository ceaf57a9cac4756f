#include "cli/run_command.h"

#include <unistd.h>

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>

#include "run/card_job.h"
#include "run/measure.h"
#include "run/plots.h"
#include "run/report.h"
#include "run/sim_run.h"

namespace cpstep::cli {

namespace {

namespace fs = std::filesystem;

constexpr int kExitFault = 1;
constexpr int kExitRefused = 2;

void print_diagnostics(const plan::Result<run::CardJob>& r) {
  for (const plan::Diagnostic& w : r.warnings) {
    if (w.loc.line > 0)
      fmt::print(stderr, "{}:{}:{}: warning: {}\n", w.file, w.loc.line, w.loc.col, w.message);
    else
      fmt::print(stderr, "{}: warning: {}\n", w.file, w.message);
  }
  for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
}

// Plans the job; prints every diagnostic. nullopt when it is refused.
std::optional<run::CardJob> prepare(const std::string& job, const std::string& machine) {
  auto r = run::prepare_job(job, machine);
  print_diagnostics(r);
  if (!r.ok()) return std::nullopt;
  return std::move(*r.value);
}

void print_plan_summary(const run::CardJob& j) {
  const plan::PlanStats& s = j.planned.stats;
  const uint64_t chunks = j.wire_chunks();
  fmt::print("job        {}\n", j.job_file);
  fmt::print("machine    {} ({:.0f} Hz)\n", j.machine.file, j.clock_hz());
  fmt::print("segments   {} card segments ({} step segments)\n", j.wire.segments.size(), s.step_segments);
  fmt::print("moves      {}\n", j.moves());
  fmt::print("chunks     {}, {:.2f} moves per chunk\n", chunks,
             chunks ? double(j.moves()) / double(chunks) : 0.0);
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

int run_sim_transport(const RunOptions& o, const run::CardJob& j) {
  // Outputs that cannot be produced are refused before the (long) run.
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
  std::ofstream report_file;
  if (!o.report.empty()) {
    report_file.open(o.report, std::ios::trunc);
    if (!report_file) {
      fmt::print(stderr, "cpstep run: cannot write {}\n", o.report);
      return kExitRefused;
    }
  }
  Progress progress(!o.no_progress);
  run::SimRunOptions so;
  so.vcd = o.vcd;
  so.max_cycles = o.max_cycles;
  so.progress = [&progress](uint64_t done, uint64_t total) { progress.update(done, total); };
  const auto began = std::chrono::steady_clock::now();
  const run::CardRun r = run::run_on_sim(j, so);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  progress.clear();
  const run::RunMeasure m = run::measure_run(j, r);

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
  if (!o.plots.empty()) plot_error = run::write_plots(o.plots, j, r, m);

  print_plan_summary(j);
  fmt::print("job time   {:.6f} s = {} cycles from START to the last move (planned {:.6f} s)\n", m.job_time_s,
             m.job_time_cycles, j.planned.stats.duration_s);
  fmt::print("timing     max {:.1f} cycles ({:.3f} us) from the planner's ideal times, at move {}; "
             "{} moves off their chunk times\n",
             m.max_timing_error_cycles, m.max_timing_error_cycles / j.clock_hz() * 1e6,
             m.max_timing_error_move, m.moves_off_chunk_time);
  fmt::print("checked    position_o at {} of {} card segment ends, {} off the plan\n", r.checked_segments,
             j.checkpoints.size(), r.position_mismatches);
  fmt::print("stretches  {}\n", r.stretch_count);
  fmt::print("simulated  {} card cycles in {:.1f} s ({:.2f} M cycles/s, Verilated cp_core)\n", r.cycles, wall_s,
             wall_s > 0 ? double(r.cycles) / wall_s / 1e6 : 0.0);
  if (r.faults.empty()) {
    fmt::print("faults     none\n");
  } else {
    fmt::print("faults     {}\n", r.faults.size());
    for (const run::Fault& f : r.faults) fmt::print("  {} ({}): {}\n", f.name, f.code, f.message);
  }
  fmt::print("position   {}\n", axis_positions(j, r.position));
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
  for (int a = 0; a < plan::kAxes; ++a) {
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

}  // namespace

CLI::App* add_run_command(CLI::App& app, RunOptions& o) {
  auto* c = app.add_subcommand("run", "Plan a G-code job and run it on the card (docs/HOST.md)");
  c->add_option("JOB", o.job, "the G-code file")->required();
  c->add_option("--machine", o.machine, "the machine file (TOML, docs/PLANNING.md)")->required();
  c->add_option("--transport", o.transport, "sim: the Verilated card; file: write the command words to --out")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "file"}));
  c->add_option("--out", o.out, "file transport: the command stream (little-endian 32-bit words)");
  c->add_option("--vcd", o.vcd, "sim: write the STEP/DIR pins to this VCD file");
  c->add_option("--report", o.report, "sim: write the JSON report here");
  c->add_option("--plots", o.plots, "sim: write path/speed/accel/jerk PNGs (gnuplot) into this directory");
  c->add_option("--max-cycles", o.max_cycles, "sim: give up after this many clock cycles (default: twice the "
                                              "planned time plus 10^7)");
  c->add_flag("--no-progress", o.no_progress, "no progress display on stderr");
  return c;
}

CLI::App* add_plan_command(CLI::App& app, PlanOptions& o) {
  auto* c = app.add_subcommand("plan", "Plan a G-code job for the card and write its command stream");
  c->add_option("JOB", o.job, "the G-code file")->required();
  c->add_option("--machine", o.machine, "the machine file (TOML, docs/PLANNING.md)")->required();
  c->add_option("-o,--out", o.out, "write the command words (little-endian 32-bit) here");
  return c;
}

int run_job(const RunOptions& o) {
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
  const auto j = prepare(o.job, o.machine);
  if (!j) return kExitRefused;
  if (o.transport == "file") return run_file_transport(o, *j);
  return run_sim_transport(o, *j);
}

int plan_only(const PlanOptions& o) {
  const auto j = prepare(o.job, o.machine);
  if (!j) return kExitRefused;
  if (!o.out.empty() && !run::write_words(o.out, j->words)) {
    fmt::print(stderr, "cpstep plan: cannot write {}\n", o.out);
    return kExitFault;
  }
  print_plan_summary(*j);
  fmt::print("planned    {:.6f} s\n", j->planned.stats.duration_s);
  if (!o.out.empty())
    fmt::print("wrote      {} command words ({} bytes, little-endian) to {}\n", j->words.size(),
               4 * j->words.size(), o.out);
  else
    fmt::print("words      {} command words\n", j->words.size());
  return 0;
}

}  // namespace cpstep::cli

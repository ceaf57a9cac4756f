// SPDX-License-Identifier: MIT
#include "cli/interp_command.h"

#include <fmt/core.h>
#include <fmt/os.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "plan/gcode.h"
#include "plan/interp.h"
#include "plan/machine.h"
#include "plan/nurbs.h"

namespace cpstep::cli {

namespace {

constexpr int kExitRefused = 2;

template <class T>
bool refused(const plan::Result<T>& r) {
  for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
  return !r.ok();
}

// The figures of one method over every NURBS block of the job (worst of each).
struct Figures {
  plan::InterpMethod method{};
  double fluct = 0, fluct_all = 0, fluct_cruise = 0, chord = 0, lag = 0;
  std::size_t samples = 0;
  std::vector<std::vector<plan::InterpSample>> per_block;
};

std::string num(double v) { return fmt::format("{:.6g}", v); }

// The samples as a G-code program of G1 lines (one card line segment each);
// the job's other blocks as they were (XY arcs with I J).
bool write_ngc(const std::string& path, const plan::Job& job, const Figures& f, double period_ms) {
  std::string out = fmt::format("(cpstep interp, {}: every NURBS block sampled every {:g} ms, one G1 line a sample)\n",
                                plan::method_name(f.method), period_ms);
  out += "G21 G90 G17\n";
  std::size_t nb = 0;
  bool first = true;
  for (const plan::MotionBlock& b : job.blocks) {
    if (first) {
      out += fmt::format("G0 X{:.6f} Y{:.6f} Z{:.6f}\n", b.start[0], b.start[1], b.start[2]);
      first = false;
    }
    const double fmin = b.feed * 60;
    switch (b.kind) {
      case plan::MotionKind::rapid:
        out += fmt::format("G0 X{:.6f} Y{:.6f} Z{:.6f}\n", b.end[0], b.end[1], b.end[2]);
        break;
      case plan::MotionKind::linear:
        out += fmt::format("G1 X{:.6f} Y{:.6f} Z{:.6f} F{:.6g}\n", b.end[0], b.end[1], b.end[2], fmin);
        break;
      case plan::MotionKind::arc_cw:
      case plan::MotionKind::arc_ccw:
        if (b.plane != plan::Plane::xy) {
          fmt::print(stderr, "cpstep interp: --ngc: arcs outside the XY plane are not written\n");
          return false;
        }
        out += fmt::format("G{} X{:.6f} Y{:.6f} Z{:.6f} I{:.6f} J{:.6f} F{:.6g}\n",
                           b.kind == plan::MotionKind::arc_cw ? 2 : 3, b.end[0], b.end[1], b.end[2],
                           b.center_x - b.start[0], b.center_y - b.start[1], fmin);
        break;
      case plan::MotionKind::dwell:
        if (b.dwell_s > 0) out += fmt::format("G4 P{:.6g}\n", b.dwell_s);
        break;
      case plan::MotionKind::nurbs: {
        const auto& samples = f.per_block[nb++];
        out += fmt::format("F{:.6g}\n", fmin);
        for (std::size_t i = 1; i < samples.size(); ++i) {
          const Eigen::Vector3d p = i + 1 == samples.size() ? Eigen::Vector3d(b.end[0], b.end[1], b.end[2])
                                                            : b.curve->point(samples[i].u);
          out += fmt::format("G1 X{:.6f} Y{:.6f}\n", p[0], p[1]);
        }
        break;
      }
    }
  }
  out += "M2\n";
  try {
    auto file = fmt::output_file(path);
    file.print("{}", out);
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}: cannot write: {}\n", path, e.what());
    return false;
  }
  return true;
}

}  // namespace

CLI::App* add_interp_command(CLI::App& app, InterpCliOptions& o) {
  auto* c = app.add_subcommand("interp",
                               "Interpolate a job's NURBS blocks (G5, G5.1, G5.2/G5.3) at a fixed period with seed "
                               "002's parameter updates and print the worst feed fluctuation and chord error "
                               "(docs/CURVES.md)");
  c->add_option("FILE", o.job, "the G-code job")->required();
  c->add_option("--machine", o.machine, "the machine file (its X/Y limits give the S-curve's A and J)")->required();
  c->add_option("--method", o.method, "taylor1, taylor2 or milne (default: all three)")
      ->check(CLI::IsMember({"taylor1", "taylor2", "milne"}));
  c->add_option("--period-ms", o.period_ms, "the interpolation period T in ms")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 1000.0));
  c->add_flag("--json", o.json, "print a JSON object instead of a table");
  c->add_option("--ngc", o.ngc,
                "write the samples (of --method, else milne) as a G1 program: one card line segment each");
  return c;
}

int run_interp(const InterpCliOptions& o) {
  auto machine = plan::load_machine(o.machine);
  if (refused(machine)) return kExitRefused;
  const plan::Machine& m = *machine;
  auto job = plan::load_gcode(o.job, plan::gcode_options(m));
  for (const plan::Diagnostic& w : job.warnings) fmt::print(stderr, "{}: warning: {}\n", w.file, w.message);
  if (refused(job)) return kExitRefused;
  std::vector<const plan::MotionBlock*> curves;
  for (const auto& b : job->blocks)
    if (b.kind == plan::MotionKind::nurbs) curves.push_back(&b);
  if (curves.empty()) {
    fmt::print(stderr, "{}: no NURBS blocks (G5, G5.1, G5.2 ... G5.3) to interpolate\n", o.job);
    return kExitRefused;
  }
  // The S-curve's limits along the path: the tightest of the X and Y axes
  // (a curve in the XY plane may point any way).
  double vmax = HUGE_VAL, amax = HUGE_VAL, jmax = HUGE_VAL;
  for (std::size_t a = 0; a < 2; ++a) {
    const auto& ax = m.axes[a];
    if (!ax.present) continue;
    vmax = std::min(vmax, ax.max_velocity);
    amax = std::min(amax, ax.max_accel);
    jmax = std::min(jmax, ax.max_jerk);
  }
  std::vector<plan::InterpMethod> methods;
  if (o.method.empty()) {
    methods = {plan::InterpMethod::taylor1, plan::InterpMethod::taylor2, plan::InterpMethod::milne};
  } else {
    methods = {*plan::parse_method(o.method)};
  }
  double length = 0, duration = 0, v_peak = 0;
  std::vector<Figures> figs;
  for (plan::InterpMethod meth : methods) {
    Figures f;
    f.method = meth;
    length = duration = v_peak = 0;
    for (const plan::MotionBlock* b : curves) {
      plan::InterpOptions io;
      io.period_s = o.period_ms / 1000.0;
      io.method = meth;
      const plan::InterpLimits lim{std::min(b->feed, vmax), amax, jmax};
      const plan::InterpResult r = plan::interpolate(*b->curve, lim, io);
      f.fluct = std::max(f.fluct, r.feed_fluctuation_max);
      f.fluct_all = std::max(f.fluct_all, r.feed_fluctuation_all_max);
      f.fluct_cruise = std::max(f.fluct_cruise, r.feed_fluctuation_cruise_max);
      f.chord = std::max(f.chord, r.chord_error_max_mm);
      f.lag = std::max(f.lag, r.lag_max_mm);
      f.samples += r.samples.size() - 1;
      f.per_block.push_back(r.samples);
      length += r.length_mm;
      duration += r.duration_s;
      v_peak = std::max(v_peak, r.v_peak);
    }
    figs.push_back(std::move(f));
  }
  if (!o.ngc.empty()) {
    const Figures& f = figs.size() == 1 ? figs.front() : figs.back();  // milne when all three
    if (!write_ngc(o.ngc, *job, f, o.period_ms)) return kExitRefused;
  }
  if (o.json) {
    auto obj = [&](const Figures& f) {
      return fmt::format(
          "{{\"method\": \"{}\", \"feed_fluctuation_max\": {}, \"feed_fluctuation_all_max\": {}, "
          "\"feed_fluctuation_cruise_max\": {}, \"chord_error_max_mm\": {}, \"lag_max_mm\": {}, \"samples\": {}}}",
          plan::method_name(f.method), num(f.fluct), num(f.fluct_all), num(f.fluct_cruise), num(f.chord), num(f.lag),
          f.samples);
    };
    const std::string head = fmt::format(
        "\"file\": \"{}\", \"nurbs_blocks\": {}, \"period_ms\": {}, \"length_mm\": {}, \"duration_s\": {}, "
        "\"v_peak_mm_s\": {}, \"low_feed_fraction\": 0.1",
        o.job, curves.size(), num(o.period_ms), num(length), num(duration), num(v_peak));
    if (figs.size() == 1) {
      std::string body = obj(figs.front());
      body.pop_back();
      fmt::print("{}, {}}}\n", body, head);
    } else {
      std::string s = "{" + head;
      for (const Figures& f : figs) s += fmt::format(", \"{}\": {}", plan::method_name(f.method), obj(f));
      fmt::print("{}}}\n", s);
    }
    return 0;
  }
  fmt::print("{}: {} NURBS block{}, {:.4f} mm in {:.4f} s (S-curve peak {:.4g} mm/s, A {:g} mm/s^2, J {:g} mm/s^3), "
             "T = {:g} ms\n",
             o.job, curves.size(), curves.size() == 1 ? "" : "s", length, duration, v_peak, amax, jmax, o.period_ms);
  fmt::print("{:<8} {:>14} {:>14} {:>14} {:>14} {:>12} {:>8}\n", "method", "fluct(>=10%V)", "fluct(all)",
             "fluct(cruise)", "chord_err_mm", "lag_mm", "samples");
  for (const Figures& f : figs) {
    fmt::print("{:<8} {:>14.3e} {:>14.3e} {:>14.3e} {:>14.3e} {:>12.3e} {:>8}\n", plan::method_name(f.method), f.fluct,
               f.fluct_all, f.fluct_cruise, f.chord, f.lag, f.samples);
  }
  return 0;
}

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
#include "card/caps.h"
#include "cpstep/builds.h"
#include "cli/check_command.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <fstream>

#include "check/check.h"
#include "check/pin_map.h"
#include "check/vcd.h"
#include "run/card_job.h"

namespace cpstep::cli {

namespace {

constexpr int kExitFindings = 1;
constexpr int kExitRefused = 2;

// Every error of a refused input on stderr, one a line; nonzero when refused.
template <class T>
bool refused(const plan::Result<T>& r) {
  for (const plan::Diagnostic& e : r.errors) fmt::print(stderr, "{}\n", e.str());
  return !r.ok();
}

}  // namespace

CLI::App* add_check_command(CLI::App& app, CheckOptions& o) {
  auto* c = app.add_subcommand(
      "check", "Check a STEP/DIR trace (VCD) of any device against cpstep's plan of the job (docs/VALIDATING.md)");
  c->add_option("--vcd", o.vcd, "the trace: a VCD from a simulation or a logic analyzer")->required();
  c->add_option("--job", o.job, "the G-code job the device ran")->required();
  c->add_option("--machine", o.machine, "the machine file it was planned for")->required();
  c->add_option("--board", o.board,
                "plan for this card build (rtl/builds.json: " + card::board_names() + "; default " +
                    std::string(builds::kDefaultBoard) + "): its clock is the plan's time base");
  c->add_option("--map", o.map, "a pin map (TOML): signal names, polarity, time base");
  c->add_option("--json", o.json, "write the verdict with every finding to this JSON file");
  c->add_option("--time-tol-cycles", o.time_tol_cycles,
                fmt::format("how far a move event may be from its planned time, card cycles, beyond the trace's "
                            "resolution (default {:g})",
                            check::kDefaultTimeTolCycles))
      ->check(CLI::NonNegativeNumber);
  c->add_option("--skew-cycles", o.skew_cycles,
                "STEP edges of several axes this close after a move event's first edge belong to it, card cycles "
                "(default: a quarter of the shortest planned interval)")
      ->check(CLI::NonNegativeNumber);
  return c;
}

int run_check(const CheckOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string board = o.board.empty() ? std::string(builds::kDefaultBoard) : o.board;
  const auto caps = card::board_caps(board);
  if (!caps) {
    fmt::print(stderr, "cpstep check: --board {}: no such board (boards: {})\n", board, card::board_names());
    return kExitRefused;
  }
  auto job = run::prepare_job(o.job, o.machine, *caps);
  for (const plan::Diagnostic& w : job.warnings) {
    // A warning's text goes after its position, as `cpstep run` prints it.
    plan::Diagnostic d = w;
    d.message = "warning: " + d.message;
    fmt::print(stderr, "{}\n", d.str());
  }
  if (refused(job)) return kExitRefused;
  check::PinMap map = check::default_pin_map();
  if (!o.map.empty()) {
    auto loaded = check::load_pin_map(o.map);
    if (refused(loaded)) return kExitRefused;
    map = std::move(*loaded.value);
  }
  const auto vcd = check::read_vcd(o.vcd);
  if (refused(vcd)) return kExitRefused;
  const auto pins = check::read_pins(*vcd, map, *job);
  if (refused(pins)) return kExitRefused;
  // Opened before the check, so that an unwritable path is refused like any bad input.
  std::ofstream json;
  if (!o.json.empty()) {
    json.open(o.json, std::ios::trunc);
    if (!json) {
      fmt::print(stderr, "{}: cannot write the verdict\n", o.json);
      return kExitRefused;
    }
  }

  check::Verdict v = check::check_trace(*job, *pins, {o.time_tol_cycles, o.skew_cycles});
  v.map = o.map;
  fmt::print("{}", check::verdict_summary(v));
  if (json.is_open()) {
    json << check::verdict_json(v).dump(2) << '\n';
    json.close();
    if (!json) {
      fmt::print(stderr, "{}: writing the verdict failed\n", o.json);
      return kExitRefused;
    }
    fmt::print("{:<10} {}\n", "json", o.json);
  }
  fmt::print("{:<10} {:.2f} s\n", "checked in",
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return v.conforms() ? 0 : kExitFindings;
}

}  // namespace cpstep::cli

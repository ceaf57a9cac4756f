// SPDX-License-Identifier: MIT
// cpstep — command-line front end.
//
//   cpstep moves U V [--k K] [--rep R] [--engine rtl|model|oracle] [--stats] [--table]
//   cpstep sim FILE [--board B] [--vcd OUT.vcd] [--max-cycles N] [--sck-div N]
//   cpstep run JOB.ngc --machine M.toml [--transport sim|spidev|file] [--out F] [--vcd F] [--report F]
//              [--plots DIR] [--sck-div N] [--device /dev/spidevB.C] [--spi-hz HZ]
//   cpstep plan JOB.ngc --machine M.toml [-o OUT.bin]
//   cpstep cam PART.dxf... --sheet SHEET.toml [-o JOB.ngc] [--svg PREVIEW.svg] [--run --machine M.toml]
//   cpstep conic --from X0 Y0 --to X1 Y1 (--center CX CY | --coeffs A B C D E F) [--ccw] [--engine rtl|model|oracle] [--json]
//   cpstep check --vcd TRACE.vcd --job JOB.ngc --machine M.toml [--map PINS.toml] [--json OUT.json]
//
// Exit codes: 0 success, 2 refused input (file:line:col or one line on stderr),
// 1 internal error (moves) or a run that ended with a fault (sim, docs/SIM.md;
// run, docs/HOST.md).
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <cstdint>
#include <iostream>
#include <optional>

#include "cli/accuracy_command.h"
#include "cli/cam_command.h"
#include "cli/check_command.h"
#include "cli/home_command.h"
#include "cli/interp_command.h"
#include "cli/conic_command.h"
#include "cli/run_command.h"
#include "cli/vectors_command.h"
#include "card/caps.h"
#include "cli/sim_command.h"
#include "cpstep/builds.h"
#include "model/oracle.h"
#include "run/card_job.h"
#include "sim/engine_configs.h"
#include "sim/engine_session.h"

namespace {

using namespace cpstep;

constexpr int kExitRefused = 2;

struct MovesOptions {
  uint64_t u = 0, v = 0, k = 0, rep = 1;
  std::string engine = "rtl";
  bool stats = false, table = false;
};

const char* engine_error_text(uint32_t code) {
  switch (model::EngineError(code)) {
    case model::EngineError::u_zero: return "u must be at least 1";
    case model::EngineError::v_gt_u: return "v must not exceed u";
    case model::EngineError::u_gt_umax: return "u exceeds the pattern capacity W";
    case model::EngineError::k_gt_kmax: return "k exceeds the largest doubling exponent KMAX";
    case model::EngineError::rep_zero: return "rep must be at least 1";
    case model::EngineError::pattern_gt_w: return "the pattern u/gcd(u,v) exceeds the capacity W";
    default: return "refused";
  }
}

void print_table(const std::vector<oracle::Iteration>& rows) {
  fmt::print("{:>6} {:>6}  {:<24} {}\n", "x", "y", "M1", "M2");
  for (const auto& r : rows) fmt::print("{:>6} {:>6}  {:<24} {}\n", r.x, r.y, r.m1, r.m2);
}

int run_moves(const MovesOptions& o) {
  using P = sim::EngineDefault;
  const auto params = P::model_params();
  sim::EngineRun run;
  std::optional<uint64_t> build_cycles;
  if (o.engine == "oracle") {
    // The oracle has no registers; it applies the card's limits so that every
    // engine refuses the same requests.
    uint32_t err = 0;
    if (o.u == 0) err = 1;
    else if (o.v > o.u) err = 2;
    else if (o.u > params.w) err = 3;
    else if (o.k > params.kmax) err = 4;
    else if (o.rep == 0) err = 5;
    if (err) {
      fmt::print(stderr, "cpstep moves: refused: {} (u={} v={} k={})\n", engine_error_text(err),
                 o.u, o.v, o.k);
      return kExitRefused;
    }
    std::string once = oracle::castle_pitteway(o.u << o.k, o.v << o.k, &run.iterations);
    for (uint64_t r = 0; r < o.rep; ++r) run.moves += once;
  } else {
    // Values wider than the ports are refused as the engine would refuse them.
    const uint64_t umax = (1ull << params.uw()) - 1;
    if (o.u > umax || o.v > umax || o.k > (1ull << params.kw()) - 1 || o.rep > 0xffff) {
      const uint32_t err = o.u > umax ? (o.v > o.u ? 2 : 3) : o.v > umax ? 2 : o.rep > 0xffff ? 5 : 4;
      fmt::print(stderr, "cpstep moves: refused: {} (u={} v={} k={})\n",
                 o.rep > 0xffff ? "rep exceeds 65535" : engine_error_text(err), o.u, o.v, o.k);
      return kExitRefused;
    }
    const sim::EngineRequest req{uint32_t(o.u), uint32_t(o.v), uint32_t(o.k), uint32_t(o.rep)};
    run = sim::run_fresh<P>(o.engine == "rtl", req);
    if (run.err_code) {
      fmt::print(stderr, "cpstep moves: refused: {} (u={} v={} k={})\n",
                 engine_error_text(run.err_code), o.u, o.v, o.k);
      return kExitRefused;
    }
    build_cycles = run.build_cycles();
  }
  if (o.table) print_table(run.iterations);
  fmt::print("{}\n", run.moves);
  if (o.stats)
    fmt::print("iterations={} build_cycles={}\n", run.iterations.size(),
               build_cycles ? std::to_string(*build_cycles) : "none");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cpstep: Castle-Pitteway FPGA step generator — model, simulated card and host"};
  app.require_subcommand(1);

  MovesOptions mo;
  auto* moves = app.add_subcommand("moves", "Print the move string of the segment (0,0)-(U,V)");
  moves->add_option("U", mo.u, "major-axis count u (1..W)")->required();
  moves->add_option("V", mo.v, "minor-axis count v (0..u)")->required();
  moves->add_option("--k", mo.k, "step-doubling exponent: u*2^k moves");
  moves->add_option("--rep", mo.rep, "replay the whole string this many times");
  moves->add_option("--engine", mo.engine, "rtl (Verilated), model (C++ golden model) or oracle")
      ->check(CLI::IsMember({"rtl", "model", "oracle"}));
  moves->add_flag("--stats", mo.stats, "second line: iterations=N build_cycles=M");
  moves->add_flag("--table", mo.table, "print the register table (x, y, M1, M2) first");

  cli::SimOptions so;
  auto* simc = app.add_subcommand("sim", "Run a script of raw segments and commands on the simulated card "
                                         "(docs/SIM.md)");
  simc->add_option("FILE", so.file, "the script")->required();
  simc->add_option("--vcd", so.vcd, "write the STEP/DIR pins (and estop) to this VCD file");
  simc->add_option("--max-cycles", so.max_cycles, "give up after this many clock cycles")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  simc->add_option("--board", so.board, "the board whose card build is simulated (rtl/builds.json: " +
                   card::board_names() + "; default " + std::string(builds::kDefaultBoard) + ")");
  simc->add_option("--clock-hz", so.clock_hz, "refused unless it is the board's clock (the VCD's time axis is the board's)")
      ->check(CLI::Range(uint64_t(1), uint64_t(1'000'000'000'000)));
  simc->add_option("--sck-div", so.sck_div, "clock cycles per SCK period of the SPI link (8 or more)")
      ->capture_default_str()
      ->check(CLI::Range(8u, 1'000'000u));
  simc->add_option("--engine", so.engine,
                   "rtl (the Verilated card, every cycle) or model (the fast engine: the golden model, event "
                   "to event; docs/SIM.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"rtl", "model"}));

  cli::RunOptions ro;
  auto* runc = cli::add_run_command(app, ro);
  cli::PlanOptions po;
  auto* planc = cli::add_plan_command(app, po);
  cli::AccuracyOptions ao;
  auto* accc = cli::add_accuracy_command(app, ao);
  cli::VectorsOptions vo;
  auto* vecc = cli::add_vectors_command(app, vo);
  cli::CheckOptions co;
  auto* chkc = cli::add_check_command(app, co);
  cli::CamOptions camo;
  auto* camc = cli::add_cam_command(app, camo);
  cli::InterpCliOptions io;
  auto* intc = cli::add_interp_command(app, io);
  cli::HomeOptions hmo;
  auto* homc = cli::add_home_command(app, hmo);

  cli::ConicOptions ko;
  auto* conc = app.add_subcommand("conic", "Step one arc or conic by combined steps (seed 001) on the conic "
                                           "engine and print its moves (docs/CONIC.md)");
  conc->add_option("--from", ko.from, "start point X0 Y0, in steps (decimals allowed)")->required();
  conc->add_option("--to", ko.to, "end point X1 Y1, in steps; equal to --from: a full turn")->required();
  conc->add_option("--center", ko.center, "circle centre CX CY, in steps, on the 1/16-step grid");
  conc->add_option("--coeffs", ko.coeffs, "any conic A x^2 + B xy + C y^2 + D x + E y + F = 0 (integers)");
  conc->add_flag("--ccw", ko.ccw, "counter-clockwise (circles; for --coeffs: G > 0 right of travel)");
  conc->add_option("--engine", ko.engine, "rtl (Verilated cp_conic), model (C++ twin) or oracle (nearest-node walk)")
      ->capture_default_str()
      ->check(CLI::IsMember({"rtl", "model", "oracle"}));
  conc->add_flag("--json", ko.json, "one JSON object: moves ([dx, dy] pairs), max_deviation (steps), ...");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : kExitRefused;
  }
  try {
    if (*moves) return run_moves(mo);
    if (*simc) return cli::run_sim(so);
    if (*runc) return cli::run_job(ro);
    if (*planc) return cli::plan_only(po);
    if (*accc) return cli::run_accuracy(ao);
    if (*vecc) return cli::run_vectors(vo);
    if (*chkc) return cli::run_check(co);
    if (*camc)
      return cli::run_cam(camo, [](const cli::CamOptions& c, const std::string& job) {
        cli::RunOptions r;  // the generated job runs exactly as `cpstep run JOB --machine M` would
        r.job = job;
        r.machine = c.machine;
        r.board = c.board;
        r.report = c.report;
        r.plots = c.plots;
        r.vcd = c.vcd;
        return cli::run_job(r);
      });
    if (*intc) return cli::run_interp(io);
    if (*homc) return cli::run_home(hmo);
    if (*conc) return cli::run_conic(ko);
  } catch (const cpstep::run::JobFileChanged& e) {
    // A streamed job's file written over while the job ran (docs/HOST.md "Streamed").
    fmt::print(stderr, "cpstep: {}; stopped\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "cpstep: internal error: {}\n", e.what());
    return 1;
  }
  return 0;
}

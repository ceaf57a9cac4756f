// SPDX-License-Identifier: MIT
#include "cli/accuracy_command.h"

#include <fmt/core.h>
#include <fmt/os.h>

#include <cmath>

#include "model/oracle.h"
#include "sim/engine_configs.h"
#include "sim/engine_session.h"

namespace cpstep::cli {

AccuracyStats accuracy_of(const std::string& moves, uint64_t u, uint64_t v, unsigned k,
                          bool base_grid) {
  AccuracyStats s;
  const uint64_t n = u << k, stride = base_grid ? (uint64_t(1) << k) : 1;
  uint64_t y = 0;
  for (uint64_t i = 0; i <= n; ++i) {
    if (i > 0 && moves.at(i - 1) == '1') ++y;
    if (i % stride != 0) continue;
    // |y - v i / u| / 2^k, from the exact integer |u y - v i|.
    const double e = std::fabs(double(int64_t(u * y) - int64_t(v * i))) / double(u) / double(1u << k);
    s.errors.push_back(e);
    s.at.push_back(i);
  }
  double sum = 0;
  for (double e : s.errors) {
    sum += e;
    s.max = std::max(s.max, e);
  }
  s.mean = sum / double(s.errors.size());
  double sq = 0;
  for (double e : s.errors) sq += (e - s.mean) * (e - s.mean);
  s.std = s.errors.size() > 1 ? std::sqrt(sq / double(s.errors.size() - 1)) : 0;
  return s;
}

CLI::App* add_accuracy_command(CLI::App& app, AccuracyOptions& o) {
  auto* c = app.add_subcommand(
      "accuracy", "Deviation of an engine's move stream from the ideal line (mean, std, max)");
  c->add_option("U", o.u, "major-axis count u (1..W)")->required();
  c->add_option("V", o.v, "minor-axis count v (0..u)")->required();
  c->add_option("--k", o.k, "step-doubling exponent: u*2^k fine steps");
  c->add_option("--engine", o.engine, "rtl (Verilated), model or oracle")
      ->check(CLI::IsMember({"rtl", "model", "oracle"}));
  c->add_option("--grid", o.grid, "fine: every fine step; base: every base step (2^k-th)")
      ->check(CLI::IsMember({"fine", "base"}));
  c->add_option("--curve", o.curve, "write the error at each sample to FILE (i error)");
  return c;
}

int run_accuracy(const AccuracyOptions& o) {
  using P = sim::EngineDefault;
  const auto params = P::model_params();
  if (o.u == 0 || o.v > o.u || o.u > params.w || o.k > params.kmax) {
    fmt::print(stderr, "cpstep accuracy: refused: need 1 <= u <= {}, v <= u, k <= {} (u={} v={} k={})\n",
               params.w, params.kmax, o.u, o.v, o.k);
    return 2;
  }
  std::string moves;
  const sim::EngineRequest req{uint32_t(o.u), uint32_t(o.v), uint32_t(o.k), 1};
  moves = o.engine == "oracle" ? oracle::doubled(o.u, o.v, unsigned(o.k))
                              : sim::run_fresh<P>(o.engine == "rtl", req).moves;
  const AccuracyStats s = accuracy_of(moves, o.u, o.v, unsigned(o.k), o.grid == "base");
  if (!o.curve.empty()) {
    auto f = fmt::output_file(o.curve);
    for (size_t i = 0; i < s.errors.size(); ++i)
      f.print("{} {:.6f}\n", double(s.at[i]) / double(1u << o.k), s.errors[i]);
  }
  fmt::print("mean={:.4f} std={:.4f} max={:.4f}\n", s.mean, s.std, s.max);
  return 0;
}

}  // namespace cpstep::cli

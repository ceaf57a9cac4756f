// SPDX-License-Identifier: MIT
// bench_engine — engine figures for docs/BENCHMARKS.md (run by scripts/bench).
// Cycle counts come from the Verilated RTL (deterministic); speeds are wall-clock.
#include <fmt/core.h>

#include <chrono>
#include <numeric>
#include <random>

#include "sim/engine_configs.h"
#include "sim/engine_session.h"

using namespace cpstep;
using P = sim::EngineDefault;

namespace {

sim::EngineRun run_rtl(sim::RtlDut<P>& dut, uint32_t u, uint32_t v, uint32_t k = 0) {
  return sim::run_request(dut, P::model_params().aw(), {u, v, k, 1});
}

template <class Dut>
double moves_per_second(Dut& dut, uint32_t u, uint32_t v, uint32_t k, uint64_t* moves_out) {
  const auto t0 = std::chrono::steady_clock::now();
  uint64_t moves = 0;
  double s = 0;
  do {
    moves += sim::run_request(dut, P::model_params().aw(), {u, v, k, 1}).moves.size();
    s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (s < 1.0);
  *moves_out = moves;
  return moves / s;
}

}  // namespace

int main() {
  sim::RtlDut<P> rtl;
  model::CpEngineIn reset{};
  reset.rst = true;
  rtl.step(reset);

  fmt::print("### Build cycles against the reduced length u/gcd (W = 1024)\n\n");
  fmt::print("Cycles from the request's handshake to the first move being valid "
             "(docs/ENGINE.md: (u/gcd - 2) + 3).\n\n");
  fmt::print("| family | u | v | u/gcd | loop iterations | build cycles | cycles per pattern bit |\n");
  fmt::print("|---|---:|---:|---:|---:|---:|---:|\n");
  const auto row = [&](const char* family, uint32_t u, uint32_t v) {
    const auto r = run_rtl(rtl, u, v);
    const uint32_t n = u / std::gcd(u, v);
    fmt::print("| {} | {} | {} | {} | {} | {} | {:.3f} |\n", family, u, v, n, r.iterations.size(),
               r.build_cycles(), double(r.build_cycles()) / n);
  };
  for (uint32_t u : {16u, 64u, 256u, 1024u}) row("v = 1 (most iterations)", u, 1);
  const uint32_t fib[] = {8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987};
  for (int i = 3; i + 1 < 11; i += 2) row("Fibonacci ratio", fib[i + 1], fib[i]);
  row("the paper's line", 51, 11);
  row("u = 2v (no iteration)", 1024, 512);
  row("common factor 8", 1024, 8 * 37);

  std::mt19937_64 rng(1);
  uint64_t sum_n = 0, sum_cycles = 0, worst_excess = 0;
  const int trials = 2000;
  for (int i = 0; i < trials; ++i) {
    const uint32_t u = std::uniform_int_distribution<uint32_t>(3, 1024)(rng);
    const uint32_t v = std::uniform_int_distribution<uint32_t>(1, u - 1)(rng);
    if (2 * v == u) continue;
    const auto r = run_rtl(rtl, u, v);
    const uint64_t n = u / std::gcd(u, v);
    sum_n += n;
    sum_cycles += r.build_cycles();
    worst_excess = std::max<uint64_t>(worst_excess, r.build_cycles() - n);
  }
  fmt::print("\nRandom (u, v), u uniform in 3..1024, {} requests: {:.4f} build cycles per pattern "
             "bit on average; build cycles - u/gcd is at most {}.\n\n",
             trials, double(sum_cycles) / sum_n, worst_excess);

  fmt::print("### Replay\n\n| request | moves | cycles first..last move | cycles per move |\n");
  fmt::print("|---|---:|---:|---:|\n");
  for (auto [u, v, k] : {std::tuple{51u, 11u, 0u}, {1024u, 633u, 0u}, {1024u, 1u, 4u}, {7u, 3u, 8u}}) {
    const auto r = run_rtl(rtl, u, v, k);
    const uint64_t span = r.last_move_cycle - r.first_move_cycle + 1;
    fmt::print("| ({}, {}, k={}) | {} | {} | {:.3f} |\n", u, v, k, r.moves.size(), span,
               double(span) / r.moves.size());
  }

  fmt::print("\n### Simulation speed (moves per second, wall clock, one core)\n\n");
  fmt::print("| engine | request | moves per second |\n|---|---|---:|\n");
  {
    sim::ModelDut<P> model;
    uint64_t n = 0;
    const double mps = moves_per_second(model, 1024, 633, 8, &n);
    fmt::print("| golden model (model/cp_engine.cpp) | (1024, 633, k=8) | {:.3g} |\n", mps);
    const double rps = moves_per_second(rtl, 1024, 633, 8, &n);
    fmt::print("| Verilated RTL (rtl/cp_engine.v) | (1024, 633, k=8) | {:.3g} |\n", rps);
  }
  return 0;
}

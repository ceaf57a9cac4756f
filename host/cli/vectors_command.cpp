// SPDX-License-Identifier: MIT
#include "cli/vectors_command.h"

#include <fmt/core.h>
#include <fmt/os.h>

#include <bit>
#include <filesystem>
#include <numeric>
#include <random>

#include "model/oracle.h"
#include "sim/engine_configs.h"
#include "sim/engine_session.h"

namespace cpstep::cli {
namespace {

// The move string the Verilated engine emits for (u, v, k); it must equal the
// oracle's closed form, or the vectors are not written.
std::string engine_moves(sim::RtlDut<sim::EngineDefault>& dut, uint32_t u, uint32_t v, uint32_t k) {
  const auto run = sim::run_request(dut, sim::EngineDefault::model_params().aw(), {u, v, k, 1});
  const std::string want = oracle::doubled(u, v, k);
  if (run.err_code != 0 || run.moves != want)
    throw std::runtime_error(fmt::format("engine and oracle disagree on ({}, {}, k={})", u, v, k));
  return run.moves;
}

}  // namespace

CLI::App* add_vectors_command(CLI::App& app, VectorsOptions& o) {
  auto* c = app.add_subcommand("vectors", "Write conformance vectors (docs/VALIDATING.md) into OUT_DIR");
  c->add_option("OUT_DIR", o.out_dir, "directory to write engine.vec and segments.vec into")->required();
  c->add_option("--seed", o.seed, "seed of the random segments");
  c->add_option("--random", o.random, "number of random 4-axis segments");
  return c;
}

int run_vectors(const VectorsOptions& o) {
  namespace fs = std::filesystem;
  fs::create_directories(o.out_dir);
  sim::RtlDut<sim::EngineDefault> dut;
  model::CpEngineIn reset{};
  reset.rst = true;
  dut.step(reset);

  // engine.vec: one (major, minor) pair per line.
  {
    auto f = fmt::output_file((fs::path(o.out_dir) / "engine.vec").string());
    f.print("# cpstep conformance vectors: the move string of the line (0,0)-(u,v) with its\n"
            "# steps doubled k times (u*2^k moves; 1 = diagonal, 0 = axial). SPEC section 1:\n"
            "# the minor position after move i (i = 1..u*2^k) is floor((2*v*i + u) / (2*u)),\n"
            "# Bresenham with ties rounded up. Taken from rtl/cp_engine.v's streams.\n"
            "# Format: u v k moves\n");
    size_t n = 0;
    const auto line = [&](uint32_t u, uint32_t v, uint32_t k) {
      f.print("{} {} {} {}\n", u, v, k, engine_moves(dut, u, v, k));
      ++n;
    };
    for (uint32_t u = 1; u <= 16; ++u)
      for (uint32_t v = 0; v <= u; ++v) line(u, v, 0);
    line(51, 11, 0);  // the seed paper's line
    line(51, 11, 1);
    line(102, 22, 0);
    for (uint32_t v : {1u, 2u, 511u, 512u, 633u, 1023u}) line(1024, v, 0);
    line(7, 3, 8);
    fmt::print("{}: {} engine vectors\n", (fs::path(o.out_dir) / "engine.vec").string(), n);
  }

  // segments.vec: 4-axis segments as a card executes them.
  {
    auto f = fmt::output_file((fs::path(o.out_dir) / "segments.vec").string());
    f.print("# cpstep conformance vectors: 4-axis segments (x y z a). The major axis is the\n"
            "# first of largest |d|; it steps at every move; axis j steps at move i when the\n"
            "# closed form floor((2*|d_j|*i + T) / (2*T)) advances (T = moves). Each axis lands\n"
            "# on d_j. Format: d_x d_y d_z d_a then one move string per axis (1 = STEP at\n"
            "# that move), then the positions after the segment.\n");
    std::mt19937_64 rng(o.seed);
    std::uniform_int_distribution<int64_t> mag(-300, 300);
    size_t n = 0;
    const auto seg = [&](std::array<int64_t, 4> d) {
      int64_t t = 0;
      uint64_t g = 0;
      for (int64_t x : d) {
        t = std::max<int64_t>(t, std::abs(x));
        g = std::gcd(g, uint64_t(std::abs(x)));
      }
      if (t == 0) return;
      const unsigned k = std::min(8u, unsigned(std::countr_zero(g)));
      f.print("{} {} {} {}", d[0], d[1], d[2], d[3]);
      for (int64_t x : d) {
        // Each axis's string from the engine the card gives it: (T >> k, |d| >> k, k).
        const std::string m = engine_moves(dut, uint32_t(t >> k), uint32_t(std::abs(x) >> k), k);
        f.print(" {}", m);
      }
      f.print(" -> {} {} {} {}\n", d[0], d[1], d[2], d[3]);
      ++n;
    };
    seg({51, 11, 0, 0});
    seg({-51, 11, -11, 51});
    seg({8, 8, 8, 8});
    seg({1, 0, 0, 0});
    seg({0, 0, 0, -1});
    seg({1000, 999, -1, 500});
    for (unsigned i = 0; i < o.random; ++i) seg({mag(rng), mag(rng), mag(rng), mag(rng)});
    fmt::print("{}: {} segment vectors\n", (fs::path(o.out_dir) / "segments.vec").string(), n);
  }
  return 0;
}

}  // namespace cpstep::cli

// SPDX-License-Identifier: MIT
#include "cli/vectors_command.h"

#include <fmt/core.h>
#include <fmt/os.h>

#include <bit>
#include <filesystem>
#include <numeric>
#include <random>

#include "cli/conic_command.h"
#include "model/cp_conic.h"
#include "model/cp_conic_serial.h"
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
  c->add_option("OUT_DIR", o.out_dir, "directory to write engine.vec, segments.vec and conic.vec into")->required();
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

  // conic.vec: circle walks by seed 001's combined steps (docs/CONIC.md), from the
  // Verilated conic engine, each equal to the card's walker rule (CONIC segments).
  {
    auto f = fmt::output_file((fs::path(o.out_dir) / "conic.vec").string());
    f.print("# cpstep conformance vectors: walks of the curve A x^2 + B xy + C y^2 + D x + E y + F = 0\n"
            "# (integers, step units) by seed 001's combined steps (docs/CONIC.md: the rule, the\n"
            "# quadrant flags, the ties), from node (x0, y0) to node (x1, y1) (a full turn when\n"
            "# equal), cw 1 = clockwise (G > 0 on the left of travel). Each move is one digit,\n"
            "# 3 (dx + 1) + (dy + 1): 0 = (-1,-1), 1 = (-1,0), 2 = (-1,+1), 3 = (0,-1), 5 = (0,+1),\n"
            "# 6 = (+1,-1), 7 = (+1,0), 8 = (+1,+1). Every node lies within half a step of a\n"
            "# circle of radius >= 1; the walk reaches (x1, y1) on its last move and on no other.\n"
            "# Taken from rtl/cp_conic.v's streams, each equal to the card walker's rule\n"
            "# (rtl/cp_conic_serial.v: model::CpConicSerial::rule at IW = 40).\n"
            "# Format: A B C D E F x0 y0 x1 y1 cw moves\n");
    size_t n = 0;
    const auto walk = [&](std::array<int64_t, 6> k, std::array<int64_t, 2> s, std::array<int64_t, 2> e, bool cw) {
      const ConicRun r = conic_rtl_moves(k, s, e, cw);
      if (r.err != 0 || r.moves.empty())
        throw std::runtime_error(fmt::format("the conic engine refused a vector (code {})", r.err));
      // The card's walker, from the same start, must make the same moves.
      const model::CpConic::Coeffs co{k[0], k[1], k[2], k[3], k[4], k[5]};
      model::CpConic::Node node = model::CpConic::at(co, s[0], s[1]);
      std::string digits;
      for (const auto& [dx, dy] : r.moves) {
        int wx = 0, wy = 0;
        model::CpConicSerial::rule(co, node, cw, 40, wx, wy);
        if (wx != dx || wy != dy) throw std::runtime_error("the conic engine and the card's walker rule disagree");
        node = model::CpConic::advance(co, node, dx, dy);
        digits += char('0' + 3 * (dx + 1) + (dy + 1));
      }
      f.print("{} {} {} {} {} {} {} {} {} {} {} {}\n", k[0], k[1], k[2], k[3], k[4], k[5], s[0], s[1], e[0], e[1],
              int(cw), digits);
      ++n;
    };
    // Circles about a node (radius r: x^2 + y^2 = r^2), a quarter from (r, 0) and a
    // full turn each way; about (1/2, 1/4) (scaled by 16: 16x^2 + 16y^2 - 16x - 8y + F).
    for (int64_t r : {1, 2, 3, 4, 5, 7, 8, 13, 16, 25, 64, 100, 1000}) {
      walk({1, 0, 1, 0, 0, -r * r}, {r, 0}, {0, r}, false);
      walk({1, 0, 1, 0, 0, -r * r}, {0, r}, {r, 0}, true);
      walk({1, 0, 1, 0, 0, -r * r}, {r, 0}, {r, 0}, false);
      walk({1, 0, 1, 0, 0, -r * r}, {r, 0}, {r, 0}, true);
    }
    for (int64_t r : {3, 10, 50}) {  // centre (1/2, 1/4), through (r, 0): F = -16 r^2 + 16 r
      const std::array<int64_t, 6> k{16, 0, 16, -16, -8, -16 * r * r + 16 * r};
      walk(k, {r, 0}, {r, 0}, false);
      walk(k, {r, 0}, {r, 0}, true);
    }
    // Seed 001's other conics: an ellipse (x^2 + 4 y^2 = 400) and a rotated one.
    walk({1, 0, 4, 0, 0, -400}, {20, 0}, {20, 0}, false);
    walk({5, 4, 5, 0, 0, -1125}, {15, 0}, {15, 0}, true);
    fmt::print("{}: {} conic vectors\n", (fs::path(o.out_dir) / "conic.vec").string(), n);
  }
  return 0;
}

}  // namespace cpstep::cli

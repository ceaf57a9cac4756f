// SPDX-License-Identifier: MIT
// bench_host — host planner figures for docs/BENCHMARKS.md (run by scripts/bench):
// G-code lines planned per second, moves per chunk in the card's chunk form at the
// machine's tolerance (with add2, and without for comparison), and the time of one
// 7-phase S-curve solve.
#include <fmt/core.h>

#include <chrono>
#include <fstream>
#include <random>
#include <sstream>

#include "card/job.h"
#include "cpstep/builds.h"
#include "plan/gcode.h"
#include "plan/pipeline.h"
#include "plan/profile.h"

using namespace cpstep;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

size_t count_lines(const std::string& path) {
  std::ifstream f(path);
  size_t n = 0;
  for (std::string line; std::getline(f, line);) ++n;
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string root = argc > 1 ? argv[1] : ".";
  plan::PlanOptions card_form;
  card_form.chunk_limits = card::chunk_limits();
  card_form.add2_from_machine = false;
  plan::PlanOptions no_add2 = card_form;  // the card's form before add2, for comparison
  no_add2.chunk_limits.enable_add2 = false;

  fmt::print("### Planning speed and chunks (card chunk form: 16-bit add and add2, increments of one sign)\n\n");
  fmt::print("Each job planned whole (parse, segments, reduction, lookahead, S-curves, move times,\n"
             "chunks) and encoded to command words, best of 3 runs. *Without add2*: moves per chunk\n"
             "of the same job planned with add2 disabled (the card's form before add2).\n\n");
  fmt::print("| machine | job | G-code lines | card segments | moves | chunks | moves per chunk | "
             "without add2 | chunk tolerance | planning time | lines per second |\n");
  fmt::print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  const std::pair<const char*, const char*> jobs[] = {
      {"seed002", "dense"}, {"seed002", "bracket"}, {"seed002", "plasma"}, {"router", "bracket"},
      {"plotter", "plasma"}, {"seed002", "tab"}};
  for (auto [mach, job] : jobs) {
    const std::string mpath = root + "/examples/machines/" + mach + ".toml";
    const std::string jpath = root + "/examples/jobs/" + job + ".ngc";
    auto m = plan::load_machine(mpath);
    if (!m.ok()) { fmt::print(stderr, "{}\n", plan::join(m.errors)); return 1; }
    {
      // Bound to the default board's card (rtl/builds.json), as `cpstep plan` does:
      // the example machine files leave the card's clock to the card.
      const builds::Build& b = *builds::find(builds::kDefaultBoard);
      const auto errs = plan::bind_card(*m.value, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw});
      if (!errs.empty()) { fmt::print(stderr, "{}\n", plan::join(errs)); return 1; }
    }
    double best = 1e9;
    plan::PlanStats stats;
    size_t segments = 0;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = Clock::now();
      const auto g = plan::load_gcode(jpath);
      const auto p = plan::plan_job(*g, *m, card_form);
      if (!p.ok()) { fmt::print(stderr, "{}\n", plan::join(p.errors)); return 1; }
      const auto w = card::to_wire(*p, jpath);
      if (!w.ok()) { fmt::print(stderr, "{}\n", plan::join(w.errors)); return 1; }
      const auto words = card::encode_job(*m, *w);
      best = std::min(best, seconds_since(t0));
      stats = p->stats;
      segments = w->segments.size();
    }
    const auto before = plan::plan_job(*plan::load_gcode(jpath), *m, no_add2);
    if (!before.ok()) { fmt::print(stderr, "{}\n", plan::join(before.errors)); return 1; }
    const size_t lines = count_lines(jpath);
    fmt::print("| {} | {} | {} | {} | {} | {} | {:.2f} | {:.2f} | {:.0f} cycles ({:.2g} s) | {:.3f} s | {:.0f} |\n",
               mach, job, lines, segments, stats.moves, stats.chunks, stats.moves_per_chunk(),
               before->stats.moves_per_chunk(), m->chunk_tolerance_cycles(), m->planner.chunk_tolerance_s,
               best, lines / best);
  }

  fmt::print("\n### One S-curve solve\n\n");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> len(0.01, 100), speed(0, 60);
  const int n = 200000;
  std::vector<std::array<double, 3>> cases(n);
  for (auto& c : cases) c = {len(rng), speed(rng), speed(rng)};
  int feasible = 0;
  const auto t0 = Clock::now();
  for (const auto& c : cases) feasible += plan::make_profile(c[0], 0, 0, c[1] + 1, 500, 2000).has_value();
  const double t_rest = seconds_since(t0) / n;
  const auto t1 = Clock::now();
  for (const auto& c : cases)
    feasible += plan::make_profile(c[0], c[2] * 0.2, c[1] * 0.2, 60, 500, 2000).has_value();
  const double t_moving = seconds_since(t1) / n;
  fmt::print("`plan::make_profile` with seed 002's limits (J = 2000 mm/s^3, A = 500 mm/s^2, "
             "vmax up to 60 mm/s), {} random lengths 0.01..100 mm each ({} feasible in all):\n\n", n,
             feasible);
  fmt::print("| case | time per solve |\n|---|---:|\n");
  fmt::print("| from rest to rest | {:.2f} µs |\n", t_rest * 1e6);
  fmt::print("| non-zero entry and exit speeds | {:.2f} µs |\n\n", t_moving * 1e6);
  return 0;
}

// SPDX-License-Identifier: MIT
#include "cli/home_command.h"

#include <fmt/format.h>

#include <cctype>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "card/caps.h"
#include "cpstep/builds.h"
#include "run/home.h"

namespace cpstep::cli {

namespace {
constexpr int kExitFailed = 1, kExitRefused = 2;

std::string axis_name(int a) { return std::string(1, char(std::toupper(plan::kAxisLetters[a]))); }
}  // namespace

CLI::App* add_home_command(CLI::App& app, HomeOptions& o) {
  auto* c = app.add_subcommand("home", "Home the machine's axes ([axes.X.home]) on the simulated card, its switches "
                                       "where home.sim_switch_mm places them (docs/HOST.md \"Homing\")");
  c->add_option("--machine", o.machine, "machine file (TOML)")->required()->check(CLI::ExistingFile);
  c->add_option("--board", o.board,
                "the simulated board (rtl/builds.json: " + card::board_names() + "; one with inputs; default hx8k)");
  c->add_option("--engine", o.engine, "model (the fast engine), rtl (the Verilated card) or lockstep (both)")
      ->capture_default_str()
      ->check(CLI::IsMember({"model", "rtl", "lockstep"}));
  c->add_flag("--json", o.json, "one JSON object: axes (trips, offsets, moves), counts, pins, switch trips");
  return c;
}

int run_home(const HomeOptions& o) {
  const std::string board = o.board.empty() ? std::string("hx8k") : o.board;
  const run::SimHomeRun r = run::home_on_sim(o.machine, board, o.engine);
  if (!r.error.empty()) {
    fmt::print(stderr, "cpstep home: {}\n", r.error);
    return kExitRefused;
  }
  const plan::Machine& m = r.machine;
  std::string error = r.result.error;
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present && r.pins[a] != r.counts[a] && error.empty())
      error = fmt::format("PIN_COUNT: {} counted {} steps on its pins, the card's counter reads {}", axis_name(a),
                          r.pins[a], r.counts[a]);
  if (o.json) {
    nlohmann::json j;
    j["board"] = board;
    j["engine"] = o.engine;
    j["ok"] = error.empty();
    j["error"] = error;
    j["cycles"] = r.cycles;
    j["clock_hz"] = m.card.clock_hz;
    nlohmann::json axes = nlohmann::json::array();
    for (const run::HomedAxis& h : r.result.axes) {
      const plan::AxisConfig& ax = m.axes[h.axis];
      nlohmann::json moves = nlohmann::json::array();
      for (const run::HomeMove& mv : h.moves)
        moves.push_back({{"what", mv.what}, {"from", mv.from}, {"to", mv.to}, {"tripped", mv.tripped}});
      axes.push_back({{"axis", std::string(1, plan::kAxisLetters[h.axis])},
                      {"switch", ax.home.at_max ? "max" : "min"},
                      {"steps_per_mm", ax.steps_per_mm},
                      {"position_mm", ax.home.position_mm},
                      {"sim_switch_steps", r.switch_at[h.axis]},
                      {"search_trip", h.search_trip},
                      {"latch_trip", h.latch_trip},
                      {"offset", h.offset},
                      {"final_count", h.final_count},
                      {"final_mm", h.final_mm},
                      {"moves", moves}});
    }
    j["axes"] = axes;
    nlohmann::json counts, pins, trips = nlohmann::json::array();
    for (int a = 0; a < plan::kAxes; ++a)
      if (m.axes[a].present) {
        counts[std::string(1, plan::kAxisLetters[a])] = r.counts[a];
        pins[std::string(1, plan::kAxisLetters[a])] = r.pins[a];
      }
    for (const run::SimHomeSwitchTrip& t : r.trips)
      trips.push_back({{"axis", std::string(1, plan::kAxisLetters[t.axis])}, {"cycle", t.cycle}, {"pins", t.pins}});
    j["counts"] = counts;
    j["pins"] = pins;
    j["switch_trips"] = trips;
    fmt::print("{}\n", j.dump(2));
  } else {
    fmt::print("cpstep home: {} on the simulated {} card (engine {}), {:.3f} s simulated\n", m.file, board, o.engine,
               double(r.cycles) / m.card.clock_hz);
    for (const run::HomedAxis& h : r.result.axes) {
      const plan::AxisConfig& ax = m.axes[h.axis];
      fmt::print("{}  {} switch (simulated at {} steps)\n", axis_name(h.axis), ax.home.at_max ? "max" : "min",
                 r.switch_at[h.axis]);
      for (const run::HomeMove& mv : h.moves)
        fmt::print("   {:<8} {:>10} -> {:>10}{}\n", mv.what, mv.from, mv.to, mv.tripped ? "  tripped" : "");
      if (h.moves.size() >= 4)
        fmt::print("   home: the latch trip at count {} is {:.4f} mm (offset {}); backed off to {:.4f} mm\n",
                   h.latch_trip, ax.home.position_mm, h.offset, h.final_mm);
    }
    std::string pins;
    for (int a = 0; a < plan::kAxes; ++a)
      if (m.axes[a].present) pins += fmt::format("{}{}={}", pins.empty() ? "" : " ", plan::kAxisLetters[a], r.pins[a]);
    fmt::print("pins       {} (STEP edges counted by DIR){}\n", pins,
               error.rfind("PIN_COUNT", 0) == 0 ? "" : ", equal to the card's counters");
    fmt::print("result     {}\n", error.empty() ? "homed" : error);
  }
  if (!error.empty() && o.json) fmt::print(stderr, "cpstep home: {}\n", error);
  return error.empty() ? 0 : kExitFailed;
}

}  // namespace cpstep::cli

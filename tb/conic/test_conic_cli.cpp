// SPDX-License-Identifier: MIT
// `cpstep conic` as a user runs it (docs/CONIC.md "From the command line"): the
// program runs as a process, its JSON is read back, and every check is made here
// from the moves it printed and the curve the test asked for: the nodes are summed
// from the moves, their distances to the curve computed in this file (circles in
// closed form, the ellipse by dense sampling), not taken from the program.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "common/process.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using cpstep::tb::Outcome;

// `cpstep conic ARGS` (split at spaces: the tests' arguments hold none). Its
// output files are named after the test and a call count: ctest runs the tests
// of this file as parallel processes, which must not share a file.
Outcome cpstep(const std::string& args) {
  std::vector<std::string> argv{"conic"};
  std::istringstream in(args);
  for (std::string a; in >> a;) argv.push_back(a);
  static int calls = 0;
  const std::string tag = std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
                          std::to_string(calls++);
  return cpstep::tb::run_program(CPSTEP_BIN, argv, fs::path(CPSTEP_TEST_DIR) / "conic_cli", tag);
}

struct Path {
  std::vector<std::pair<int, int>> moves;
  std::vector<std::pair<long, long>> nodes;  // start, then after each move
  double max_deviation = -1;
  int combined = 0;
};

// The program's JSON, with the nodes summed here from its start and moves.
Path read(const std::string& text) {
  const json j = json::parse(text);
  Path p;
  p.max_deviation = j.at("max_deviation").get<double>();
  long x = j.at("start").at(0).get<long>(), y = j.at("start").at(1).get<long>();
  p.nodes.push_back({x, y});
  for (const json& m : j.at("moves")) {
    const int dx = m.at(0).get<int>(), dy = m.at(1).get<int>();
    p.moves.push_back({dx, dy});
    x += dx;
    y += dy;
    p.nodes.push_back({x, y});
    p.combined += dx != 0 && dy != 0;
  }
  const long ex = j.at("end").at(0).get<long>(), ey = j.at("end").at(1).get<long>();
  EXPECT_EQ(p.nodes.back(), std::make_pair(ex, ey)) << "the moves do not add up to the end node";
  return p;
}

// Each move one step or one combined step; the distances to the curve.
double check_path(const Path& p, const std::function<double(double, double)>& distance) {
  double worst = 0;
  for (const auto& [dx, dy] : p.moves) {
    EXPECT_TRUE(std::abs(dx) <= 1 && std::abs(dy) <= 1 && (dx || dy)) << dx << "," << dy;
  }
  for (const auto& [x, y] : p.nodes) worst = std::max(worst, distance(double(x), double(y)));
  return worst;
}

std::function<double(double, double)> circle(double cx, double cy, double r) {
  return [=](double x, double y) { return std::abs(std::hypot(x - cx, y - cy) - r); };
}

TEST(ConicCli, QuarterCircleSameOnEveryEngineWithinHalfAStep) {
  Path paths[3];
  const char* engines[3] = {"rtl", "model", "oracle"};
  for (int e = 0; e < 3; ++e) {
    SCOPED_TRACE(engines[e]);
    const Outcome o =
        cpstep(std::string("--from 20 0 --to 0 20 --center 0 0 --ccw --json --engine ") + engines[e]);
    ASSERT_EQ(o.rc, 0) << o.err;
    paths[e] = read(o.out);
    const Path& p = paths[e];
    EXPECT_EQ(p.nodes.front(), std::make_pair(20L, 0L));
    EXPECT_EQ(p.nodes.back(), std::make_pair(0L, 20L));
    const double worst = check_path(p, circle(0, 0, 20));
    EXPECT_LE(worst, 0.5);
    EXPECT_NEAR(p.max_deviation, worst, 1e-9);
    // Counter-clockwise from (20, 0): x never grows, y never falls.
    for (const auto& [dx, dy] : p.moves) EXPECT_TRUE(dx <= 0 && dy >= 0);
    // Combined steps: a quarter of radius r takes about r*sqrt(2) moves, not 2r.
    EXPECT_LT(p.moves.size(), 2u * 20u);
    EXPECT_GT(p.combined, 0);
  }
  EXPECT_EQ(paths[0].moves, paths[1].moves) << "the RTL and its model differ";
}

TEST(ConicCli, FullTurnOffGridCentreClockwise) {
  // Centre (0.25, -0.5), through (7.25, -0.5): r = 7, a full turn.
  const Outcome o = cpstep("--from 7.25 -0.5 --to 7.25 -0.5 --center 0.25 -0.5 --json --engine model");
  ASSERT_EQ(o.rc, 0) << o.err;
  const Path p = read(o.out);
  EXPECT_EQ(p.nodes.front(), p.nodes.back()) << "a full turn ends where it started";
  EXPECT_GT(p.moves.size(), 7u * 4u);
  const double worst = check_path(p, circle(0.25, -0.5, 7));
  EXPECT_LE(worst, 0.5);
  EXPECT_NEAR(p.max_deviation, worst, 1e-9);
  // Clockwise: the cross product of successive moves never turns left by much;
  // the signed area of the closed walk is negative.
  double area2 = 0;
  for (std::size_t i = 0; i + 1 < p.nodes.size(); ++i)
    area2 += double(p.nodes[i].first) * double(p.nodes[i + 1].second) -
             double(p.nodes[i + 1].first) * double(p.nodes[i].second);
  EXPECT_LT(area2, 0);
  EXPECT_NEAR(-area2 / 2, M_PI * 49, M_PI * 49 * 0.1);
}

TEST(ConicCli, GeneralConicAnEllipse) {
  // x^2 + 4 y^2 - 400 = 0: semi-axes 20 and 10, a quarter counter-clockwise.
  const Outcome o = cpstep("--from 20 0 --to 0 10 --coeffs 1 0 4 0 0 -400 --ccw --json --engine rtl");
  ASSERT_EQ(o.rc, 0) << o.err;
  const Path p = read(o.out);
  EXPECT_EQ(p.nodes.front(), std::make_pair(20L, 0L));
  EXPECT_EQ(p.nodes.back(), std::make_pair(0L, 10L));
  // Distance to the ellipse by dense sampling of (20 cos t, 10 sin t).
  const double worst = check_path(p, [](double x, double y) {
    double best = 1e9;
    for (int i = 0; i <= 200000; ++i) {
      const double t = 2 * M_PI * i / 200000;
      best = std::min(best, std::hypot(x - 20 * std::cos(t), y - 10 * std::sin(t)));
    }
    return best;
  });
  EXPECT_LE(worst, 0.55);
  EXPECT_NEAR(p.max_deviation, worst, 1e-3);
}

TEST(ConicCli, TextOutputListsTheMoves) {
  const Outcome o = cpstep("--from 3 0 --to 0 3 --center 0 0 --ccw --engine model");
  ASSERT_EQ(o.rc, 0) << o.err;
  const Outcome j = cpstep("--from 3 0 --to 0 3 --center 0 0 --ccw --engine model --json");
  ASSERT_EQ(j.rc, 0) << j.err;
  std::string expected;
  for (const auto& [dx, dy] : read(j.out).moves) {
    expected += (dx < 0 ? "-" : "+") + std::to_string(std::abs(dx)) + " " + (dy < 0 ? "-" : "+") +
                std::to_string(std::abs(dy)) + "\n";
  }
  const auto nl = o.out.find('\n', o.out.find('\n') + 1);
  ASSERT_NE(nl, std::string::npos);
  EXPECT_EQ(o.out.substr(nl + 1), expected);
}

TEST(ConicCli, RefusalsNameTheProblem) {
  struct Case {
    const char* args;
    const char* message;
  };
  const Case cases[] = {
      {"--from 10 0 --to 0 10 --center 0.3 0", "not on the 1/16-step grid"},
      {"--from 10 0 --to 0 12 --center 0 0", "--to is 2 steps from the curve"},
      {"--from 0 0 --to 0 10 --center 0 0", "the radius is zero"},
      {"--from 10 0 --to 0 10", "give either --center"},
      {"--from 10 0 --to 0 10 --center 0 0 --coeffs 1 0 1 0 0 -100", "give either --center"},
      {"--from 10 0 --to 0 10 --coeffs 1.5 0 1 0 0 -100", "A = 1.5 is not an integer"},
      {"--from 10 0 --to 0 10 --coeffs 40000 0 40000 0 0 -4000000", "outside the engine's widths"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const Outcome o = cpstep(c.args);
    EXPECT_EQ(o.rc, 2);
    EXPECT_NE(o.err.find(c.message), std::string::npos) << o.err;
    EXPECT_EQ(o.out, "");
  }
}

}  // namespace

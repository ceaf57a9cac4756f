// SPDX-License-Identifier: MIT
#include "cli/conic_command.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/conic_oracle.h"
#include "model/cp_conic.h"
#include "sim/conic_configs.h"
#include "sim/dut.h"

namespace cpstep::cli {
namespace {

using model::CpConic;
using model::i128;
using Node = oracle::Node;
using P = sim::ConicDefault;

constexpr int kRefused = 2;
// Circles are scaled by 256 (A = C = 256): a centre on the 1/16-step grid gives
// integer D, E and F exactly; the radius through --from is rounded to F's unit,
// which moves the circle by at most 1/(512 r) steps.
constexpr int64_t kScale = 256;
constexpr int kCentreGrid = 16;

int refuse(const std::string& why) {
  fmt::print(stderr, "cpstep conic: refused: {}\n", why);
  return kRefused;
}

const char* conic_error_text(uint32_t code) {
  switch (model::ConicError(code)) {
    case model::ConicError::coef_range:
      return "a coefficient is outside the engine's widths (A, B, C: 16 bits; D, E: 32; F: 48; signed)";
    case model::ConicError::point_range: return "a start or end coordinate is outside the engine's 20 bits";
    case model::ConicError::degenerate: return "the curve's gradient is zero at the start node";
    case model::ConicError::start_off: return "the start node is not on the curve";
    case model::ConicError::end_off: return "the end node is not on the curve";
    case model::ConicError::end_missed: return "the walk did not reach the end node within NMAX moves";
    default: return "refused";
  }
}

struct Request {
  CpConic::Coeffs k;
  int64_t a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
  Node start, end;
  bool cw = true;
  oracle::Conic conic() const {
    return {(long double)a, (long double)b, (long double)c, (long double)d, (long double)e, (long double)f};
  }
};

bool integral(double v, double scale) {
  const double s = v * scale;
  return std::abs(s - std::nearbyint(s)) <= 1e-9 * std::max(1.0, std::abs(s));
}

long double dist(Node n, const std::array<double, 2>& p) {
  return std::hypot((long double)n.x - p[0], (long double)n.y - p[1]);
}

struct Outcome {
  std::vector<std::pair<int, int>> moves;
  uint32_t err = 0;
};

// One request through a stepper (the Verilated RTL or the model), taking every move.
template <class Stepper>
Outcome run_engine(Stepper& dut, const Request& rq, uint64_t max_cycles) {
  model::CpConicIn in;
  in.in_a = rq.a, in.in_b = rq.b, in.in_c = rq.c, in.in_d = rq.d, in.in_e = rq.e, in.in_f = rq.f;
  in.in_x0 = int32_t(rq.start.x), in.in_y0 = int32_t(rq.start.y);
  in.in_x1 = int32_t(rq.end.x), in.in_y1 = int32_t(rq.end.y);
  in.in_cw = rq.cw;
  in.move_ready = true;
  Outcome out;
  bool accepted = false;
  for (uint64_t n = 0; n < max_cycles; ++n) {
    in.in_valid = !accepted;
    const model::CpConicOut o = dut.step(in);
    if (in.in_valid && o.in_ready) accepted = true;
    if (o.err) {
      out.err = o.err_code;
      return out;
    }
    if (o.move_valid) {
      out.moves.emplace_back(o.move_dx, o.move_dy);
      if (o.move_last) {
        // END_MISSED shows the cycle after the last move.
        in.in_valid = false;
        const model::CpConicOut o2 = dut.step(in);
        if (o2.err) out.err = o2.err_code;
        return out;
      }
    }
  }
  out.err = uint32_t(model::ConicError::end_missed);
  return out;
}

}  // namespace

ConicRun conic_rtl_moves(const std::array<int64_t, 6>& k, std::array<int64_t, 2> start, std::array<int64_t, 2> end,
                         bool cw) {
  Request rq;
  rq.a = k[0], rq.b = k[1], rq.c = k[2], rq.d = k[3], rq.e = k[4], rq.f = k[5];
  rq.k = {rq.a, rq.b, rq.c, rq.d, rq.e, rq.f};
  rq.start = {start[0], start[1]};
  rq.end = {end[0], end[1]};
  rq.cw = cw;
  sim::RtlDut<P> dut;
  const Outcome r = run_engine(dut, rq, uint64_t(P::model_params().nmax) + 64 * 64 + 1000);
  return {r.moves, r.err};
}

int run_conic(const ConicOptions& o) {
  const auto params = P::model_params();
  Request rq;
  rq.cw = !o.ccw;
  if (o.center.has_value() == o.coeffs.has_value())
    return refuse("give either --center CX CY (a circular arc) or --coeffs A B C D E F");
  if (o.center) {
    const auto [cx, cy] = *o.center;
    if (!integral(cx, kCentreGrid) || !integral(cy, kCentreGrid))
      return refuse(fmt::format("--center {} {} is not on the 1/{}-step grid", cx, cy, kCentreGrid));
    const int64_t i = std::llround(cx * kCentreGrid), j = std::llround(cy * kCentreGrid);
    const long double r2 = std::pow((long double)o.from[0] - cx, 2) + std::pow((long double)o.from[1] - cy, 2);
    if (!(r2 > 0)) return refuse("--from is the centre: the radius is zero");
    rq.a = rq.c = kScale;
    rq.d = -2 * kScale * i / kCentreGrid;  // kScale / kCentreGrid = 16: exact
    rq.e = -2 * kScale * j / kCentreGrid;
    rq.f = i * i + j * j - std::llroundl(kScale * r2);
  } else {
    const auto& c = *o.coeffs;
    for (std::size_t n = 0; n < 6; ++n)
      if (!integral(c[n], 1) || std::abs(c[n]) > 9.2e18)
        return refuse(fmt::format("--coeffs: {} = {} is not an integer", "ABCDEF"[n], c[n]));
    rq.a = std::llround(c[0]), rq.b = std::llround(c[1]), rq.c = std::llround(c[2]);
    rq.d = std::llround(c[3]), rq.e = std::llround(c[4]), rq.f = std::llround(c[5]);
  }
  rq.k = {rq.a, rq.b, rq.c, rq.d, rq.e, rq.f};
  const oracle::Conic curve = rq.conic();
  const long double from_off = oracle::nearest(curve, o.from[0], o.from[1]).distance;
  const long double to_off = oracle::nearest(curve, o.to[0], o.to[1]).distance;
  if (!(from_off <= 0.5L)) return refuse(fmt::format("--from is {:.4g} steps from the curve", double(from_off)));
  if (!(to_off <= 0.5L))
    return refuse(fmt::format("--to is {:.4g} steps from the curve through --from", double(to_off)));

  // The start: of the four nodes around --from, those passing the engine's
  // eight-point test, the one nearest the curve.
  {
    bool found = false;
    long double best = 0;
    const auto bx = int64_t(std::floor(o.from[0])), by = int64_t(std::floor(o.from[1]));
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        const Node n{bx + i, by + j};
        if (!CpConic::on_curve(rq.k, CpConic::at(rq.k, n.x, n.y))) continue;
        const long double d = oracle::nearest(curve, n.x, n.y).distance;
        if (!found || d < best) found = true, best = d, rq.start = n;
      }
    if (!found) return refuse("no node next to --from passes the engine's on-curve test (docs/CONIC.md)");
  }
  // The end: the walk's node nearest --to, run with the engine's own rule (the
  // host knows every node the engine will make), around once at most.
  {
    std::vector<Node> walk;
    Node p = rq.start;
    CpConic::Node n = CpConic::at(rq.k, p.x, p.y);
    while (walk.size() < params.nmax) {
      int dx = 0, dy = 0;
      CpConic::rule(rq.k, n, rq.cw, dx, dy);
      if (dx == 0 && dy == 0) break;
      n = CpConic::advance(rq.k, n, dx, dy);
      p = {p.x + dx, p.y + dy};
      if (std::max(std::abs(p.x), std::abs(p.y)) > params.pmax()) break;
      walk.push_back(p);
      if (p == rq.start) break;
    }
    if (walk.empty()) return refuse("the walk makes no move from the start node");
    std::size_t best = 0;
    for (std::size_t m = 1; m < walk.size(); ++m)
      if (dist(walk[m], o.to) < dist(walk[best], o.to)) best = m;
    // A closed walk's return to the start wins a tie: --to equal to --from is a full turn.
    if (walk.back() == rq.start && !(dist(walk[best], o.to) < dist(rq.start, o.to))) best = walk.size() - 1;
    rq.end = walk[best];
  }

  std::vector<std::pair<int, int>> moves;
  const uint64_t max_cycles = uint64_t(params.nmax) + 64 * 64 + 1000;
  if (o.engine == "oracle") {
    const std::vector<Node> nodes = oracle::nearest_walk(curve, rq.start, rq.end, rq.cw, params.nmax);
    if (nodes.empty() || !(nodes.back() == rq.end))
      return refuse("the oracle's nearest-node walk did not reach the end node");
    Node prev = rq.start;
    for (const Node& n : nodes) {
      moves.emplace_back(int(n.x - prev.x), int(n.y - prev.y));
      prev = n;
    }
  } else {
    Outcome r;
    if (o.engine == "rtl") {
      sim::RtlDut<P> dut;
      r = run_engine(dut, rq, max_cycles);
    } else {
      sim::ModelDut<P> dut;
      r = run_engine(dut, rq, max_cycles);
    }
    if (r.err) return refuse(conic_error_text(r.err));
    moves = std::move(r.moves);
  }

  // Every node's geometric distance from the true curve (the oracle's).
  long double worst = oracle::nearest(curve, rq.start.x, rq.start.y).distance;
  std::size_t combined = 0;
  Node p = rq.start;
  for (const auto& [dx, dy] : moves) {
    p = {p.x + dx, p.y + dy};
    combined += dx != 0 && dy != 0;
    worst = std::max(worst, oracle::nearest(curve, p.x, p.y).distance);
  }

  if (o.json) {
    nlohmann::json j;
    j["engine"] = o.engine;
    j["coeffs"] = {rq.a, rq.b, rq.c, rq.d, rq.e, rq.f};
    j["direction"] = rq.cw ? "cw" : "ccw";
    j["start"] = {rq.start.x, rq.start.y};
    j["end"] = {rq.end.x, rq.end.y};
    nlohmann::json mv = nlohmann::json::array();
    for (const auto& [dx, dy] : moves) mv.push_back({dx, dy});
    j["moves"] = std::move(mv);
    j["combined"] = combined;
    j["max_deviation"] = double(worst);
    fmt::print("{}\n", j.dump());
    return 0;
  }
  fmt::print("conic {}x^2 + {}xy + {}y^2 + {}x + {}y + {} = 0, {}, engine {}\n", rq.a, rq.b, rq.c, rq.d, rq.e,
             rq.f, rq.cw ? "clockwise" : "counter-clockwise", o.engine);
  fmt::print("start {} {}  end {} {}  moves {} ({} combined)  max deviation {:.6f} steps\n", rq.start.x,
             rq.start.y, rq.end.x, rq.end.y, moves.size(), combined, double(worst));
  for (const auto& [dx, dy] : moves) fmt::print("{:+d} {:+d}\n", dx, dy);
  return 0;
}

}  // namespace cpstep::cli

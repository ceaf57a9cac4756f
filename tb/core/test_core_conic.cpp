// SPDX-License-Identifier: MIT
// CONIC segments through the whole motion core (docs/CORE.md "CONIC"): the HX8K's
// core built with CONIC = 1, RTL and model in lockstep every cycle, words in at the
// command port, and the plane axes' moves read back from the position counters and
// judged against the rule's walk (model::CpConicSerial::rule, docs/CONIC.md), the
// other axes' steps against their patterns' totals; whole circles in four conics,
// conics between lines, and a walk that ends early or late (CONIC_END).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "Vcp_core_conic.h"
#include "card/protocol.h"
#include "common/lockstep.h"
#include "cpstep/builds.h"
#include "model/cp_conic_serial.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"

namespace cpstep::tb {
namespace {

constexpr unsigned kIw = 40;

struct CoreConic : sim::CorePortBase<Vcp_core_conic, 4> {
  using Model = model::CpCore;
  static Model::Params model_params() {
    model::CpCoreParams p = model::core_params(builds::hx8k);
    p.conic = true;
    p.ciw = kIw;
    return p;
  }
};

using Coeffs = model::CpConic::Coeffs;
using CNode = model::CpConic::Node;
using Move = std::pair<int, int>;

// An arc of the circle about (cx16/16, cy16/16) of radius r steps, at the host's
// scale (A = C = 256): from the node nearest the circle at angle a0, `moves` moves
// of the rule's walk.
struct Arc {
  Coeffs k;
  CNode start;
  bool cw = false;
  std::vector<Move> moves;
  int64_t du = 0, dv = 0;
};

Arc circle_arc(int64_t cx16, int64_t cy16, double r, double a0, bool cw, size_t moves) {
  Arc arc;
  arc.k = {256, 0, 256, -32 * cx16, -32 * cy16, cx16 * cx16 + cy16 * cy16 - std::llround(256 * r * r)};
  arc.cw = cw;
  const double px = cx16 / 16.0 + r * std::cos(a0), py = cy16 / 16.0 + r * std::sin(a0);
  // Of the nodes around the point, the one with the smallest |G| / |gradient| that
  // passes the eight-point test.
  int64_t bx = 0, by = 0;
  double best = INFINITY;
  for (int64_t x = int64_t(std::floor(px)); x <= int64_t(std::floor(px)) + 1; ++x)
    for (int64_t y = int64_t(std::floor(py)); y <= int64_t(std::floor(py)) + 1; ++y) {
      const CNode n = model::CpConic::at(arc.k, x, y);
      const double d = std::fabs(double(n.g)) / std::hypot(double(n.gx), double(n.gy));
      if (model::CpConic::on_curve(arc.k, n) && d < best) {
        best = d;
        bx = x;
        by = y;
      }
    }
  arc.start = model::CpConic::at(arc.k, bx, by);
  CNode n = arc.start;
  for (size_t i = 0; i < moves; ++i) {
    EXPECT_TRUE(model::CpConicSerial::fits(arc.k, n, kIw));
    int dx = 0, dy = 0;
    model::CpConicSerial::rule(arc.k, n, cw, kIw, dx, dy);
    n = model::CpConic::advance(arc.k, n, dx, dy);
    arc.moves.push_back({dx, dy});
    arc.du += dx;
    arc.dv += dy;
  }
  return arc;
}

// The first move first_interval cycles after the one before (or START), then every
// `interval` cycles.
std::vector<card::WireChunk> even_chunks(uint64_t moves, uint32_t interval, uint32_t first_interval) {
  std::vector<card::WireChunk> out = {{first_interval, 1, 0, 0}};
  for (uint64_t left = moves - 1; left > 0;) {
    const uint16_t c = uint16_t(std::min<uint64_t>(left, 60000));
    out.push_back({interval, c, 0, 0});
    left -= c;
  }
  return out;
}

// The arc as a CONIC segment on axes x (u) and y (v), z following by v_z steps; `t`
// overrides its move count (a wrong one, for CONIC_END).
card::WireConic conic_segment(const Arc& arc, uint32_t vz, bool end, uint32_t interval, uint32_t first_interval,
                              uint32_t t = 0) {
  card::WireConic s;
  s.t = t ? t : uint32_t(arc.moves.size());
  s.end = end;
  s.cw = arc.cw;
  s.axis_u = 0;
  s.axis_v = 1;
  s.dir_positive = {true, true, true, true};
  s.v = {0, 0, vz, 0};
  s.a = int32_t(arc.k.a);
  s.b = int32_t(arc.k.b);
  s.c = int32_t(arc.k.c);
  EXPECT_EQ(int32_t(arc.start.gx), arc.start.gx) << "the start's values fit the wire's 32 bits";
  EXPECT_EQ(int32_t(arc.start.gy), arc.start.gy);
  s.g = int32_t(arc.start.g);
  s.gx = int32_t(arc.start.gx);
  s.gy = int32_t(arc.start.gy);
  s.du = int32_t(arc.du);
  s.dv = int32_t(arc.dv);
  s.chunks = even_chunks(s.t, interval, first_interval);
  return s;
}

// A line segment of `moves` moves on x and y (as the host sends one: U the larger).
card::WireSegment line_segment(int64_t dx, int64_t dy, bool end, uint32_t interval) {
  card::WireSegment s;
  const uint64_t ax = uint64_t(std::llabs(dx)), ay = uint64_t(std::llabs(dy));
  s.u = uint32_t(std::max(ax, ay));
  s.k = 0;
  s.end = end;
  s.dir_positive = {dx > 0, dy > 0, true, true};
  s.v = {uint32_t(ax), uint32_t(ay), 0, 0};
  s.chunks = even_chunks(s.u, interval, interval);
  return s;
}

// A job through the lockstep core: the words of every command, START after the
// first, then until the run stops. Each cycle whose x or y position changed is one
// move of the plane (a conic's move steps x or y or both; a line's too, here).
struct JobResult {
  std::vector<Move> xy_moves;
  model::CpCoreOut last;
};

// must_run: a run that never starts (a command refused before START) is a failure.
JobResult run_job(const std::vector<std::vector<uint32_t>>& commands, uint64_t max_cycles, bool must_run = true) {
  Lockstep<CoreConic> ls;
  JobResult r;
  std::array<int64_t, 2> pos{};
  sim::CoreDriver<Lockstep<CoreConic>> drv(ls, [&](uint64_t, const model::CpCoreIn&, const model::CpCoreOut& o) {
    const int64_t dx = o.position[0] - pos[0], dy = o.position[1] - pos[1];
    if (dx || dy) r.xy_moves.push_back({int(dx), int(dy)});
    pos = {o.position[0], o.position[1]};
  });
  drv.reset();
  for (size_t i = 0; i < commands.size(); ++i) {
    drv.send(commands[i]);
    if (i == 0) {
      std::vector<uint32_t> start;
      card::encode_control(true, false, false, start);
      drv.send(start);
    }
  }
  try {
    drv.run_until_stopped(max_cycles);
  } catch (const std::runtime_error& e) {
    const auto& o = drv.last();
    if (must_run || o.running || o.err_code == 0)
      ADD_FAILURE() << e.what() << ": " << o.moves_done << " moves done, " << o.segments_done
                  << " segments, error " << o.err_code << ", running " << o.running;
  }
  drv.idle(50);
  r.last = drv.last();
  return r;
}

std::vector<uint32_t> words_of(const card::WireConic& s) {
  std::vector<uint32_t> w;
  card::encode_conic(s, w);
  return w;
}
std::vector<uint32_t> words_of(const card::WireSegment& s) {
  std::vector<uint32_t> w;
  card::encode_segment(s, w);
  return w;
}

std::vector<Move> concat(std::vector<Move> a, const std::vector<Move>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Arcs of radius 10, 57.3 and 300 steps, both directions, across quadrant changes
// (x or y reverses inside the segment, DIR set before the move), with z following as
// a helix: the pins' moves are the rule's walk, z ends at v_z, nothing late.
TEST(CoreConic, ArcsAndHelicesOnThePins) {
  struct Case {
    int64_t cx16, cy16;
    double r, a0;
    bool cw;
    size_t moves;
    uint32_t vz;
  };
  const Case cases[] = {
      {0, 0, 10, 0.3, false, 20, 7},          {5, -3, 57.3, 1.2, true, 120, 0},
      {-11, 7, 57.3, 2.9, false, 160, 160},   {16, 16, 300, -0.4, false, 600, 211},
      {3, 9, 300, 4.0, true, 700, 350},
  };
  for (const Case& c : cases) {
    const Arc arc = circle_arc(c.cx16, c.cy16, c.r, c.a0, c.cw, c.moves);
    // The first move 3,000 cycles after START: the segment is built (z's pattern of up
    // to 700 moves takes twice that in clocks) and the walker's first move decided by
    // then (the host plans the start so).
    const JobResult r = run_job({words_of(conic_segment(arc, c.vz, true, 50, 3000))}, 200000);
    const std::string what = "r " + std::to_string(c.r) + (c.cw ? " cw" : " ccw");
    EXPECT_EQ(r.last.err_code, 0u) << what;
    EXPECT_EQ(r.xy_moves, arc.moves) << what;
    EXPECT_EQ(r.last.position[0], arc.du) << what;
    EXPECT_EQ(r.last.position[1], arc.dv) << what;
    EXPECT_EQ(r.last.position[2], int64_t(c.vz)) << what;
    EXPECT_EQ(r.last.moves_done, uint32_t(c.moves)) << what;
    EXPECT_EQ(r.last.stretch_count, 0u) << what;
    if (HasFailure()) return;
  }
}

// A whole circle of radius 40 in four conics, back to back (the next conic's words
// wait for the walker: here its first move `gap` cycles on, docs/CORE.md), back where
// it started.
// With `cont` the three conics after the first continue the walk (H0[18]): K5, K6
// only, the walker going on from where the one before ended.
void whole_circle(uint32_t gap, uint64_t& stretches, bool cont = false) {
  Arc whole = circle_arc(0, 0, 40, 0.05, false, 0);
  // Walk until back at the start.
  for (CNode n = whole.start; whole.moves.empty() || whole.du != 0 || whole.dv != 0;) {
    ASSERT_LT(whole.moves.size(), 1000u);
    int dx = 0, dy = 0;
    model::CpConicSerial::rule(whole.k, n, whole.cw, kIw, dx, dy);
    n = model::CpConic::advance(whole.k, n, dx, dy);
    whole.moves.push_back({dx, dy});
    whole.du += dx;
    whole.dv += dy;
  }
  std::vector<std::vector<uint32_t>> job;
  std::vector<Move> want;
  size_t at = 0;
  CNode node = whole.start;
  for (int q = 0; q < 4; ++q) {
    const size_t n = q < 3 ? whole.moves.size() / 4 : whole.moves.size() - at;
    Arc part;
    part.k = whole.k;
    part.cw = whole.cw;
    part.start = node;
    for (size_t i = at; i < at + n; ++i) {
      part.moves.push_back(whole.moves[i]);
      part.du += whole.moves[i].first;
      part.dv += whole.moves[i].second;
      node = model::CpConic::advance(whole.k, node, whole.moves[i].first, whole.moves[i].second);
    }
    at += n;
    want = concat(want, part.moves);
    card::WireConic seg = conic_segment(part, 0, q == 3, 45, q == 0 ? 300 : gap);
    seg.cont = cont && q > 0;
    job.push_back(words_of(seg));
    EXPECT_EQ(job.back().size(), 2 + 4 + (seg.cont ? 2 : 7) + 2 * seg.chunks.size());
  }
  const JobResult r = run_job(job, 200000);
  EXPECT_EQ(r.last.err_code, 0u);
  EXPECT_EQ(r.xy_moves, want);
  EXPECT_EQ(r.last.position[0], 0);
  EXPECT_EQ(r.last.position[1], 0);
  EXPECT_EQ(r.last.segments_done, 4u);
  stretches = r.last.stretch_count;
}

TEST(CoreConic, AWholeCircleInFourConicsBackToBack) {
  uint64_t stretches = 0;
  whole_circle(100, stretches);
  EXPECT_EQ(stretches, 0u);
}

// The same circle with the three later conics continuing the walk: the same moves.
TEST(CoreConic, AWholeCircleInAConicAndThreeContinuations) {
  uint64_t stretches = 0;
  whole_circle(100, stretches, true);
  EXPECT_EQ(stretches, 0u);
}

// A continuation is refused whole (CONIC_CONTINUE, 18) unless it follows a CONIC on
// its axes and way: after a line, first after reset, on other axes, the other way.
TEST(CoreConic, AContinuationAfterAnythingButItsConicIsRefused) {
  const Arc arc = circle_arc(0, 0, 30, 0.4, false, 50);
  Arc rest = circle_arc(0, 0, 30, 0.4, false, 80);
  // rest: the 30 moves after arc's 50, from arc's end node.
  rest.start = arc.start;
  for (const Move& m : arc.moves) rest.start = model::CpConic::advance(arc.k, rest.start, m.first, m.second);
  rest.moves.erase(rest.moves.begin(), rest.moves.begin() + 50);
  rest.du = rest.dv = 0;
  for (const Move& m : rest.moves) rest.du += m.first, rest.dv += m.second;
  const auto cont_of = [&](bool end) {
    card::WireConic c = conic_segment(rest, 0, end, 50, 300);
    c.cont = true;
    return c;
  };
  {  // after its conic: taken, the walk goes on
    const JobResult r = run_job({words_of(conic_segment(arc, 0, false, 50, 300)), words_of(cont_of(true))}, 200000);
    EXPECT_EQ(r.last.err_code, 0u);
    EXPECT_EQ(r.xy_moves, concat(arc.moves, rest.moves));
  }
  {  // after a line
    const JobResult r = run_job({words_of(line_segment(10, 3, false, 40)), words_of(cont_of(true))}, 20000, false);
    EXPECT_EQ(r.last.err_code, uint32_t(model::CoreError::conic_cont));
    EXPECT_LE(r.xy_moves.size(), 10u) << "nothing of the continuation moved";
  }
  {  // first after reset
    const JobResult r = run_job({words_of(cont_of(true))}, 20000, false);
    EXPECT_EQ(r.last.err_code, uint32_t(model::CoreError::conic_cont));
    EXPECT_TRUE(r.xy_moves.empty());
  }
  {  // on other axes, the other way
    card::WireConic other_axes = cont_of(true), other_way = cont_of(true);
    other_axes.axis_v = 2;
    other_axes.v = {0, 0, 0, 0};
    other_way.cw = !other_way.cw;
    for (const card::WireConic& c : {other_axes, other_way}) {
      const JobResult r = run_job({words_of(conic_segment(arc, 0, false, 50, 300)), words_of(c)}, 20000, false);
      EXPECT_EQ(r.last.err_code, uint32_t(model::CoreError::conic_cont));
      // The conic may run (the fault flushes after the segment under way), the
      // continuation does not.
      ASSERT_LE(r.xy_moves.size(), arc.moves.size());
      EXPECT_EQ(r.xy_moves, std::vector<Move>(arc.moves.begin(), arc.moves.begin() + long(r.xy_moves.size())));
    }
  }
}

// The same with the next conic's first move 20 cycles after the last (less than the
// 8 + CIW + 2 the walker needs): each of the three is late, once; the path is the same.
TEST(CoreConic, ConicsTooCloseAreLateNotWrong) {
  uint64_t stretches = 0;
  whole_circle(20, stretches);
  EXPECT_EQ(stretches, 3u);
}

// Lines and conics in turn: the walker loads while a line runs.
TEST(CoreConic, ConicsBetweenLines) {
  const Arc a1 = circle_arc(2, 1, 25, 0.7, true, 40);
  const Arc a2 = circle_arc(-7, 4, 80, 2.2, false, 90);
  const card::WireSegment l1 = line_segment(30, -12, false, 20), l2 = line_segment(-5, 17, false, 20),
                          l3 = line_segment(9, 9, true, 20);
  const JobResult r = run_job({words_of(l1), words_of(conic_segment(a1, 0, false, 48, 48)), words_of(l2),
                               words_of(conic_segment(a2, 13, false, 48, 48)), words_of(l3)},
                              200000);
  EXPECT_EQ(r.last.err_code, 0u);
  EXPECT_EQ(r.last.position[0], 30 + a1.du - 5 + a2.du + 9);
  EXPECT_EQ(r.last.position[1], -12 + a1.dv + 17 + a2.dv + 9);
  EXPECT_EQ(r.last.position[2], 13);
  EXPECT_EQ(r.last.stretch_count, 0u);
  // The conics' moves, in their place among the lines' (a line's moves are its
  // pattern's; here only their count is judged).
  ASSERT_EQ(r.xy_moves.size(), 30 + a1.moves.size() + 17 + a2.moves.size() + 9);
  EXPECT_EQ(std::vector<Move>(r.xy_moves.begin() + 30, r.xy_moves.begin() + 30 + 40), a1.moves);
  EXPECT_EQ(std::vector<Move>(r.xy_moves.begin() + 87, r.xy_moves.begin() + 87 + 90), a2.moves);
}

// A conic whose move count disagrees with its walk: the move that says otherwise does
// not fire and CONIC_END (17) latches; the positions are where the last move left them.
TEST(CoreConic, AWalkEndingEarlyOrLateIsConicEnd) {
  const Arc arc = circle_arc(0, 0, 30, 0.4, false, 50);
  for (const uint32_t t : {52u, 48u}) {
    const JobResult r = run_job({words_of(conic_segment(arc, 0, true, 50, 300, t))}, 200000);
    const size_t made = t > 50 ? 49 : t - 1;  // the end move (t > 50) or the segment's last (t < 50) is refused
    EXPECT_EQ(r.last.err_code, uint32_t(model::CoreError::conic_end)) << "T = " << t;
    EXPECT_EQ(r.last.moves_done, uint32_t(made)) << "T = " << t;
    ASSERT_EQ(r.xy_moves.size(), made) << "T = " << t;
    EXPECT_EQ(r.xy_moves, std::vector<Move>(arc.moves.begin(), arc.moves.begin() + long(made)));
  }
}

}  // namespace
}  // namespace cpstep::tb

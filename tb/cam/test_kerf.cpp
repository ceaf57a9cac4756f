// SPDX-License-Identifier: MIT
// Kerf compensation (host/cam/kerf.h): exact where the answer is known (a circle
// grows or shrinks by half the kerf), elsewhere against libpolyclipping's offset of
// the flattened contour (round joins): area and Hausdorff distance.
#include <gtest/gtest.h>
#include <polyclipping/clipper.hpp>

#include <cmath>

#include "cam/contour.h"
#include "cam/kerf.h"

using namespace cpstep::cam;

namespace {

constexpr double kScale = 1e5;  // clipper units per mm

// The contour as cut: chained, classified, oriented (outer clockwise, hole counter-clockwise).
Chain as_cut(const std::vector<Seg>& segs, bool hole) {
  auto chains = build_chains(segs, 0.001);
  EXPECT_EQ(chains.size(), 1u);
  Chain c = chains[0];
  c.depth = hole ? 1 : 0;
  orient_for_cut(c);
  return c;
}

std::vector<Vec2> flat(const std::vector<Seg>& segs, double tol = 0.001) {
  Chain c;
  c.segs = segs;
  c.closed = true;
  return c.polygon(tol);
}

// libpolyclipping's offset of the flattened contour: outward by d (outer) or inward (hole).
std::vector<std::vector<Vec2>> clipper_offset(const std::vector<Seg>& segs, double d, bool hole) {
  ClipperLib::Path p;
  for (Vec2 v : flat(segs)) p.push_back({ClipperLib::cInt(std::llround(v.x * kScale)), ClipperLib::cInt(std::llround(v.y * kScale))});
  if (!ClipperLib::Orientation(p)) ClipperLib::ReversePath(p);
  ClipperLib::ClipperOffset off;
  off.ArcTolerance = 0.0005 * kScale;
  off.AddPath(p, ClipperLib::jtRound, ClipperLib::etClosedPolygon);
  ClipperLib::Paths out;
  off.Execute(out, (hole ? -d : d) * kScale);
  std::vector<std::vector<Vec2>> res;
  for (const auto& q : out) {
    res.emplace_back();
    for (const auto& v : q) res.back().push_back({double(v.X) / kScale, double(v.Y) / kScale});
  }
  return res;
}

double seg_dist(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0;
  return dist(p, a + d * t);
}

double one_way(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  double worst = 0;
  for (Vec2 p : a) {
    double best = 1e300;
    for (std::size_t i = 0; i < b.size(); ++i) best = std::min(best, seg_dist(p, b[i], b[(i + 1) % b.size()]));
    worst = std::max(worst, best);
  }
  return worst;
}

double hausdorff(const std::vector<Vec2>& a, const std::vector<Vec2>& b) { return std::max(one_way(a, b), one_way(b, a)); }

void expect_matches_clipper(const std::vector<Seg>& segs, double kerf, bool hole, double hd_tol = 0.003) {
  const Chain c = as_cut(segs, hole);
  const OffsetResult r = offset_left(c.segs, kerf / 2);
  ASSERT_FALSE(r.segs.empty());
  const auto ref = clipper_offset(c.segs, kerf / 2, hole);
  ASSERT_EQ(ref.size(), 1u);
  const auto mine = flat(r.segs);
  EXPECT_NEAR(std::abs(signed_area(mine)), std::abs(signed_area(ref[0])), 1e-3 * std::abs(signed_area(ref[0])));
  EXPECT_LE(hausdorff(mine, ref[0]), hd_tol);
  // the result is one closed path, joint to joint
  for (std::size_t i = 0; i < r.segs.size(); ++i) EXPECT_LE(dist(r.segs[i].b, r.segs[(i + 1) % r.segs.size()].a), 1e-9);
}

std::vector<Seg> rounded_rect(double w, double h, double r) {
  return {Seg::line({r, 0}, {w - r, 0}), Seg::circle_arc({w - r, r}, r, -kPi / 2, 0), Seg::line({w, r}, {w, h - r}),
          Seg::circle_arc({w - r, h - r}, r, 0, kPi / 2), Seg::line({w - r, h}, {r, h}),
          Seg::circle_arc({r, h - r}, r, kPi / 2, kPi), Seg::line({0, h - r}, {0, r}),
          Seg::circle_arc({r, r}, r, kPi, 3 * kPi / 2)};
}

}  // namespace

TEST(Kerf, CircleOuterGrowsByHalfTheKerf) {
  const Chain c = as_cut({Seg::circle_arc({3, 4}, 10, 0, 2 * kPi)}, false);
  const OffsetResult r = offset_left(c.segs, 1.0);
  ASSERT_EQ(r.segs.size(), 1u);
  EXPECT_TRUE(r.segs[0].is_circular());
  EXPECT_NEAR(r.segs[0].radius(), 11, 1e-12);
  EXPECT_NEAR(dist(r.segs[0].c, {3, 4}), 0, 1e-12);
  EXPECT_TRUE(r.notes.empty());
}

TEST(Kerf, CircleHoleShrinksByHalfTheKerf) {
  const Chain c = as_cut({Seg::circle_arc({0, 0}, 10, 0, 2 * kPi)}, true);
  const OffsetResult r = offset_left(c.segs, 1.0);
  ASSERT_EQ(r.segs.size(), 1u);
  EXPECT_NEAR(r.segs[0].radius(), 9, 1e-12);
}

TEST(Kerf, SquareOuterHasArcCornersLikeClipper) {
  const std::vector<Seg> sq{Seg::line({0, 0}, {30, 0}), Seg::line({30, 0}, {30, 20}), Seg::line({30, 20}, {0, 20}),
                            Seg::line({0, 20}, {0, 0})};
  const Chain c = as_cut(sq, false);
  const OffsetResult r = offset_left(c.segs, 1.5);
  int arcs = 0;
  for (const Seg& s : r.segs) {
    if (s.kind != SegKind::arc) continue;
    ++arcs;
    EXPECT_NEAR(s.radius(), 1.5, 1e-12);  // joins are arcs about the corners
    EXPECT_NEAR(s.sweep(), kPi / 2, 1e-9);
  }
  EXPECT_EQ(arcs, 4);
  // the offset's area: the rectangle, its sides pushed out, and a full circle of corners
  double len = 0;
  for (const Seg& s : r.segs) len += s.length();
  EXPECT_NEAR(len, 2 * (30 + 20) + 2 * kPi * 1.5, 1e-9);
  expect_matches_clipper(sq, 3, false);
  expect_matches_clipper(sq, 3, true);
}

TEST(Kerf, RoundedRectangleOuterAndHole) {
  expect_matches_clipper(rounded_rect(60, 40, 6), 2, false);
  expect_matches_clipper(rounded_rect(60, 40, 6), 2, true);
}

TEST(Kerf, BracketWithInnerFilletAndConcaveCorner) {
  // L shape: outer corner R8, inner fillet R5 (concave: it shrinks to R4 when the outline grows by 1)
  const std::vector<Seg> l{Seg::line({8, 0}, {50, 0}), Seg::line({50, 0}, {50, 16}), Seg::line({50, 16}, {21, 16}),
                           Seg::circle_arc({21, 21}, 5, 3 * kPi / 2, kPi), Seg::line({16, 21}, {16, 45}),
                           Seg::line({16, 45}, {0, 45}), Seg::line({0, 45}, {0, 8}),
                           Seg::circle_arc({8, 8}, 8, kPi, 3 * kPi / 2)};
  expect_matches_clipper(l, 2, false);
  expect_matches_clipper(l, 2, true);
  const Chain c = as_cut(l, false);
  const OffsetResult r = offset_left(c.segs, 1);
  bool fillet4 = false, corner9 = false;
  for (const Seg& s : r.segs) {
    if (s.kind != SegKind::arc) continue;
    fillet4 = fillet4 || (std::abs(s.radius() - 4) < 1e-9 && dist(s.c, {21, 21}) < 1e-9);
    corner9 = corner9 || (std::abs(s.radius() - 9) < 1e-9 && dist(s.c, {8, 8}) < 1e-9);
  }
  EXPECT_TRUE(fillet4);
  EXPECT_TRUE(corner9);
}

TEST(Kerf, StarWithSharpConcaveCorners) {
  std::vector<Seg> star;
  std::vector<Vec2> p;
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 ? 8 : 20, a = kPi / 2 + i * kPi / 5;
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  for (int i = 0; i < 10; ++i) star.push_back(Seg::line(p[std::size_t(i)], p[std::size_t((i + 1) % 10)]));
  expect_matches_clipper(star, 1.6, false);
  expect_matches_clipper(star, 1.6, true);
}

TEST(Kerf, ArcsTighterThanHalfTheKerfAreReported) {
  // a hole with corner radius 0.5: half a kerf of 2 removes the corner arcs (sharp corners remain)
  const Chain c = as_cut(rounded_rect(20, 10, 0.5), true);
  const OffsetResult r = offset_left(c.segs, 1);
  EXPECT_EQ(r.notes.size(), 4u);
  for (const std::string& n : r.notes) EXPECT_NE(n.find("tighter than half the kerf"), std::string::npos) << n;
  expect_matches_clipper(rounded_rect(20, 10, 0.5), 2, true, 0.01);
}

TEST(Kerf, HoleSmallerThanTheKerfCollapses) {
  const Chain c = as_cut({Seg::circle_arc({0, 0}, 0.8, 0, 2 * kPi)}, true);
  const OffsetResult r = offset_left(c.segs, 1);
  EXPECT_TRUE(r.segs.empty());
  ASSERT_FALSE(r.notes.empty());
  const Chain s = as_cut({Seg::line({0, 0}, {1.5, 0}), Seg::line({1.5, 0}, {1.5, 1.5}), Seg::line({1.5, 1.5}, {0, 1.5}),
                          Seg::line({0, 1.5}, {0, 0})},
                         true);
  const OffsetResult rs = offset_left(s.segs, 1);
  EXPECT_TRUE(rs.segs.empty());
  EXPECT_NE(rs.notes.back().find("narrower than the kerf"), std::string::npos);
}

TEST(Kerf, NarrowSlotInAnOutlineIsReported) {
  // a 1 mm wide, 10 mm deep notch in a 30 x 20 plate: a kerf of 2 cannot enter it
  const std::vector<Vec2> p{{0, 0}, {30, 0}, {30, 20}, {15.5, 20}, {15.5, 10}, {14.5, 10}, {14.5, 20}, {0, 20}};
  std::vector<Seg> s;
  for (std::size_t i = 0; i < p.size(); ++i) s.push_back(Seg::line(p[i], p[(i + 1) % p.size()]));
  const Chain c = as_cut(s, false);
  const OffsetResult r = offset_left(c.segs, 1);
  ASSERT_FALSE(r.notes.empty());
  bool said = false;
  for (const std::string& n : r.notes) said = said || n.find("narrower than the kerf") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(Kerf, ZeroKerfLeavesThePathAlone) {
  const Chain c = as_cut(rounded_rect(10, 10, 2), false);
  const OffsetResult r = offset_left(c.segs, 0);
  ASSERT_EQ(r.segs.size(), c.segs.size());
}

// SPDX-License-Identifier: MIT
// Chaining, hierarchy, transforms and normalization (host/cam/contour.h).
#include <gtest/gtest.h>

#include <cmath>

#include "cam/contour.h"

using namespace cpstep::cam;

namespace {
std::vector<Seg> square(double x, double y, double a) {
  return {Seg::line({x, y}, {x + a, y}), Seg::line({x + a, y}, {x + a, y + a}), Seg::line({x + a, y + a}, {x, y + a}),
          Seg::line({x, y + a}, {x, y})};
}
}  // namespace

TEST(Contour, LinesInMixedDirectionsChainIntoOneClosedContour) {
  // the seed's square (b-3): AB, then CB, DC and AD drawn against the direction of travel
  const Vec2 A{0, 0}, B{10, 0}, C{10, 10}, D{0, 10};
  auto chains = build_chains({Seg::line(A, B, 0), Seg::line(C, B, 1), Seg::line(D, C, 2), Seg::line(A, D, 3)}, 0.01);
  ASSERT_EQ(chains.size(), 1u);
  EXPECT_TRUE(chains[0].closed);
  EXPECT_TRUE(chains[0].simple);
  ASSERT_EQ(chains[0].segs.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(dist(chains[0].segs[i].b, chains[0].segs[(i + 1) % 4].a), 0.0);
  EXPECT_NEAR(chains[0].length(), 40, 1e-12);
}

TEST(Contour, ToleranceJoinsSmallGapsOnly) {
  std::vector<Seg> s = square(0, 0, 10);
  s[1].a = {10.004, 0.003};  // a gap of 0.005 mm
  EXPECT_EQ(build_chains(s, 0.01).size(), 1u);
  EXPECT_TRUE(build_chains(s, 0.01)[0].closed);
  s[1].a = {10.05, 0};  // 0.05 mm: not joined at 0.01
  auto open = build_chains(s, 0.01);
  ASSERT_EQ(open.size(), 1u);  // still one connected trail: the other three corners join
  EXPECT_FALSE(open[0].closed);
  EXPECT_TRUE(build_chains(s, 0.1)[0].closed);
}

TEST(Contour, HierarchyOuterHolesAndIsland) {
  std::vector<Seg> s = square(0, 0, 100);
  for (const Seg& q : square(10, 10, 40)) s.push_back(q);  // hole
  for (const Seg& q : square(20, 20, 10)) s.push_back(q);  // island inside the hole
  s.push_back(Seg::circle_arc({75, 75}, 10, 0, 2 * kPi));  // round hole
  auto chains = build_chains(s, 0.01);
  classify(chains, 0.01);
  ASSERT_EQ(chains.size(), 4u);
  int outers = 0, holes = 0, islands = 0;
  for (const Chain& c : chains) {
    const double w = c.box().width();
    if (std::abs(w - 100) < 1e-9) { EXPECT_EQ(c.depth, 0); EXPECT_FALSE(c.hole()); ++outers; }
    if (std::abs(w - 40) < 1e-9 || std::abs(w - 20) < 1e-9) {
      EXPECT_EQ(c.depth, 1);
      EXPECT_TRUE(c.hole());
      EXPECT_NEAR(chains[std::size_t(c.parent)].box().width(), 100, 1e-9);
      ++holes;
    }
    if (std::abs(w - 10) < 1e-9) {
      EXPECT_EQ(c.depth, 2);
      EXPECT_FALSE(c.hole());
      EXPECT_NEAR(chains[std::size_t(c.parent)].box().width(), 40, 1e-9);
      ++islands;
    }
  }
  EXPECT_EQ(outers, 1);
  EXPECT_EQ(holes, 2);
  EXPECT_EQ(islands, 1);
}

TEST(Contour, UnevenScaleTurnsACircleIntoAnEllipse) {
  Shape s;
  s.chains = build_chains({Seg::circle_arc({0, 0}, 5, 0, 2 * kPi)}, 0.01);
  const Shape e = transformed(s, Affine::scale(2, 1));
  const Seg& g = e.chains[0].segs[0];
  EXPECT_FALSE(g.is_circular());
  for (int i = 0; i < 24; ++i) {
    const Vec2 p = g.at(g.t0 + (g.t1 - g.t0) * i / 24);
    EXPECT_NEAR(p.x * p.x / 100 + p.y * p.y / 25, 1, 1e-12);
  }
  const Shape c = transformed(s, Affine::scale(3, 3) * Affine::rotate_deg(33));
  EXPECT_TRUE(c.chains[0].segs[0].is_circular());
  EXPECT_NEAR(c.chains[0].segs[0].radius(), 15, 1e-12);
}

TEST(Contour, RotateThenScaleIsNotScaleThenRotate) {
  // the seed: a 20 x 10 rectangle; rotate 90 degrees then scale x by 2 gives 20 x 20,
  // scale x by 2 then rotate gives 10 x 40
  Shape s;
  s.chains = build_chains({Seg::line({0, 0}, {20, 0}), Seg::line({20, 0}, {20, 10}), Seg::line({20, 10}, {0, 10}),
                           Seg::line({0, 10}, {0, 0})},
                          0.01);
  const Box rs = transformed(transformed(s, Affine::rotate_deg(90)), Affine::scale(2, 1)).box();
  const Box sr = transformed(transformed(s, Affine::scale(2, 1)), Affine::rotate_deg(90)).box();
  EXPECT_NEAR(rs.width(), 20, 1e-9);
  EXPECT_NEAR(rs.height(), 20, 1e-9);
  EXPECT_NEAR(sr.width(), 10, 1e-9);
  EXPECT_NEAR(sr.height(), 40, 1e-9);
}

TEST(Contour, NormalizedBoundingBoxStartsAtTheOrigin) {
  Shape s;
  s.chains = build_chains({Seg::circle_arc({50, -30}, 7, 0, 2 * kPi)}, 0.01);
  const Shape n = normalized(transformed(s, Affine::rotate_deg(17)));
  const Box b = n.box();
  EXPECT_NEAR(b.lo.x, 0, 1e-9);
  EXPECT_NEAR(b.lo.y, 0, 1e-9);
  EXPECT_NEAR(b.width(), 14, 1e-9);
  // an arc's box counts its extreme points, not just its ends
  Shape a;
  a.chains = build_chains({Seg::circle_arc({0, 0}, 10, -kPi / 4, kPi / 4)}, 0.01);
  EXPECT_NEAR(a.box().hi.x, 10, 1e-12);
}

TEST(Contour, OrientForCutOutersClockwiseHolesCounterClockwise) {
  std::vector<Seg> s = square(0, 0, 100);
  for (const Seg& q : square(10, 10, 40)) s.push_back(q);
  auto chains = build_chains(s, 0.01);
  classify(chains, 0.01);
  for (Chain& c : chains) {
    orient_for_cut(c);
    const double a = signed_area(c.polygon(0.01));
    if (c.hole()) EXPECT_GT(a, 0);
    else EXPECT_LT(a, 0);
  }
}

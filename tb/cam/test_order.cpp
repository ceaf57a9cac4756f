// SPDX-License-Identifier: MIT
// Cut order, start points, pierces and leads (host/cam/plan.h): the seed's worked
// examples by their stated answers, brute-force optima against 2-opt, and the
// lead and pierce rules.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "cam/contour.h"
#include "cam/plan.h"

using namespace cpstep::cam;

namespace {

Shape shape_of(const std::vector<Seg>& segs) {
  Shape s;
  s.chains = build_chains(segs, 0.01);
  classify(s.chains, 0.01);
  return s;
}

CutParams bare() {
  CutParams p;  // no kerf, no leads, no delays: the order alone
  return p;
}

Box no_sheet() { return Box{}; }

std::vector<Seg> square(Vec2 o, double a) {
  return {Seg::line(o, o + Vec2{a, 0}), Seg::line(o + Vec2{a, 0}, o + Vec2{a, a}), Seg::line(o + Vec2{a, a}, o + Vec2{0, a}),
          Seg::line(o + Vec2{0, a}, o)};
}

}  // namespace

TEST(Order, InnerCircleBeforeOuter) {
  // the seed's ring (a-7): the inner circle first, else the part falls out before its hole is cut
  const Shape ring = shape_of({Seg::circle_arc({0, 0}, 20, 0, 2 * kPi), Seg::circle_arc({0, 0}, 10, 0, 2 * kPi)});
  const CutPlan plan = plan_cuts({ring}, {21, 0}, bare(), no_sheet());  // the torch right next to the outer circle
  ASSERT_EQ(plan.cuts.size(), 2u);
  EXPECT_TRUE(plan.cuts[0].hole);
  EXPECT_NEAR(plan.cuts[0].path[0].radius(), 10, 1e-12);
  EXPECT_FALSE(plan.cuts[1].hole);
}

TEST(Order, SquareOfReversedLinesIsOneCutWithoutTravel) {
  // the seed's square (b-3): AB, CB, DC, AD as drawn would cost extra travel; chained, none
  const Vec2 A{0, 0}, B{10, 0}, C{10, 10}, D{0, 10};
  const Shape sq = shape_of({Seg::line(A, B), Seg::line(C, B), Seg::line(D, C), Seg::line(A, D)});
  const CutPlan plan = plan_cuts({sq}, A, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_EQ(plan.pierces, 1);
  EXPECT_EQ(plan.cuts[0].path.size(), 4u);
  EXPECT_NEAR(plan.rapid_mm, 0, 1e-12);
  EXPECT_NEAR(plan.cut_mm, 40, 1e-12);
}

TEST(Order, CircleTouchingTheLinesIsCutInOnePass) {
  // the seed's (a-4): line AB, a circle through B, line BC: starting the circle at B
  // needs no travel; starting it at D (opposite B) would cost 4R
  const double R = 5;
  const Vec2 A{-10, 0}, B{0, 0}, C{10, 0};
  const Shape s = shape_of({Seg::line(A, B), Seg::circle_arc({0, R}, R, 0, 2 * kPi), Seg::line(B, C)});
  ASSERT_EQ(s.chains.size(), 1u);
  const CutPlan plan = plan_cuts({s}, A, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_EQ(plan.cuts[0].path.size(), 3u);
  EXPECT_NEAR(plan.rapid_mm, 0, 1e-12);
  EXPECT_NEAR(plan.cut_mm, 20 + 2 * kPi * R, 1e-9);
}

TEST(Order, CircleStartsOnTheSideNearestTheTorch) {
  const Vec2 c{30, 40};
  const double R = 5;
  const Shape s = shape_of({Seg::circle_arc(c, R, 0, 2 * kPi)});
  const CutPlan plan = plan_cuts({s}, {0, 0}, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_NEAR(plan.rapid_mm, 50 - R, 1e-9);  // |P - c| - R
  EXPECT_NEAR(dist(plan.cuts[0].pierce, c * ((50 - R) / 50)), 0, 1e-9);
  // out and back from the torch: nearest start 2(|P-c| - R), opposite start 2(|P-c| + R): 4R more
  const std::vector<OrderElement> el{{plan.cuts[0].path, true}};
  EXPECT_NEAR(travel_of(el, {0}, {0, 0}), 50 - R, 1e-9);
}

TEST(Order, SplittingALineAtAJunctionRemovesTravel) {
  // the seed's (a-5): AB ends on CD at B; with CD split into BD and CB the cut is
  // AB, BD, arc DC, CB without moving between entities
  const Vec2 A{10, -8}, B{10, 0}, C{0, 0}, D{20, 0};
  const Shape s = shape_of({Seg::line(A, B), Seg::line(C, D), Seg::circle_arc({10, 0}, 10, 0, kPi)});
  ASSERT_EQ(s.chains.size(), 1u);
  const CutPlan plan = plan_cuts({s}, A, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_EQ(plan.pierces, 1);
  EXPECT_EQ(plan.cuts[0].path.size(), 4u);
  EXPECT_NEAR(plan.rapid_mm, 0, 1e-12);
  EXPECT_NEAR(dist(plan.cuts[0].path.front().a, A), 0, 1e-12);
  EXPECT_NEAR(dist(plan.cuts[0].path.back().b, B), 0, 1e-9);
  for (std::size_t i = 1; i < plan.cuts[0].path.size(); ++i)
    EXPECT_NEAR(dist(plan.cuts[0].path[i - 1].b, plan.cuts[0].path[i].a), 0, 1e-9);
}

TEST(Order, TwoTrianglesMergeIntoOneChainOfSixLines) {
  // the seed's (a-6): two triangles meeting at B: one chain, one pierce
  const Vec2 A{0, 0}, B{10, 5}, C{0, 10}, D{20, 0}, E{20, 10};
  const Shape s = shape_of({Seg::line(A, B), Seg::line(B, C), Seg::line(C, A), Seg::line(B, D), Seg::line(D, E),
                            Seg::line(E, B)});
  ASSERT_EQ(s.chains.size(), 1u);
  EXPECT_TRUE(s.chains[0].closed);
  EXPECT_FALSE(s.chains[0].simple);
  const CutPlan plan = plan_cuts({s}, A, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_EQ(plan.cuts[0].path.size(), 6u);
  EXPECT_EQ(plan.pierces, 1);
}

TEST(Order, FromPointNearDTheOrderIsCdBcAbDa) {
  // the seed's (b-7): square ABCD (counter-clockwise from A at the origin), torch at a near D:
  // the best order is CD, BC, AB, DA
  const Vec2 A{0, 0}, B{10, 0}, C{10, 10}, D{0, 10};
  const Shape s = shape_of({Seg::line(A, B, 0), Seg::line(B, C, 1), Seg::line(C, D, 2), Seg::line(D, A, 3)});
  const CutPlan plan = plan_cuts({s}, {-1, 11}, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  std::vector<int> src;
  for (const Seg& g : plan.cuts[0].path) src.push_back(g.src);
  EXPECT_EQ(src, (std::vector<int>{2, 1, 0, 3}));
  EXPECT_NEAR(dist(plan.cuts[0].pierce, D), 0, 1e-12);
  EXPECT_NEAR(plan.rapid_mm, std::sqrt(2.0), 1e-12);
}

TEST(Order, OpenChainIsReversedWhenItsOtherEndIsNearer) {
  const Shape s = shape_of({Seg::line({100, 0}, {5, 0})});
  const CutPlan plan = plan_cuts({s}, {0, 0}, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 1u);
  EXPECT_NEAR(dist(plan.cuts[0].pierce, {5, 0}), 0, 1e-12);
  EXPECT_NEAR(plan.rapid_mm, 5, 1e-12);
}

namespace {

// Travel to visit small circles in this order, computed here: the torch goes to each
// circle's nearest point and ends there.
double circles_travel(const std::vector<Vec2>& c, double r, const std::vector<int>& order, Vec2 pos) {
  double t = 0;
  for (int i : order) {
    const Vec2 d = c[std::size_t(i)] - pos;
    const double l = norm(d);
    t += l - r;
    pos = pos + d * ((l - r) / l);
  }
  return t;
}

}  // namespace

TEST(Order, TwoOptAgainstBruteForceOptimum) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(0, 100);
  const double r = 0.5;
  double sum_ratio = 0;
  const int trials = 25;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<Vec2> c;
    std::vector<OrderElement> els;
    for (int i = 0; i < 7; ++i) {
      c.push_back({u(rng), u(rng)});
      els.push_back({{Seg::circle_arc(c.back(), r, 0, 2 * kPi)}, true});
    }
    const Vec2 base{0, 0};
    std::vector<int> perm{0, 1, 2, 3, 4, 5, 6};
    double best = 1e300;
    do best = std::min(best, circles_travel(c, r, perm, base));
    while (std::next_permutation(perm.begin(), perm.end()));
    const std::vector<std::vector<int>> none(7);
    const auto nn = nearest_neighbour(els, none, base);
    const auto opt = order_elements(els, none, base, true);
    const double t_nn = circles_travel(c, r, nn, base), t_opt = circles_travel(c, r, opt, base);
    EXPECT_NEAR(travel_of(els, opt, base), t_opt, 1e-6);
    EXPECT_GE(t_opt, best - 1e-6);
    EXPECT_LE(t_opt, t_nn + 1e-9);        // 2-opt never worse than its start
    EXPECT_LE(t_opt, 1.15 * best);        // and within 15 % of the optimum on every case
    sum_ratio += t_opt / best;
  }
  EXPECT_LE(sum_ratio / trials, 1.03);    // within 3 % on average
}

TEST(Order, PrecedenceHoldsUnderTwoOpt) {
  // ten plates with a hole each, base point in the middle: every hole before its plate
  std::vector<Shape> parts;
  for (int i = 0; i < 10; ++i) {
    const Vec2 o{double(i % 5) * 30, double(i / 5) * 30};
    std::vector<Seg> s = square(o, 20);
    s.push_back(Seg::circle_arc(o + Vec2{10, 10}, 4, 0, 2 * kPi));
    parts.push_back(shape_of(s));
  }
  const CutPlan plan = plan_cuts(parts, {70, 25}, bare(), no_sheet());
  ASSERT_EQ(plan.cuts.size(), 20u);
  std::vector<bool> hole_done(10, false);
  for (const Cut& c : plan.cuts) {
    if (c.hole) hole_done[std::size_t(c.part)] = true;
    else EXPECT_TRUE(hole_done[std::size_t(c.part)]) << "plate " << c.part << " before its hole";
  }
}

TEST(Pierce, DelayOnlyAtTheStartOfEachChain) {
  // the seed's two nested squares: one pierce at the first point of each, none at the other corners
  std::vector<Seg> s = square({0, 0}, 40);
  for (const Seg& q : square({10, 10}, 20)) s.push_back(q);
  CutParams p = bare();
  p.pierce_s = 0.7;
  const CutPlan plan = plan_cuts({shape_of(s)}, {0, 0}, p, no_sheet());
  ASSERT_EQ(plan.cuts.size(), 2u);
  EXPECT_EQ(plan.pierces, 2);
  for (const Cut& c : plan.cuts) {
    EXPECT_DOUBLE_EQ(c.delay, 0.7);
    double len = 0;  // all four sides cut without stopping (the outer one starts mid-side, nearest the torch)
    for (const Seg& g : c.path) len += g.length();
    EXPECT_NEAR(len, c.hole ? 80 : 160, 1e-9);
    EXPECT_NEAR(dist(c.pierce, c.path.front().a), 0, 1e-12);
  }
}

TEST(Pierce, ShorterDelayNearTheSheetEdge) {
  std::vector<Shape> parts{shape_of(square({3, 50}, 10)), shape_of(square({50, 50}, 10))};
  CutParams p = bare();
  p.pierce_s = 0.8;
  p.pierce_edge_s = 0.3;
  p.edge_distance = 10;
  Box sheet;
  sheet.add({0, 0});
  sheet.add({200, 100});
  const CutPlan plan = plan_cuts(parts, {0, 55}, p, sheet);
  ASSERT_EQ(plan.cuts.size(), 2u);
  for (const Cut& c : plan.cuts) {
    const bool near_edge = c.pierce.x < 10;
    EXPECT_EQ(c.edge_pierce, near_edge);
    EXPECT_DOUBLE_EQ(c.delay, near_edge ? 0.3 : 0.8);
  }
}

TEST(Leads, OutsideTheOutlineInsideTheHoleFixedLength) {
  CutParams p = bare();
  p.lead_in = 3;
  p.lead_out = 2;
  for (double scale : {1.0, 2.0}) {
    // the seed's ring: the hole's lead inside it, the outline's outside; the same length at any scale
    const Shape ring = transformed(
        shape_of({Seg::circle_arc({0, 0}, 20, 0, 2 * kPi), Seg::circle_arc({0, 0}, 10, 0, 2 * kPi)}),
        Affine::scale(scale, scale));
    const CutPlan plan = plan_cuts({ring}, {-100, 0}, p, no_sheet());
    ASSERT_EQ(plan.cuts.size(), 2u);
    for (const Cut& c : plan.cuts) {
      ASSERT_TRUE(c.lead_in && c.lead_out);
      EXPECT_NEAR(c.lead_in->length(), 3, 1e-12);
      EXPECT_NEAR(c.lead_out->length(), 2, 1e-12);
      const double r = (c.hole ? 10 : 20) * scale;
      if (c.hole) {
        EXPECT_LT(norm(c.pierce), r - 1);
        EXPECT_LT(norm(c.lead_out->b), r - 1);
      } else {
        EXPECT_GT(norm(c.pierce), r + 1);
        EXPECT_GT(norm(c.lead_out->b), r + 1);
      }
      EXPECT_NEAR(dist(c.lead_in->b, c.path.front().a), 0, 1e-12);
    }
  }
}

TEST(Leads, ShortenedWhenTheHoleIsSmall) {
  CutParams p = bare();
  p.lead_in = 3;
  const Shape s = shape_of({Seg::circle_arc({0, 0}, 20, 0, 2 * kPi), Seg::circle_arc({0, 0}, 2, 0, 2 * kPi)});
  const CutPlan plan = plan_cuts({s}, {0, 0}, p, no_sheet());
  ASSERT_TRUE(plan.cuts[0].hole);
  ASSERT_TRUE(plan.cuts[0].lead_in);
  EXPECT_LT(plan.cuts[0].lead_in->length(), 3);
  EXPECT_LT(norm(plan.cuts[0].pierce), 2);
  EXPECT_FALSE(plan.warnings.empty());
}

TEST(Leads, MoveAndRotateWithThePart) {
  std::vector<Seg> s = square({0, 0}, 30);
  s.push_back(Seg::circle_arc({10, 12}, 4, 0, 2 * kPi));
  const Shape part = shape_of(s);
  CutParams p = bare();
  p.lead_in = 3;
  p.lead_out = 2;
  p.kerf = 1.5;
  const Vec2 base{-7, 4};
  const CutPlan a = plan_cuts({part}, base, p, no_sheet());
  const Affine m = Affine::translate(120, 35) * Affine::rotate_deg(37);
  const CutPlan b = plan_cuts({transformed(part, m)}, m.apply(base), p, no_sheet());
  ASSERT_EQ(a.cuts.size(), b.cuts.size());
  for (std::size_t i = 0; i < a.cuts.size(); ++i) {
    EXPECT_NEAR(dist(m.apply(a.cuts[i].pierce), b.cuts[i].pierce), 0, 1e-6);
    ASSERT_TRUE(a.cuts[i].lead_in && b.cuts[i].lead_in);
    EXPECT_NEAR(dist(m.apply(a.cuts[i].lead_in->b), b.cuts[i].lead_in->b), 0, 1e-6);
    EXPECT_NEAR(b.cuts[i].lead_in->length(), 3, 1e-9);
  }
  EXPECT_NEAR(a.rapid_mm, b.rapid_mm, 1e-6);
}

// SPDX-License-Identifier: MIT
// The sheet file, the seed's sheet rules, regular arrays with their traversal
// orders, and nesting (host/cam/sheet.h).
#include <gtest/gtest.h>
#include <polyclipping/clipper.hpp>

#include <cmath>

#include "cam/sheet.h"

using namespace cpstep::cam;

namespace {

const char* kChart = R"(
[[chart]]
thickness = 3
kerf = 1.5
pierce_s = 0.5
pierce_edge_s = 0.2
feed_mm_min = 1800
)";

SheetResult parse(const std::string& body) { return parse_sheet(body + kChart, "s.toml"); }

Shape rect_shape(double w, double h) {
  Shape s;
  s.file = "rect.dxf";
  s.chains = build_chains({Seg::line({0, 0}, {w, 0}), Seg::line({w, 0}, {w, h}), Seg::line({w, h}, {0, h}),
                           Seg::line({0, h}, {0, 0})},
                          0.01);
  classify(s.chains, 0.01);
  return s;
}

// isosceles: base a, apex a above the base's middle
Shape triangle_shape(double a) {
  Shape s;
  s.file = "tri.dxf";
  s.chains = build_chains({Seg::line({0, 0}, {a, 0}), Seg::line({a, 0}, {a / 2, a}), Seg::line({a / 2, a}, {0, 0})}, 0.01);
  classify(s.chains, 0.01);
  return s;
}

SheetConfig config(const std::string& body) {
  const SheetResult r = parse(body);
  EXPECT_TRUE(r.config) << (r.errors.empty() ? "" : r.errors.front());
  return r.config ? *r.config : SheetConfig{};
}

}  // namespace

TEST(SheetFile, ReadsEverything) {
  const SheetConfig c = config(R"(
[sheet]
width = 300
height = 200
thickness = 3
material = "mild steel"
margins = { left = 10, right = 5, top = 8, bottom = 12 }
invalid = [ { x = 100, y = 50, width = 30, height = 20 } ]
[start]
point = "corner"
corner = "top-right"
[layout]
mode = "array"
spacing_x = -2.5
spacing_y = 4
rotate = "alternate-x"
order = "y-zigzag"
[leads]
lead_in = 4
lead_out = 1.5
edge_distance = 12
)");
  EXPECT_EQ(c.sheet.width, 300);
  EXPECT_EQ(c.sheet.margin_right, 5);
  EXPECT_EQ(c.sheet.invalid.size(), 1u);
  EXPECT_EQ(c.layout.corner, Corner::top_right);
  EXPECT_EQ(c.layout.spacing_x, -2.5);
  EXPECT_EQ(c.layout.order, "y-zigzag");
  EXPECT_EQ(c.chart.kerf, 1.5);
  EXPECT_EQ(c.chart.feed_mm_min, 1800);
  EXPECT_EQ(c.lead_in, 4);
  const Box u = c.sheet.usable();
  EXPECT_EQ(u.lo.x, 10);
  EXPECT_EQ(u.lo.y, 12);
  EXPECT_EQ(u.hi.x, 295);
  EXPECT_EQ(u.hi.y, 192);
}

TEST(SheetFile, ErrorsSayFileLineAndColumn) {
  const SheetResult syntax = parse_sheet("[sheet]\nwidth = = 3\n", "bad.toml");
  ASSERT_EQ(syntax.errors.size(), 1u);
  EXPECT_EQ(syntax.errors[0].rfind("bad.toml:2:", 0), 0u) << syntax.errors[0];
  const SheetResult typo = parse("[sheet]\nwidth = 100\nheight = 100\nthickness = 3\nwidht = 5\n");
  ASSERT_FALSE(typo.errors.empty());
  EXPECT_EQ(typo.errors[0].rfind("s.toml:5:1: sheet.widht: unknown key", 0), 0u) << typo.errors[0];
  const SheetResult thick = parse("[sheet]\nwidth = 100\nheight = 100\nthickness = 4\n");
  ASSERT_FALSE(thick.errors.empty());
  EXPECT_EQ(thick.errors[0].rfind("s.toml:4:13: sheet.thickness: 4 mm is not in the cut chart (thicknesses: 3)", 0), 0u)
      << thick.errors[0];
  const SheetResult type = parse("[sheet]\nwidth = \"wide\"\nheight = 100\nthickness = 3\n");
  ASSERT_FALSE(type.errors.empty());
  EXPECT_EQ(type.errors[0].rfind("s.toml:2:9: sheet.width: must be a number", 0), 0u) << type.errors[0];
}

TEST(SheetRules, MarginsNotNegativeAndSmallerThanTheSheet) {
  Sheet s;
  s.width = 100;
  s.height = 50;
  EXPECT_TRUE(check_sheet(s).empty());
  s.margin_left = -1;
  ASSERT_EQ(check_sheet(s).size(), 1u);
  EXPECT_NE(check_sheet(s)[0].find("left margin is negative"), std::string::npos);
  s.margin_left = 60;
  s.margin_right = 40;  // together 100: nothing left
  ASSERT_EQ(check_sheet(s).size(), 1u);
  EXPECT_NE(check_sheet(s)[0].find("left and right margins"), std::string::npos);
  s.margin_right = 39;
  EXPECT_TRUE(check_sheet(s).empty());
  s.margin_top = 30;
  s.margin_bottom = 20;
  EXPECT_NE(check_sheet(s)[0].find("top and bottom"), std::string::npos);
}

TEST(SheetRules, InvalidRegionInsideAnotherIsRefused) {
  // the seed's figure: regions 1, 2, 3 stand; region 4 inside region 3 adds nothing
  Sheet s;
  s.width = 300;
  s.height = 200;
  auto box = [](double x, double y, double w, double h) { Box b; b.add({x, y}); b.add({x + w, y + h}); return b; };
  s.invalid = {box(10, 10, 40, 30), box(100, 20, 50, 60), box(200, 100, 80, 80)};
  EXPECT_TRUE(check_sheet(s).empty());
  s.invalid.push_back(box(120, 40, 20, 20));  // partly outside none: inside region 2
  const auto e = check_sheet(s);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("invalid region 4 lies inside invalid region 2"), std::string::npos) << e[0];
  s.invalid.back() = box(140, 40, 20, 20);  // sticks out of region 2: kept
  EXPECT_TRUE(check_sheet(s).empty());
  const SheetResult r = parse("[sheet]\nwidth = 100\nheight = 100\nthickness = 3\n"
                              "invalid = [ { x = 10, y = 10, width = 50, height = 50 }, { x = 20, y = 20, width = 5, height = 5 } ]\n");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_NE(r.errors[0].find("invalid region 2 lies inside invalid region 1"), std::string::npos);
}

TEST(Traversal, TheEightRegularOrders) {
  using V = std::vector<std::pair<int, int>>;
  EXPECT_EQ(traversal(3, 2, "x-oneway", Corner::bottom_left), (V{{0, 0}, {1, 0}, {2, 0}, {0, 1}, {1, 1}, {2, 1}}));
  EXPECT_EQ(traversal(3, 2, "x-zigzag", Corner::bottom_left), (V{{0, 0}, {1, 0}, {2, 0}, {2, 1}, {1, 1}, {0, 1}}));
  EXPECT_EQ(traversal(3, 2, "y-oneway", Corner::bottom_left), (V{{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}, {2, 1}}));
  EXPECT_EQ(traversal(3, 2, "y-zigzag", Corner::bottom_left), (V{{0, 0}, {0, 1}, {1, 1}, {1, 0}, {2, 0}, {2, 1}}));
  // from the other corners the grid is mirrored: the first part sits at that corner
  // (half the kerf, 0.75 mm, in from the sheet's edge: 5 x 3 cells of 20 mm fit in 101.5 x 61.5)
  SheetConfig c = config("[sheet]\nwidth = 101.5\nheight = 61.5\nthickness = 3\n");
  const std::vector<Shape> m{rect_shape(20, 20)};
  for (Corner k : {Corner::bottom_left, Corner::bottom_right, Corner::top_left, Corner::top_right})
    for (const char* order : {"x-oneway", "x-zigzag", "y-oneway", "y-zigzag"}) {
      c.layout.corner = k;
      c.layout.order = order;
      const LayoutResult r = layout_parts(m, c);
      ASSERT_EQ(r.placed.size(), 15u);  // 5 x 3 cells of 20 mm
      const bool right = k == Corner::bottom_right || k == Corner::top_right;
      const bool top = k == Corner::top_left || k == Corner::top_right;
      EXPECT_NEAR(r.placed[0].x, right ? 80.75 : 0.75, 1e-9);
      EXPECT_NEAR(r.placed[0].y, top ? 40.75 : 0.75, 1e-9);
      // the second part: one pitch along the traversal's axis, away from the corner
      const bool along_x = order[0] == 'x';
      EXPECT_NEAR(r.placed[1].x, along_x ? (right ? 60.75 : 20.75) : (right ? 80.75 : 0.75), 1e-9);
      EXPECT_NEAR(r.placed[1].y, along_x ? (top ? 40.75 : 0.75) : 20.75, 1e-9);
    }
}

TEST(Array, SpacingAndCountsAndMargins) {
  SheetConfig c = config("[sheet]\nwidth = 200\nheight = 100\nthickness = 3\nmargins = { left = 10, right = 10, top = 5, bottom = 5 }\n"
                         "[layout]\nspacing_x = 5\nspacing_y = 10\norder = \"x-oneway\"\n");
  const LayoutResult r = layout_parts({rect_shape(30, 20)}, c);
  // usable 180 x 90, 0.75 mm (half the kerf) in: columns at 10.75, 45.75, ... 150.75; rows at 5.75, 35.75, 65.75
  ASSERT_EQ(r.placed.size(), 15u);
  EXPECT_NEAR(r.placed[4].x, 150.75, 1e-9);
  EXPECT_NEAR(r.placed[5].y, 35.75, 1e-9);
  EXPECT_NEAR(r.use_percent, 100.0 * 15 * 600 / (180 * 90), 1e-9);
  c.layout.count = 20;
  const LayoutResult too_many = layout_parts({rect_shape(30, 20)}, c);
  ASSERT_FALSE(too_many.errors.empty());
  EXPECT_NE(too_many.errors[0].find("20 parts asked, only 15 fit"), std::string::npos) << too_many.errors[0];
}

TEST(Array, NegativeSpacingInterlocksTurnedTriangles) {
  // triangles of base 20 and height 20: every other one turned 180 degrees (apex down)
  // fits between its neighbours with a pitch of 12 mm (spacing -8): sloping sides
  // 2 * 2/sqrt(5) = 1.79 mm apart (> kerf 1); the unturned ones, 24 mm apart, 4 mm apart
  SheetConfig c = config("[sheet]\nwidth = 100\nheight = 30\nthickness = 3\n[layout]\nspacing_x = -8\n"
                         "rotate = \"alternate-x\"\norder = \"x-oneway\"\n");
  const std::vector<Shape> m{triangle_shape(20)};
  const LayoutResult r = layout_parts(m, c);
  ASSERT_TRUE(r.errors.empty());
  ASSERT_GE(r.placed.size(), 4u);
  EXPECT_EQ(r.placed[1].theta_deg, 180);
  std::vector<Shape> placed;
  std::vector<std::string> names;
  for (const Placed& p : r.placed) {
    placed.push_back(transformed(m[0], p.transform()));
    names.push_back("p");
  }
  // the second triangle is the first turned about its box centre and moved one pitch
  const Box b1 = placed[1].box();
  EXPECT_NEAR(b1.lo.x, 0.75 + 12, 1e-9);
  EXPECT_NEAR(b1.hi.x, 0.75 + 32, 1e-9);
  EXPECT_NEAR(placed[1].chains[0].segs[0].a.y, 20.75, 1e-9);  // turned: its base on top
  for (const std::string& e : check_fit(placed, c.sheet, 1.0, names)) ADD_FAILURE() << e;
  EXPECT_FALSE(check_fit(placed, c.sheet, 3.0, names).empty());  // 1.79 mm < 3 mm of kerf
  c.layout.rotate = "none";
  const LayoutResult straight = layout_parts(m, c);
  placed.clear();
  for (const Placed& p : straight.placed) placed.push_back(transformed(m[0], p.transform()));
  names.assign(placed.size(), "p");
  EXPECT_FALSE(check_fit(placed, c.sheet, 1.0, names).empty());  // unturned, they overlap
}

TEST(Array, CellsOnInvalidRegionsStayEmpty) {
  SheetConfig c = config("[sheet]\nwidth = 101.5\nheight = 21.5\nthickness = 3\n"
                         "invalid = [ { x = 45, y = 0, width = 10, height = 20 } ]\n[layout]\norder = \"x-oneway\"\n");
  const LayoutResult r = layout_parts({rect_shape(20, 20)}, c);
  // cells at 0.75, 20.75, 40.75, 60.75, 80.75: the one at 40.75 touches the region
  ASSERT_EQ(r.placed.size(), 4u);
  for (const Placed& p : r.placed) EXPECT_NE(p.x, 40.75);
}

TEST(Fit, PartsOutsideTheMarginsOrOnInvalidRegionsAreRefused) {
  Sheet s;
  s.width = 100;
  s.height = 100;
  s.margin_left = 10;
  Box iv;
  iv.add({50, 50});
  iv.add({60, 60});
  s.invalid.push_back(iv);
  const Shape r = rect_shape(20, 20);
  const auto e = check_fit({transformed(r, Affine::translate(5, 20)), transformed(r, Affine::translate(45, 45))}, s, 1,
                           {"A", "B"});
  ASSERT_EQ(e.size(), 2u);
  EXPECT_NE(e[0].find("A does not fit inside the margins"), std::string::npos) << e[0];
  EXPECT_NE(e[1].find("B lies on invalid region 1"), std::string::npos) << e[1];
}

TEST(Nest, EveryPartInsideNoOverlapsAndSheetUse) {
  SheetConfig c = config("[sheet]\nwidth = 160\nheight = 100\nthickness = 3\nmargins = { left = 5, right = 5, top = 5, bottom = 5 }\n"
                         "invalid = [ { x = 70, y = 40, width = 20, height = 20 } ]\n"
                         "[layout]\nmode = \"nest\"\ncount = 5\ngap = 1\nrotations = [0, 90]\n");
  Shape disc;
  disc.file = "disc.dxf";
  disc.chains = build_chains({Seg::circle_arc({12, 12}, 12, 0, 2 * kPi)}, 0.01);
  classify(disc.chains, 0.01);
  const std::vector<Shape> masters{rect_shape(40, 20), disc};
  const LayoutResult r = layout_parts(masters, c);
  ASSERT_TRUE(r.errors.empty()) << r.errors.front();
  ASSERT_EQ(r.placed.size(), 10u);
  // checked here with clipper on the placed outlines widened by half the kerf
  const double k = 1e4;
  std::vector<ClipperLib::Paths> outl;
  for (const Placed& p : r.placed) {
    const Shape s = transformed(masters[std::size_t(p.master)], p.transform());
    const Box b = s.box();
    EXPECT_GE(b.lo.x, 5 + 0.75 - 1e-6);
    EXPECT_GE(b.lo.y, 5 + 0.75 - 1e-6);
    EXPECT_LE(b.hi.x, 155 - 0.75 + 1e-6);
    EXPECT_LE(b.hi.y, 95 - 0.75 + 1e-6);
    ClipperLib::Path path;
    for (Vec2 v : s.chains[0].polygon(0.01)) path.push_back({ClipperLib::cInt(v.x * k), ClipperLib::cInt(v.y * k)});
    ClipperLib::ClipperOffset off;
    off.AddPath(path, ClipperLib::jtRound, ClipperLib::etClosedPolygon);
    ClipperLib::Paths w;
    off.Execute(w, 0.75 * k);
    outl.push_back(w);
  }
  ClipperLib::Path inv{{ClipperLib::cInt(70 * k), ClipperLib::cInt(40 * k)}, {ClipperLib::cInt(90 * k), ClipperLib::cInt(40 * k)},
                       {ClipperLib::cInt(90 * k), ClipperLib::cInt(60 * k)}, {ClipperLib::cInt(70 * k), ClipperLib::cInt(60 * k)}};
  for (std::size_t i = 0; i < outl.size(); ++i) {
    for (std::size_t j = i + 1; j < outl.size(); ++j) {
      ClipperLib::Clipper cl;
      cl.AddPaths(outl[i], ClipperLib::ptSubject, true);
      cl.AddPaths(outl[j], ClipperLib::ptClip, true);
      ClipperLib::Paths out;
      cl.Execute(ClipperLib::ctIntersection, out, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
      double a = 0;
      for (const auto& p : out) a += std::abs(ClipperLib::Area(p));
      EXPECT_LT(a / (k * k), 1e-3) << i << " overlaps " << j;
    }
    ClipperLib::Clipper cl;
    cl.AddPaths(outl[i], ClipperLib::ptSubject, true);
    cl.AddPath(inv, ClipperLib::ptClip, true);
    ClipperLib::Paths out;
    cl.Execute(ClipperLib::ctIntersection, out, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
    EXPECT_TRUE(out.empty()) << i << " lies on the invalid region";
  }
  const double parts = 5 * 800 + 5 * kPi * 144;
  EXPECT_NEAR(r.use_percent, 100 * parts / (150 * 90 - 400), 0.05);
}

TEST(Nest, TooManyPartsAreRefused) {
  SheetConfig c = config("[sheet]\nwidth = 50\nheight = 50\nthickness = 3\n[layout]\nmode = \"nest\"\ncount = 5\n");
  const LayoutResult r = layout_parts({rect_shape(30, 20)}, c);
  ASSERT_FALSE(r.errors.empty());
  EXPECT_NE(r.errors[0].find("do not fit"), std::string::npos) << r.errors[0];
}

TEST(Start, CornerOrFirstPartCentre) {
  SheetConfig c = config("[sheet]\nwidth = 100\nheight = 60\nthickness = 3\n[start]\ncorner = \"top-right\"\n");
  const std::vector<Shape> placed{transformed(rect_shape(10, 20), Affine::translate(30, 5))};
  EXPECT_EQ(start_point(c, placed), (Vec2{100, 60}));
  c.layout.start = StartPoint::first_part_centre;
  EXPECT_EQ(start_point(c, placed), (Vec2{35, 15}));
}

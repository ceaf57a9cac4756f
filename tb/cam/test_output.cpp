// SPDX-License-Identifier: MIT
// The G-code the CAM writes, read back by cpstep's own G-code reader (host/plan),
// the SVG preview, and `cpstep cam` end to end (run_cam): examples, refusals with
// nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cam/contour.h"
#include "cam/output.h"
#include "cam/plan.h"
#include "cli/cam_command.h"
#include "dxf_text.h"
#include "plan/gcode.h"

using namespace cpstep;
using namespace cpstep::cam;
namespace fs = std::filesystem;

namespace {

Shape plate() {
  // a 40 x 30 plate with rounded corners, a round hole and an elongated hole
  std::vector<Seg> s{Seg::line({5, 0}, {35, 0}), Seg::circle_arc({35, 5}, 5, -kPi / 2, 0), Seg::line({40, 5}, {40, 25}),
                     Seg::circle_arc({35, 25}, 5, 0, kPi / 2), Seg::line({35, 30}, {5, 30}),
                     Seg::circle_arc({5, 25}, 5, kPi / 2, kPi), Seg::line({0, 25}, {0, 5}),
                     Seg::circle_arc({5, 5}, 5, kPi, 3 * kPi / 2), Seg::circle_arc({12, 15}, 4, 0, 2 * kPi),
                     Seg::conic_arc({28, 15}, {6, 0}, {0, 3}, 0, 2 * kPi)};
  Shape sh;
  sh.chains = build_chains(s, 0.01);
  classify(sh.chains, 0.01);
  return sh;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

}  // namespace

TEST(Gcode, ReadBackByThePlannersReader) {
  CutParams p;
  p.kerf = 1.5;
  p.lead_in = 3;
  p.lead_out = 2;
  p.pierce_s = 0.5;
  const std::vector<Shape> parts{transformed(plate(), Affine::translate(20, 20)),
                                 transformed(plate(), Affine::translate(70, 20) * Affine::rotate_deg(30))};
  const CutPlan plan = plan_cuts(parts, {0, 0}, p, Box{});
  ASSERT_EQ(plan.cuts.size(), 6u);
  GcodeInfo gi;
  gi.feed_mm_min = 1800;
  const std::string text = write_gcode(plan, gi);
  const auto job = plan::parse_gcode(text, "cam.ngc");
  ASSERT_TRUE(job.ok()) << (job.errors.empty() ? "" : job.errors.front().str());
  double rapid = 0, feed_len = 0, dwell = 0;
  int dwells = 0, arcs = 0;
  for (const plan::MotionBlock& b : job->blocks) {
    const double dx = b.end[0] - b.start[0], dy = b.end[1] - b.start[1];
    switch (b.kind) {
      case plan::MotionKind::rapid:
        rapid += std::hypot(dx, dy);
        EXPECT_FALSE(b.spindle_on);
        break;
      case plan::MotionKind::linear:
        feed_len += std::hypot(dx, dy);
        EXPECT_TRUE(b.spindle_on);
        EXPECT_NEAR(b.feed, 30, 1e-9);  // 1800 mm/min
        break;
      case plan::MotionKind::arc_cw:
      case plan::MotionKind::arc_ccw: {
        ++arcs;
        EXPECT_TRUE(b.spindle_on);
        const double r0 = std::hypot(b.start[0] - b.center_x, b.start[1] - b.center_y);
        const double r1 = std::hypot(b.end[0] - b.center_x, b.end[1] - b.center_y);
        EXPECT_NEAR(r0, r1, 2e-4);
        double a0 = std::atan2(b.start[1] - b.center_y, b.start[0] - b.center_x);
        double a1 = std::atan2(b.end[1] - b.center_y, b.end[0] - b.center_x);
        double sweep = b.kind == plan::MotionKind::arc_ccw ? a1 - a0 : a0 - a1;
        while (sweep <= 1e-9) sweep += 2 * kPi;
        feed_len += r0 * sweep;
        break;
      }
      case plan::MotionKind::dwell:
        ++dwells;
        dwell += b.dwell_s;
        EXPECT_TRUE(b.spindle_on);  // the pierce: torch on, not moving
        break;
      case plan::MotionKind::nurbs:
        ADD_FAILURE() << "a NURBS block at line " << b.loc.line << ": the CAM writes lines and arcs only";
        break;
    }
  }
  EXPECT_EQ(dwells, 6);
  EXPECT_NEAR(dwell, 3.0, 1e-9);
  EXPECT_GT(arcs, 6);                                // arcs stay arcs (the ellipse as arcs too)
  EXPECT_NEAR(rapid, plan.rapid_mm, 1e-3);
  EXPECT_NEAR(feed_len, plan.cut_mm, 2e-3);
  // M3 then the pierce, every time
  EXPECT_EQ(count(text, "M3\nG4 P0.500\n"), 6);
  EXPECT_EQ(count(text, "M5\n"), 6);
}

TEST(Svg, SheetPartsLeadsPiercesNumberedAndRapids) {
  CutParams p;
  p.lead_in = 3;
  const CutPlan plan = plan_cuts({transformed(plate(), Affine::translate(20, 20))}, {0, 0}, p, Box{});
  Sheet s;
  s.width = 100;
  s.height = 80;
  s.margin_left = 5;
  Box iv;
  iv.add({80, 60});
  iv.add({90, 70});
  s.invalid.push_back(iv);
  const std::string svg = write_svg(plan, s);
  EXPECT_EQ(count(svg, "<circle class=\"pierce\""), 3);
  for (int i = 1; i <= 3; ++i) EXPECT_NE(svg.find(">" + std::to_string(i) + "</text>"), std::string::npos);
  EXPECT_EQ(count(svg, "class=\"invalid\""), 1 + 0);
  EXPECT_NE(svg.find("class=\"rapid\" d=\"M"), std::string::npos);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_NE(svg.find("class=\"lead\" d=\"M"), std::string::npos);
  EXPECT_NE(svg.find(" A4.000,4.000 "), std::string::npos);  // the round hole as SVG arcs
}

namespace {
const std::string kExamples = CPSTEP_EXAMPLES_DIR "/plasma";
}

TEST(CamCommand, ExampleArrayWritesJobAndPreview) {
  const auto dir = camtest::temp_dir("cli");
  cli::CamOptions o;
  o.parts = {kExamples + "/flange.dxf"};
  o.sheet = kExamples + "/sheet.toml";
  o.out = (dir / "job.ngc").string();
  o.svg = (dir / "job.svg").string();
  o.quiet = true;
  ASSERT_EQ(cli::run_cam(o), 0);
  const std::string text = slurp(o.out);
  const auto job = plan::parse_gcode(text, o.out);
  ASSERT_TRUE(job.ok()) << (job.errors.empty() ? "" : job.errors.front().str());
  // 300 x 200 with 10 mm margins, 0.75 mm (half the kerf) in: 278.5 x 178.5 for 60 x 40
  // flanges every 66 x 46 mm: 4 x 4 cells at x 10.75, 76.75, 142.75, 208.75 and y 10.75,
  // 56.75, 102.75, 148.75. The clamp (x 0-12, y 90-110) takes column 0 rows 1 and 2; the
  // rusty patch (x 200-240, y 130-160) columns 2 and 3 of rows 2 and 3: 10 flanges, 6
  // contours each (outline, slot, 4 bolt holes)
  EXPECT_EQ(count(text, "M3\n"), 60);
  EXPECT_EQ(count(slurp(o.svg), "<circle class=\"pierce\""), 60);
}

TEST(CamCommand, ExampleNestWithEveryPart) {
  const auto dir = camtest::temp_dir("cli");
  cli::CamOptions o;
  o.parts = {kExamples + "/flange.dxf", kExamples + "/bracket.dxf", kExamples + "/wave.dxf"};
  o.sheet = kExamples + "/nest.toml";
  o.out = (dir / "nest.ngc").string();
  o.quiet = true;
  o.count = 1;
  ASSERT_EQ(cli::run_cam(o), 0);
  const auto job = plan::parse_gcode(slurp(o.out), o.out);
  ASSERT_TRUE(job.ok());
}

TEST(CamCommand, BadDxfRefusedNothingWritten) {
  const auto dir = camtest::temp_dir("cli");
  camtest::DxfText d;
  d.line(0, 0, 10, 0);
  const std::string h = d.arc(5, 5, -2, 0, 90);
  const std::string path = camtest::write(dir / "bad.dxf", d.text());
  cli::CamOptions o;
  o.parts = {path};
  o.sheet = kExamples + "/sheet.toml";
  o.out = (dir / "never.ngc").string();
  o.svg = (dir / "never.svg").string();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_cam(o), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(path + ":" + std::to_string(d.line_of(h)) + ": ARC handle " + h), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(o.out));
  EXPECT_FALSE(fs::exists(o.svg));
}

TEST(CamCommand, BadSheetRefusedWithLineAndColumn) {
  const auto dir = camtest::temp_dir("cli");
  const std::string sheet = camtest::write(dir / "bad.toml", "[sheet]\nwidth = 100\nheight = 100\nthickness = 3\n"
                                                             "margins = { left = -5 }\n[[chart]]\nthickness = 3\nkerf = 1\n"
                                                             "pierce_s = 0.5\nfeed_mm_min = 1000\nspeed = 3\n");
  cli::CamOptions o;
  o.parts = {kExamples + "/flange.dxf"};
  o.sheet = sheet;
  o.out = (dir / "never.ngc").string();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_cam(o), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(sheet + ":11:1: chart.speed: unknown key"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(o.out));
}

TEST(CamCommand, PartsThatDoNotFitAreRefused) {
  const auto dir = camtest::temp_dir("cli");
  cli::CamOptions o;
  o.parts = {kExamples + "/flange.dxf"};
  o.sheet = kExamples + "/sheet.toml";
  o.out = (dir / "never.ngc").string();
  o.count = 50;
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_cam(o), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("50 parts asked, only 10 fit"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(o.out));
  o.count = 1;
  o.transforms = {"scale:6"};  // 360 mm wide: larger than the sheet
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_cam(o), 2);
  EXPECT_FALSE(fs::exists(o.out));
  testing::internal::GetCapturedStderr();
}

TEST(CamCommand, TransformsInOrderAndRunNeedsTheCard) {
  const auto dir = camtest::temp_dir("cli");
  cli::CamOptions o;
  o.parts = {kExamples + "/tab.dxf"};
  o.sheet = kExamples + "/small.toml";
  o.out = (dir / "t.ngc").string();
  o.quiet = true;
  o.transforms = {"rotate:90", "scale:1:0.5"};  // 18 x 12 -> 12 x 18 -> 12 x 9
  EXPECT_EQ(cli::run_cam(o), 0);
  o.run = true;
  o.machine = CPSTEP_EXAMPLES_DIR "/machines/seed002.toml";
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli::run_cam(o), 2);  // no runner given: refused
  testing::internal::GetCapturedStderr();
  std::string ran;
  EXPECT_EQ(cli::run_cam(o, [&](const cli::CamOptions&, const std::string& job) { ran = job; return 0; }), 0);
  EXPECT_EQ(ran, o.out);
}

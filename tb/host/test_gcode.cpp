#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "plan/gcode.h"

using namespace cpstep::plan;

namespace {

Result<Job> parse(const std::string& s) { return parse_gcode(s, "job.ngc"); }

const Job& ok(const Result<Job>& r) {
    EXPECT_TRUE(r.ok()) << join(r.errors);
    return *r;
}

}  // namespace

TEST(Gcode, LinearMovesModalState) {
    auto r = parse(
        "%\n"
        "(header comment) N10 G21 G90 G17 G40 G49 G80 G54 G94 G64 P0.01\n"
        "T1 M6 ; tool change is ignored\n"
        "S12000 M3 M8\n"
        "G0 X10 Y20 Z5\n"
        "G1 Z-1 F600\n"
        "X30\n"
        "G91 Y5 A2\n"
        "G20 G1 X1 F60\n"
        "M5 M9\n"
        "M30\n"
        "%\n");
    const Job& j = ok(r);
    ASSERT_EQ(j.blocks.size(), 5u);
    const auto& b0 = j.blocks[0];
    EXPECT_EQ(b0.kind, MotionKind::rapid);
    EXPECT_EQ(b0.loc, (SourceLoc{5, 1}));
    EXPECT_EQ(b0.start, (PerAxis<double>{0, 0, 0, 0}));
    EXPECT_EQ(b0.end, (PerAxis<double>{10, 20, 5, 0}));
    EXPECT_EQ(b0.feed, 0);
    EXPECT_TRUE(b0.spindle_on);
    EXPECT_EQ(b0.spindle_speed, 12000);
    EXPECT_EQ(j.blocks[1].kind, MotionKind::linear);
    EXPECT_DOUBLE_EQ(j.blocks[1].feed, 10.0);  // 600 mm/min
    EXPECT_EQ(j.blocks[1].end, (PerAxis<double>{10, 20, -1, 0}));
    EXPECT_EQ(j.blocks[2].end, (PerAxis<double>{30, 20, -1, 0}));
    EXPECT_EQ(j.blocks[2].loc, (SourceLoc{7, 1}));
    EXPECT_EQ(j.blocks[3].end, (PerAxis<double>{30, 25, -1, 2}));
    // G20 incremental: 1 inch = 25.4 mm; F60 in/min = 25.4 mm/s.
    EXPECT_DOUBLE_EQ(j.blocks[4].end[0], 55.4);
    EXPECT_DOUBLE_EQ(j.blocks[4].feed, 25.4);
    EXPECT_TRUE(r.warnings.empty());
}

TEST(Gcode, G92OffsetsProgramCoordinates) {
    const Job& j = ok(parse("G0 X10 Y10\nG92 X0 Y0\nG0 X5 Y-2\nG91 G0 X1\n"));
    ASSERT_EQ(j.blocks.size(), 3u);
    EXPECT_EQ(j.blocks[1].end, (PerAxis<double>{15, 8, 0, 0}));
    EXPECT_EQ(j.blocks[2].end, (PerAxis<double>{16, 8, 0, 0}));
}

TEST(Gcode, StartPositionOption) {
    GcodeOptions o;
    o.start_position = {1, 2, 3, 4};
    auto r = parse_gcode("G91 G0 X1\n", "job.ngc", o);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->blocks[0].start, (PerAxis<double>{1, 2, 3, 4}));
    EXPECT_EQ(r->blocks[0].end, (PerAxis<double>{2, 2, 3, 4}));
}

TEST(Gcode, ArcCentreFromIJ) {
    const Job& j = ok(parse("G0 X10 Y0\nG2 X0 Y-10 I-10 J0 F120\nG3 X10 Y0 I0 J10\n"));
    ASSERT_EQ(j.blocks.size(), 3u);
    EXPECT_EQ(j.blocks[1].kind, MotionKind::arc_cw);
    EXPECT_DOUBLE_EQ(j.blocks[1].center_x, 0);
    EXPECT_DOUBLE_EQ(j.blocks[1].center_y, 0);
    EXPECT_DOUBLE_EQ(j.blocks[1].feed, 2.0);
    EXPECT_EQ(j.blocks[2].kind, MotionKind::arc_ccw);
    EXPECT_DOUBLE_EQ(j.blocks[2].center_x, 0);
    EXPECT_DOUBLE_EQ(j.blocks[2].center_y, 0);
}

TEST(Gcode, ArcCentreFromR) {
    // Chord (0,0)-(2,0), |R| = sqrt(2): the centre is (1, +-1). A CW arc with
    // R > 0 (the short way) has its centre right of travel, i.e. below.
    const double r2 = std::sqrt(2.0);
    auto centre = [&](const std::string& code) {
        auto r = parse("G1 F60 X0 Y0\n" + code + "\n");
        EXPECT_TRUE(r.ok()) << join(r.errors);
        return std::pair{r->blocks.back().center_x, r->blocks.back().center_y};
    };
    auto [x1, y1] = centre(fmt::format("G2 X2 Y0 R{:.12f}", r2));
    EXPECT_NEAR(x1, 1, 1e-9);
    EXPECT_NEAR(y1, -1, 1e-9);
    auto [x2, y2] = centre(fmt::format("G3 X2 Y0 R{:.12f}", r2));
    EXPECT_NEAR(y2, 1, 1e-9);
    auto [x3, y3] = centre(fmt::format("G2 X2 Y0 R-{:.12f}", r2));
    EXPECT_NEAR(y3, 1, 1e-9);
    auto [x4, y4] = centre(fmt::format("G3 X2 Y0 R-{:.12f}", r2));
    EXPECT_NEAR(y4, -1, 1e-9);
    (void)x2; (void)x3; (void)x4;
}

TEST(Gcode, DwellIsAPauseBlock) {
    const Job& j = ok(parse("G0 X1\nM3\nG4 P0.5\nG4 P0\nG1 X2 F60\nM5\n"));
    ASSERT_EQ(j.blocks.size(), 3u);  // G4 P0 is no pause at all
    EXPECT_EQ(j.blocks[1].kind, MotionKind::dwell);
    EXPECT_EQ(j.blocks[1].dwell_s, 0.5);
    EXPECT_EQ(j.blocks[1].start, j.blocks[1].end);
    EXPECT_EQ(j.blocks[1].start[0], 1);
    EXPECT_TRUE(j.blocks[1].spindle_on);
}

TEST(Gcode, ProgramEndStopsParsing) {
    auto r = parse("G0 X1\nM2\n\nG0 X5\nthis is junk\n");
    const Job& j = ok(r);
    EXPECT_EQ(j.blocks.size(), 1u);
    EXPECT_EQ(join(r.warnings), "job.ngc:4:1: text after the program end (M2/M30) is ignored");
}

TEST(Gcode, IgnoreListIsDocumentedAndAccepted) {
    // Every code on the list parses to nothing.
    for (auto code : ignored_codes()) {
        std::string line = std::string(code) + (code == "T" ? "2" : "") + "\n";
        auto r = parse(line);
        EXPECT_TRUE(r.ok()) << code << ": " << join(r.errors);
        EXPECT_TRUE(r->blocks.empty());
    }
}

TEST(Gcode, AllErrorsWithLineAndColumn) {
    struct Case { std::string text; std::string errors; };
    const Case cases[] = {
        {"G18\n", "job.ngc:1:1: G18: only the XY plane (G17) is supported"},
        {"G0 X1\n  G19 X2\n", "job.ngc:2:3: G19: only the XY plane (G17) is supported"},
        {"G1 X1\n", "job.ngc:1:1: feed rate is not set (F) for a G1/G2/G3 move"},
        {"X1\n", "job.ngc:1:1: axis words without a motion mode (G0, G1, G2 or G3)"},
        {"G0 X1 B2\n", "job.ngc:1:7: unsupported word 'B2'"},
        {"G0 X1 X2\n", "job.ngc:1:7: word 'X' appears twice in one block"},
        {"G0 G1 X1 F5\n", "job.ngc:1:4: G0 and G1 are in the same modal group (motion)"},
        {"G20 G21\n", "job.ngc:1:5: G20 and G21 are in the same modal group (units)"},
        {"G90 G91\n", "job.ngc:1:5: G90 and G91 are in the same modal group (distance)"},
        {"G4 G92 X0 P1\n", "job.ngc:1:4: G4 and G92 are in the same modal group (non-modal)"},
        {"G43 H1\n", "job.ngc:1:1: unsupported G-code G43\njob.ngc:1:5: unsupported word 'H1'"},
        {"G0 X1\nG1.5 X2\n", "job.ngc:2:1: unsupported G-code G1.5"},
        {"G93\n", "job.ngc:1:1: inverse-time feed (G93) is not supported; use G94"},
        {"M0\n", "job.ngc:1:1: unsupported M-code M0"},
        {"G1 X1 F0\n", "job.ngc:1:1: feed rate is not set (F) for a G1/G2/G3 move\n"
                       "job.ngc:1:7: feed rate F must be > 0"},
        {"S-1\n", "job.ngc:1:1: spindle speed S must be >= 0"},
        {"G0 X1 (unclosed\n", "job.ngc:1:7: comment '(' is not closed on this line"},
        {"/G0 X1\n", "job.ngc:1:1: block delete '/' is not supported"},
        {"G0 X\n", "job.ngc:1:4: expected a number after 'X'"},
        {"G0 X1 $\n", "job.ngc:1:7: unexpected character '$'"},
        {"G4\n", "job.ngc:1:1: G4 needs P<seconds>"},
        {"G4 P-1\n", "job.ngc:1:4: dwell P must be >= 0 seconds"},
        {"G4 X1 P1\n", "job.ngc:1:1: G4 takes no axis words and no motion code"},
        {"G92\n", "job.ngc:1:1: G92 needs at least one axis word"},
        {"G92 G0 X1\n", "job.ngc:1:5: a motion code cannot share a block with G92"},
        {"G0 X1 P2\n", "job.ngc:1:7: P is only accepted with G4 (dwell seconds) or G64"},
        {"G0 X1 Q2\n", "job.ngc:1:7: Q is only accepted with G64"},
        {"G1 X1 I2 F5\n", "job.ngc:1:7: I, J and R are only used by G2/G3 arcs"},
        {"G2 X1 Y1 K1 F5\n",
         "job.ngc:1:10: K is only used by G18/G19 arcs; only the XY plane (G17) is supported"},
        {"G2 X1 Y1 F5\n", "job.ngc:1:1: an arc needs I/J (centre offset) or R (radius)"},
        {"G2 X1 Y1 I1 R1 F5\n", "job.ngc:1:13: give either I/J or R for an arc, not both"},
        {"G2 X1 Y1 I0 J0 F5\n", "job.ngc:1:10: arc radius is zero"},
        {"G2 X10 Y0 I3 F5\n",
         "job.ngc:1:1: arc end is not on the circle: radius 3.0000 mm at the start, 7.0000 mm "
         "at the end"},
        {"G2 X4 Y0 R1 F5\n", "job.ngc:1:10: arc radius 1 is shorter than half the chord (2 mm)"},
        {"G2 X0 Y0 R1 F5\n",
         "job.ngc:1:10: an R-form arc cannot end where it starts; use I/J for a full circle"},
        // Errors on several lines are all reported, the job refused whole.
        {"G0 X1\nG18\nG0 X2\nM0\nG1 Y3\n",
         "job.ngc:2:1: G18: only the XY plane (G17) is supported\n"
         "job.ngc:4:1: unsupported M-code M0\n"
         "job.ngc:5:1: feed rate is not set (F) for a G1/G2/G3 move"},
    };
    for (const auto& c : cases) {
        auto r = parse(c.text);
        EXPECT_FALSE(r.ok()) << c.text;
        EXPECT_FALSE(r.value.has_value());
        EXPECT_EQ(join(r.errors), c.errors) << c.text;
    }
}

TEST(Gcode, ArcRadiusToleranceAcceptsCamRounding) {
    // Posts print 3-4 decimals: a 0.004 mm mismatch on a 10 mm arc is fine.
    EXPECT_TRUE(parse("G0 X10 Y0\nG2 X0 Y-10.004 I-10 J0 F60\n").ok());
}

TEST(Gcode, FullCircleWithIJ) {
    const Job& j = ok(parse("G0 X10 Y0\nG2 I-10 F60\n"));
    ASSERT_EQ(j.blocks.size(), 2u);
    EXPECT_EQ(j.blocks[1].start, j.blocks[1].end);
    EXPECT_EQ(j.blocks[1].center_x, 0);
}

TEST(Gcode, LoadMissingFile) {
    EXPECT_EQ(join(load_gcode("/nonexistent/j.ngc").errors), "/nonexistent/j.ngc: cannot open file");
}

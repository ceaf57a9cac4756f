// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "plan/gcode.h"
#include "plan/gcode_expr.h"
#include "plan/machine.h"
#include "plan/segments.h"

using namespace cpstep::plan;

namespace {

Result<Job> parse(const std::string& s) { return parse_gcode(s, "job.ngc"); }

// By value: `const Job& j = ok(parse(...))` then keeps the job alive.
Job ok(const Result<Job>& r) {
    EXPECT_TRUE(r.ok()) << join(r.errors);
    return r.value.value_or(Job{});
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
    auto r = parse("G21\nG0 X1\nM2\n\nG0 X5\nthis is junk\n");
    const Job& j = ok(r);
    EXPECT_EQ(j.blocks.size(), 1u);
    EXPECT_EQ(join(r.warnings), "job.ngc:5:1: text after the program end (M2/M30) is ignored");
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
        {"G1 X1\n", "job.ngc:1:1: feed rate is not set (F) for a G1/G2/G3 move or canned cycle"},
        {"X1\n", "job.ngc:1:1: axis words without a motion mode (G0, G1, G2, G3 or a canned cycle)"},
        {"G0 X1 B2\n", "job.ngc:1:7: axis B is not supported: the card drives X, Y, Z and A"},
        {"G0 X1 X2\n", "job.ngc:1:7: word 'X' appears twice in one block"},
        {"G0 G1 X1 F5\n", "job.ngc:1:4: G0 and G1 are in the same modal group (motion)"},
        {"G20 G21\n", "job.ngc:1:5: G20 and G21 are in the same modal group (units)"},
        {"G90 G91\n", "job.ngc:1:5: G90 and G91 are in the same modal group (distance)"},
        {"G4 G92 X0 P1\n", "job.ngc:1:4: G4 and G92 are in the same modal group (non-modal)"},
        {"G43 H1\n", "job.ngc:1:5: G43: tool 1 has no length; give it in the machine file's "
                     "[gcode.tool_lengths] (1 = <mm>)"},
        {"G0 X1\nG1.5 X2\n", "job.ngc:2:1: unsupported G-code G1.5"},
        {"G93\n", "job.ngc:1:1: inverse-time feed (G93) is not supported; use G94"},
        {"G41 D1\n", "job.ngc:1:1: G41: cutter radius compensation is not supported; let the CAM offset "
                     "the path\njob.ngc:1:5: word 'D1' is not supported (cutter compensation G41/G42 is "
                     "not supported)"},
        {"G38.2 Z-5 F10\n", "job.ngc:1:1: G38.2: probing needs a card with a probe input, on `cpstep run` (docs/HOST.md \"Probing\")"},
        {"G84 Z-5 R1 F10\n", "job.ngc:1:1: G84: spindle-synchronized motion (threading, tapping) is not supported"},
        {"M98 P100\n", "job.ngc:1:1: M98: subprograms are not supported; expand them before planning\n"
                       "job.ngc:1:5: P is only used by G4 (dwell seconds), G10, G64, G2/G3 turns, G82/G86/G89 and M62-M65"},
        {"G1 X1 F0\n", "job.ngc:1:7: feed rate F must be > 0"},
        {"S-1\n", "job.ngc:1:1: spindle speed S must be >= 0"},
        {"G0 X1 (unclosed\n", "job.ngc:1:7: comment '(' is not closed on this line"},
        {"G0 X\n", "job.ngc:1:4: expected a value after 'X'"},
        {"G0 X1 $\n", "job.ngc:1:7: unexpected character '$'"},
        {"$H\n", "job.ngc:1:1: a Grbl '$' system command is not G-code"},
        {"G4\n", "job.ngc:1:1: G4 needs P<seconds>"},
        {"G4 P-1\n", "job.ngc:1:4: dwell P must be >= 0 seconds"},
        {"G92\n", "job.ngc:1:1: G92 needs at least one axis word"},
        {"G92 G0 X1\n", "job.ngc:1:5: G92 and G0 cannot share the axis words of one block"},
        {"G0 X1 P2\n", "job.ngc:1:7: P is only used by G4 (dwell seconds), G10, G64, G2/G3 turns, G82/G86/G89 and M62-M65"},
        {"G0 X1 Q2\n", "job.ngc:1:7: Q is only used by G64 and the peck cycles G73/G83"},
        {"G1 X1 I2 F5\n", "job.ngc:1:7: I is only used by G2/G3 arcs and canned cycles"},
        {"G2 X1 Y1 K1 F5\n", "job.ngc:1:10: K is not an offset in the XY plane (G17 arcs use I and J)"},
        {"G2 X1 Y1 F5\n", "job.ngc:1:1: an arc needs its centre (I/J) or R (radius)"},
        {"G2 X1 Y1 I1 R1 F5\n", "job.ngc:1:13: give either the centre (I/J/K) or R for an arc, not both"},
        {"G2 X1 Y1 I0 J0 F5\n", "job.ngc:1:10: arc radius is zero (the centre is on the start or end point)"},
        {"G2 X10 Y0 I3 F5\n",
         "job.ngc:1:1: arc end is not on the circle: radius 3.0000 mm at the start, 7.0000 mm "
         "at the end"},
        {"G2 X4 Y0 R1 F5\n", "job.ngc:1:10: arc radius 1 is shorter than half the chord (2 mm)"},
        {"G2 X0 Y0 R1 F5\n",
         "job.ngc:1:10: an R-form arc cannot end where it starts; use I/J/K for a full circle"},
        {"G2 X1 Y1 I1 P2 F5\n", "job.ngc:1:13: G2/G3 P (extra full turns) is not supported"},
        {"o100 sub\n", "job.ngc:1:1: O-word 'o100sub': subroutines, loops and conditionals (o-codes) are "
                       "not supported; expand them before planning"},
        {"G0 X#<nope>\n", "job.ngc:1:5: named parameter #<nope> is not defined"},
        {"#5221 = 3\n", "job.ngc:1:1: parameter #5221 is set by the interpreter and cannot be written here "
                        "(use G10 L2 / G92 / G28.1)"},
        {"G0 X[1/0]\n", "job.ngc:1:7: division by zero"},
        {"G0 X[1 + 2\n", "job.ngc:1:5: '[' is not closed on this line"},
        {"G10 L1 P1 Z5\n", "job.ngc:1:5: G10 L1: only L2 and L20 (work offsets) are supported; tool lengths "
                           "come from the machine file"},
        {"G81 X1 Y1 Z-1 F5\n", "job.ngc:1:1: G81 needs R (the retract plane)"},
        {"G0 Z5\nG81 X1 Y1 Z2 R1 F5\n", "job.ngc:2:1: G81: the hole bottom Z is above the retract plane R"},
        {"G83 X1 Y1 Z-1 R1 F5\n", "job.ngc:1:1: G83 needs Q > 0 (the peck depth)"},
        {"G18 G81 X1 Y1 Z-1 R1 F5\n", "job.ngc:1:5: G81: canned cycles are supported in the XY plane (G17) only"},
        {"G53 G91 G0 X1\n", "job.ngc:1:1: G53 cannot be used with G91 (incremental)"},
        // Errors on several lines are all reported, the job refused whole.
        {"G0 X1\nG7 X1\nG0 X2\nM60\nG1 Y3\n",
         "job.ngc:2:1: G7: lathe diameter/radius mode is not supported\n"
         "job.ngc:4:1: M60 (pallet change) is not supported\n"
         "job.ngc:5:1: feed rate is not set (F) for a G1/G2/G3 move or canned cycle"},
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

// ---------------------------------------------------------------------------
// RS274NGC as LinuxCNC and Grbl users write it. Expected values are worked
// out by hand in each test.

namespace {

Result<Job> parse_with(const std::string& s, const GcodeOptions& o) { return parse_gcode(s, "job.ngc", o); }

double eval(const std::string& text) {
    cpstep::plan::gcode::Parameters p;
    std::string e;
    auto v = cpstep::plan::gcode::evaluate(text, p, &e);
    EXPECT_TRUE(v.has_value()) << text << ": " << e;
    return v.value_or(std::nan(""));
}

std::string eval_error(const std::string& text) {
    cpstep::plan::gcode::Parameters p;
    std::string e;
    auto v = cpstep::plan::gcode::evaluate(text, p, &e);
    EXPECT_FALSE(v.has_value()) << text;
    return e;
}

std::vector<double> z_ends(const Job& j, std::size_t from = 0) {
    std::vector<double> out;
    for (std::size_t i = from; i < j.blocks.size(); ++i) out.push_back(j.blocks[i].end[2]);
    return out;
}

}  // namespace

TEST(GcodeExpr, OperatorsAndPrecedence) {
    EXPECT_DOUBLE_EQ(eval("[1 + 2 * 3]"), 7);
    EXPECT_DOUBLE_EQ(eval("[10 - 2 - 3]"), 5);           // left to right
    EXPECT_DOUBLE_EQ(eval("[8 / 2 / 2]"), 2);
    EXPECT_DOUBLE_EQ(eval("[2 ** 3 ** 2]"), 64);         // (2^3)^2, left to right as LinuxCNC
    EXPECT_DOUBLE_EQ(eval("[2 * 3 ** 2]"), 18);          // ** binds tighter than *
    EXPECT_DOUBLE_EQ(eval("[7 mod 3]"), 1);
    EXPECT_DOUBLE_EQ(eval("[-7 mod 3]"), 2);             // result made non-negative
    EXPECT_DOUBLE_EQ(eval("[1 + 2 eq 3]"), 1);           // + before eq
    EXPECT_DOUBLE_EQ(eval("[1 eq 1 and 0]"), 0);         // eq before and
    EXPECT_DOUBLE_EQ(eval("[1 ne 1]"), 0);
    EXPECT_DOUBLE_EQ(eval("[2 gt 1]"), 1);
    EXPECT_DOUBLE_EQ(eval("[2 ge 2]"), 1);
    EXPECT_DOUBLE_EQ(eval("[1 lt 1]"), 0);
    EXPECT_DOUBLE_EQ(eval("[1 le 1]"), 1);
    EXPECT_DOUBLE_EQ(eval("[1 or 0]"), 1);
    EXPECT_DOUBLE_EQ(eval("[1 xor 1]"), 0);
    EXPECT_DOUBLE_EQ(eval("[0 xor 3]"), 1);
    EXPECT_DOUBLE_EQ(eval("[-[2 + 1]]"), -3);
    EXPECT_DOUBLE_EQ(eval("[ 1 2 . 5 ]"), 12.5);         // whitespace inside a number
}

TEST(GcodeExpr, Functions) {
    EXPECT_NEAR(eval("sin[30]"), 0.5, 1e-12);
    EXPECT_NEAR(eval("cos[60]"), 0.5, 1e-12);
    EXPECT_NEAR(eval("tan[45]"), 1, 1e-12);
    EXPECT_NEAR(eval("asin[1]"), 90, 1e-12);
    EXPECT_NEAR(eval("acos[0]"), 90, 1e-12);
    EXPECT_NEAR(eval("atan[1]/[1]"), 45, 1e-12);
    EXPECT_NEAR(eval("atan[1]/[-1]"), 135, 1e-12);
    EXPECT_DOUBLE_EQ(eval("sqrt[16]"), 4);
    EXPECT_DOUBLE_EQ(eval("abs[-2]"), 2);
    EXPECT_DOUBLE_EQ(eval("exp[0]"), 1);
    EXPECT_DOUBLE_EQ(eval("ln[1]"), 0);
    EXPECT_DOUBLE_EQ(eval("round[2.5]"), 3);
    EXPECT_DOUBLE_EQ(eval("round[-2.5]"), -3);
    EXPECT_DOUBLE_EQ(eval("fix[-1.5]"), -2);
    EXPECT_DOUBLE_EQ(eval("fup[-1.5]"), -1);
    EXPECT_DOUBLE_EQ(eval("fix[1.5]"), 1);
    EXPECT_DOUBLE_EQ(eval("SQRT[[3*3]+[4*4]]"), 5);    // upper case, nested
    EXPECT_EQ(eval_error("sqrt[-1]"), "sqrt[-1]: the argument must be >= 0");
    EXPECT_EQ(eval_error("ln[0]"), "ln[0]: the argument must be > 0");
    EXPECT_EQ(eval_error("acos[2]"), "acos[2]: the argument must be in -1..1");
    EXPECT_EQ(eval_error("[1 mod 0]"), "mod by zero");
    EXPECT_EQ(eval_error("atan[1]"), "atan needs two arguments: atan[y]/[x]");
    EXPECT_EQ(eval_error("foo[1]"), "unknown function or misplaced word 'foo'");
}

TEST(Gcode, WhitespaceAnywhere) {
    const Job& j = ok(parse("G21\nG 0 X 1 2 . 5 Y - 3\ng1x1f60\nG1 X [ 1 + 1 ]\n"));
    ASSERT_EQ(j.blocks.size(), 3u);
    EXPECT_EQ(j.blocks[0].end, (PerAxis<double>{12.5, -3, 0, 0}));
    EXPECT_EQ(j.blocks[1].end[0], 1);
    EXPECT_EQ(j.blocks[2].end[0], 2);
}

TEST(Gcode, NumberedAndNamedParameters) {
    const Job& j = ok(parse(
        "G21\n"
        "#1 = 10\n"
        "#<depth> = -2  (named)\n"
        "#<_global> = 3\n"
        "G0 X#1 Y[#1 * 2] Z#<depth> A#<_global>\n"
        "#2 = 1\n"
        "G0 X##2\n"                // ##2 = #[#2] = #1 = 10: the same X, no block
        "#1 = 4 G0 X[#1 + 1]\n"   // the assignment takes effect after the line: X = 10 + 1
        "G0 X#1\n"                 // now 4
        "G0 Y#7\n"));              // unset numbered parameters read 0
    ASSERT_EQ(j.blocks.size(), 4u);
    EXPECT_EQ(j.blocks[0].end, (PerAxis<double>{10, 20, -2, 3}));
    EXPECT_EQ(j.blocks[1].end[0], 11);
    EXPECT_EQ(j.blocks[1].end[1], 20);
    EXPECT_EQ(j.blocks[2].end[0], 4);
    EXPECT_EQ(j.blocks[3].end[1], 0);
}

TEST(Gcode, SystemParametersReadTheState) {
    // #5420 = current X in program units; #5221 = G54's X offset.
    const Job& j = ok(parse("G21\nG10 L2 P1 X7\nG0 X3\n#1 = #5420\n#2 = #5221\nG0 X[#1 + #2]\n"));
    ASSERT_EQ(j.blocks.size(), 2u);
    EXPECT_EQ(j.blocks[0].end[0], 10);      // 3 + offset 7
    EXPECT_EQ(j.blocks[1].end[0], 17);      // program 3 + 7 = 10, + offset 7
}

TEST(Gcode, WorkOffsetsG54ToG593AndG10) {
    const Job& j = ok(parse(
        "G21 G90\n"
        "G10 L2 P1 X10 Y20\n"   // G54
        "G0 X0 Y0\n"            // machine (10, 20)
        "G10 L2 P2 X100\n"      // G55
        "G55 G0 X1\n"           // 101
        "G10 L2 P9 X7\n"        // G59.3
        "G59.3 G0 X1\n"         // 8
        "G54 G0 X30 Y0\n"       // 40, 20
        "G10 L20 P1 X0\n"       // G54 offset becomes 40 - 0 = 40
        "G0 X5\n"               // 45
        "G53 G0 X2\n"           // machine 2, offsets ignored
        "G0 X1\n"));            // back in G54: 41
    ASSERT_EQ(j.blocks.size(), 7u);
    EXPECT_EQ(j.blocks[0].end, (PerAxis<double>{10, 20, 0, 0}));
    EXPECT_EQ(j.blocks[1].end[0], 101);
    EXPECT_EQ(j.blocks[2].end[0], 8);
    EXPECT_EQ(j.blocks[3].end, (PerAxis<double>{40, 20, 0, 0}));
    EXPECT_EQ(j.blocks[4].end[0], 45);
    EXPECT_EQ(j.blocks[5].end[0], 2);
    EXPECT_EQ(j.blocks[6].end[0], 41);
}

TEST(Gcode, G92FamilyAndG10WithInches) {
    const Job& j = ok(parse(
        "G21 G0 X10\n"
        "G92 X0\n"      // offset 10
        "G0 X1\n"       // 11
        "G92.2\n"       // suspended
        "G0 X1\n"       // 1
        "G92.3\n"       // restored
        "G0 X1\n"       // 11
        "G92.1\n"       // cleared
        "G0 X1\n"       // 1
        "G20 G10 L2 P1 X1\n"  // 1 inch = 25.4 mm
        "G0 X0\n"));    // 25.4
    ASSERT_EQ(j.blocks.size(), 6u);
    EXPECT_EQ(j.blocks[1].end[0], 11);
    EXPECT_EQ(j.blocks[2].end[0], 1);
    EXPECT_EQ(j.blocks[3].end[0], 11);
    EXPECT_EQ(j.blocks[4].end[0], 1);
    EXPECT_DOUBLE_EQ(j.blocks[5].end[0], 25.4);
}

TEST(Gcode, G28AndG30FromTheMachineFile) {
    GcodeOptions o;
    o.g28_position = PerAxis<double>{5, 6, 7, 0};
    o.g30_position = PerAxis<double>{1, 2, 3, 0};
    auto r = parse_with(
        "G21 G0 X50 Y50 Z10\n"
        "G28 G91 Z0\n"          // through Z + 0 (no move), then Z home only: Z 7
        "G90 G28\n"             // all axes home: (5, 6, 7)
        "G30 X20\n"             // through X 20, then X to 1
        "G0 X30 Y40\n"
        "G28.1\n"               // store (30, 40, 7) as the G28 position
        "G0 X0 Y0\n"
        "G28\n", o);
    const Job& j = ok(r);
    EXPECT_TRUE(r.warnings.empty()) << join(r.warnings);
    ASSERT_EQ(j.blocks.size(), 8u);
    EXPECT_EQ(j.blocks[1].end, (PerAxis<double>{50, 50, 7, 0}));
    EXPECT_EQ(j.blocks[2].end, (PerAxis<double>{5, 6, 7, 0}));
    EXPECT_EQ(j.blocks[3].end, (PerAxis<double>{20, 6, 7, 0}));
    EXPECT_EQ(j.blocks[4].end, (PerAxis<double>{1, 6, 7, 0}));
    EXPECT_EQ(j.blocks[7].end, (PerAxis<double>{30, 40, 7, 0}));
    EXPECT_EQ(j.blocks[1].kind, MotionKind::rapid);

    // Without a position in the machine file: the origin, with one warning.
    auto r2 = parse("G21 G0 Z5\nG28 G91 Z0\nG28 G91 Z0\n");
    ASSERT_TRUE(r2.ok());
    EXPECT_EQ(r2->blocks.back().end[2], 0);
    EXPECT_EQ(join(r2.warnings), "job.ngc:2:1: G28 goes to the machine origin: the machine file gives no "
                                 "gcode.g28_position");
}

TEST(Gcode, ToolLengthG43G49) {
    GcodeOptions o;
    o.tool_lengths = {{1, 25.0}, {2, 30.5}};
    const Job& j = ok(parse_with(
        "G21\n"
        "G43 H1 G0 Z0\n"        // Z program 0 = machine 25
        "T2 M6\n"
        "G43 Z1\n"              // H from the tool in the spindle: 30.5 + 1 (G0 still active)
        "G49 G0 Z0\n"           // 0
        "G43.1 Z-2\n"           // dynamic offset: no move
        "G0 Z0\n",              // -2
        o));
    ASSERT_EQ(j.blocks.size(), 4u);
    EXPECT_EQ(j.blocks[0].end[2], 25);
    EXPECT_EQ(j.blocks[1].end[2], 31.5);
    EXPECT_EQ(j.blocks[1].tool, 2);
    EXPECT_EQ(j.blocks[2].end[2], 0);
    EXPECT_EQ(j.blocks[3].end[2], -2);
    auto bad = parse_with("G21 G43 H3\n", o);
    EXPECT_EQ(join(bad.errors), "job.ngc:1:9: G43: tool 3 has no length; give it in the machine file's "
                                "[gcode.tool_lengths] (3 = <mm>)");
}

TEST(Gcode, ArcDistanceModeG901) {
    const Job& j = ok(parse(
        "G21 G10 L2 P1 X100\n"
        "G0 X10 Y0\n"                     // machine (110, 0)
        "G90.1 G2 X0 Y-10 I0 J0 F60\n"   // absolute centre: program (0,0) = machine (100, 0)
        "G91.1 G3 X10 Y0 I0 J10\n"));    // incremental again
    ASSERT_EQ(j.blocks.size(), 3u);
    EXPECT_DOUBLE_EQ(j.blocks[1].center_x, 100);
    EXPECT_DOUBLE_EQ(j.blocks[1].center_y, 0);
    EXPECT_DOUBLE_EQ(j.blocks[2].center_x, 100);
    EXPECT_DOUBLE_EQ(j.blocks[2].center_y, 0);
}

TEST(Gcode, ArcsInAllThreePlanes) {
    // G18 (ZX): G2 from X0 to X10 about X5: seen from +Y (Z right, X up) the
    // clockwise half goes through Z = -5.
    const Job& j = ok(parse("G21 G18 G0 X0 Z0\nG2 X10 Z0 I5 K0 F60\n"));
    const MotionBlock& b = j.blocks.back();
    EXPECT_EQ(b.plane, Plane::zx);
    EXPECT_DOUBLE_EQ(b.center_x, 5);
    EXPECT_DOUBLE_EQ(b.center_z, 0);
    auto pts = arc_chord_points(b, 100.0);  // a coarse tolerance: 90-degree chords
    ASSERT_EQ(pts.size(), 2u);
    EXPECT_NEAR(pts[0][0], 5, 1e-9);
    EXPECT_NEAR(pts[0][2], -5, 1e-9);
    EXPECT_NEAR(pts[0][1], 0, 1e-9);

    // G19 (YZ): G3 from Y0 to Y10 about Y5: seen from +X (Y right, Z up) the
    // counter-clockwise half from the left point goes down through Z = -5.
    const Job& k = ok(parse("G21 G19 G0 Y0 Z0\nG3 Y10 Z0 J5 F60\n"));
    const MotionBlock& c = k.blocks.back();
    EXPECT_EQ(c.plane, Plane::yz);
    auto q = arc_chord_points(c, 100.0);
    ASSERT_EQ(q.size(), 2u);
    EXPECT_NEAR(q[0][1], 5, 1e-9);
    EXPECT_NEAR(q[0][2], -5, 1e-9);

    // K0 on a G17 arc (some posts write it) is accepted; J on a G18 arc is not an offset.
    EXPECT_TRUE(parse("G21 G0 X10 Y0\nG2 X0 Y-10 I-10 J0 K0 F60\n").ok());
    EXPECT_EQ(join(parse("G21 G18 G0 X0 Z0\nG2 X10 Z0 I5 J1 F60\n").errors),
              "job.ngc:2:14: J is not an offset in the ZX plane (G18 arcs use K and I)");
}

TEST(Gcode, ArcTolerancesAsLinuxCnc) {
    // R semicircle 0.00045 mm short of the half chord (5 mm): within LinuxCNC's
    // 0.00127 mm, taken as the exact semicircle about the midpoint.
    const Job& j = ok(parse("G21 G0 X0 Y0\nG2 X10 Y0 R4.99955 F60\n"));
    EXPECT_NEAR(j.blocks.back().center_x, 5, 1e-9);
    EXPECT_NEAR(j.blocks.back().center_y, 0, 1e-9);
    // 0.002 mm short is beyond it.
    EXPECT_FALSE(parse("G21 G0 X0 Y0\nG2 X10 Y0 R4.998 F60\n").ok());
    // Centre format: the end radius may differ by 0.005 mm or 0.1 % of the radius.
    EXPECT_TRUE(parse("G21 G0 X10 Y0\nG2 X0 Y-10.004 I-10 J0 F60\n").ok());      // 0.004 mm
    EXPECT_TRUE(parse("G21 G0 X100 Y0\nG2 X0 Y-100.09 I-100 J0 F60\n").ok());    // 0.09 % of 100
    EXPECT_FALSE(parse("G21 G0 X100 Y0\nG2 X0 Y-100.2 I-100 J0 F60\n").ok());    // 0.2 mm, 0.2 %
}

TEST(Gcode, CannedCyclesG81G98G99) {
    const Job& j = ok(parse(
        "G21 G90 G0 X0 Y0 Z10\n"
        "G99 G81 X5 Y5 Z-2 R1 F120\n"   // rapid XY, rapid to R, feed to -2, rapid to R
        "X10\n"                          // the next hole: R, Z, F are sticky
        "G98 X20\n"                      // G98: back to the initial Z (max(1, 1) = 1 here)
        "G80\n"
        "G0 Z10\n"
        "G98 G81 X30 Z-2 R1\n"           // from Z10: retract to 10
        "G80\n"));
    const std::vector<double> expect_z = {10, 10, 1, -2, 1, 1, -2, 1, 1, -2, 1, 10, 10, 1, -2, 10};
    const std::vector<double> expect_x = {0, 5, 5, 5, 5, 10, 10, 10, 20, 20, 20, 20, 30, 30, 30, 30};
    ASSERT_EQ(j.blocks.size(), expect_z.size());
    for (std::size_t i = 0; i < expect_z.size(); ++i) {
        EXPECT_DOUBLE_EQ(j.blocks[i].end[2], expect_z[i]) << i;
        EXPECT_DOUBLE_EQ(j.blocks[i].end[0], expect_x[i]) << i;
    }
    EXPECT_EQ(j.blocks[3].kind, MotionKind::linear);
    EXPECT_DOUBLE_EQ(j.blocks[3].feed, 2.0);  // 120 mm/min
    EXPECT_EQ(j.blocks[4].kind, MotionKind::rapid);
}

TEST(Gcode, PeckCyclesG83G73) {
    // G83 Q1.5 from R1 to Z-3: pecks to -0.5 and -2, each followed by a rapid
    // to R and a rapid down to 0.254 mm above the last depth; then the bottom.
    const Job& j = ok(parse("G21 G0 X0 Y0 Z5\nG98 G83 X0 Y0 Z-3 R1 Q1.5 F60\n"));
    const std::vector<double> g83 = {1, -0.5, 1, -0.5 + 0.254, -2, 1, -2 + 0.254, -3, 5};
    EXPECT_EQ(z_ends(j, 1).size(), g83.size());
    for (std::size_t i = 0; i < std::min(g83.size(), z_ends(j, 1).size()); ++i)
        EXPECT_NEAR(z_ends(j, 1)[i], g83[i], 1e-12) << i;
    // G73 Q1 from R1 to Z-2 (G99): pecks to 0 and -1, each with a 0.254 mm retract.
    const Job& k = ok(parse("G21 G0 X0 Y0 Z5\nG99 G73 X0 Y0 Z-2 R1 Q1 F60\n"));
    const std::vector<double> g73 = {1, 0, 0.254, -1, -1 + 0.254, -2, 1};
    EXPECT_EQ(z_ends(k, 1).size(), g73.size());
    for (std::size_t i = 0; i < std::min(g73.size(), z_ends(k, 1).size()); ++i)
        EXPECT_NEAR(z_ends(k, 1)[i], g73[i], 1e-12) << i;
}

TEST(Gcode, DwellAndBoringCyclesG82G85G89) {
    const Job& j = ok(parse("G21 G0 X0 Y0 Z5\nG98 G82 Z-1 R1 P0.5 F60 X1\n"));
    // rapid X, rapid R, feed bottom, dwell, rapid back to 5
    ASSERT_EQ(j.blocks.size(), 6u);
    EXPECT_EQ(j.blocks[4].kind, MotionKind::dwell);
    EXPECT_EQ(j.blocks[4].dwell_s, 0.5);
    EXPECT_EQ(j.blocks[5].end[2], 5);
    const Job& k = ok(parse("G21 G0 X0 Y0 Z5\nG99 G85 X1 Z-1 R1 F60\n"));
    // rapid X, rapid R, feed bottom, feed back to R (G99: done)
    ASSERT_EQ(k.blocks.size(), 5u);
    EXPECT_EQ(k.blocks[4].kind, MotionKind::linear);
    EXPECT_EQ(k.blocks[4].end[2], 1);
    const Job& l = ok(parse("G21 G0 X0 Y0 Z5\nG98 G89 X1 Z-1 R1 P2 F60\n"));
    // rapid X, rapid R, feed bottom, dwell 2, feed to R, rapid to 5
    ASSERT_EQ(l.blocks.size(), 7u);
    EXPECT_EQ(l.blocks[4].dwell_s, 2);
    EXPECT_EQ(l.blocks[5].kind, MotionKind::linear);
    EXPECT_EQ(l.blocks[6].end[2], 5);
}

TEST(Gcode, IncrementalCycleWithRepeats) {
    // G91: R is from the current Z (5 - 4 = 1), Z from R (1 - 3 = -2); L3
    // repeats the hole at X +10 each time.
    const Job& j = ok(parse("G21 G0 X0 Y0 Z5\nG91 G99 G81 X10 Z-3 R-4 L3 F60\n"));
    std::vector<double> bottoms_x;
    for (const auto& b : j.blocks)
        if (b.kind == MotionKind::linear) {
            EXPECT_DOUBLE_EQ(b.end[2], -2);
            bottoms_x.push_back(b.end[0]);
        }
    EXPECT_EQ(bottoms_x, (std::vector<double>{10, 20, 30}));
}

TEST(Gcode, M0M1ArePauses) {
    const Job& j = ok(parse("G21 G0 X1\nM0\nG0 X2\nM1 (optional stop)\n"));
    ASSERT_EQ(j.blocks.size(), 4u);
    EXPECT_EQ(j.blocks[1].kind, MotionKind::dwell);
    EXPECT_EQ(j.blocks[1].dwell_s, 0);
    EXPECT_EQ(j.blocks[1].pause, PauseKind::program_stop);
    EXPECT_EQ(j.blocks[3].pause, PauseKind::optional_stop);
    EXPECT_EQ(j.blocks[0].pause, PauseKind::none);
}

TEST(Gcode, SpindleM3M4M5WithS) {
    const Job& j = ok(parse("G21 M3 S1000\nG0 X1\nM4 S500\nG0 X2\nM5\nG0 X3\n"));
    ASSERT_EQ(j.blocks.size(), 3u);
    EXPECT_TRUE(j.blocks[0].spindle_on);
    EXPECT_FALSE(j.blocks[0].spindle_ccw);
    EXPECT_EQ(j.blocks[0].spindle_speed, 1000);
    EXPECT_TRUE(j.blocks[1].spindle_ccw);
    EXPECT_EQ(j.blocks[1].spindle_speed, 500);
    EXPECT_FALSE(j.blocks[2].spindle_on);
}

// M62/M63 P0: digital output 0 from the next motion on (a dwell between keeps the
// old level); M64/M65 P0: from the next block on, dwells included (docs/PLANNING.md).
TEST(Gcode, DigitalOutputM62ToM65) {
    const Job& j = ok(parse("G21 G0 X1\nM62 P0\nG4 P0.5\nG1 X2 F600\nG1 X3\nM63 P0\nG1 X4 M64 P0\n"
                            "M65 P0\nG4 P1\nG0 X5\n"));
    ASSERT_EQ(j.blocks.size(), 7u);
    EXPECT_FALSE(j.blocks[0].output0);              // G0 X1
    EXPECT_EQ(j.blocks[1].kind, MotionKind::dwell); // G4 after M62: not yet
    EXPECT_FALSE(j.blocks[1].output0);
    EXPECT_TRUE(j.blocks[2].output0);               // the next motion
    EXPECT_TRUE(j.blocks[3].output0);
    EXPECT_TRUE(j.blocks[4].output0);               // M64 in the block: at once, and the M63 pending dropped
    EXPECT_EQ(j.blocks[5].kind, MotionKind::dwell); // after M65: off for the dwell
    EXPECT_FALSE(j.blocks[5].output0);
    EXPECT_FALSE(j.blocks[6].output0);
    EXPECT_FALSE(j.blocks[2].spindle_on);           // the spindle is another thing
}

TEST(Gcode, DigitalOutputRefusals) {
    const auto r = parse("M62 P1\nM64\nG4 P1 M62\nM63 P0 M65 P0\n");
    ASSERT_FALSE(r.ok());
    const std::string e = join(r.errors);
    EXPECT_NE(e.find("job.ngc:1:5: M62: the card has one digital output, P0 (the torch); P1 is not one"),
              std::string::npos) << e;
    EXPECT_NE(e.find("job.ngc:2:1: M64 needs P<output>"), std::string::npos) << e;
    EXPECT_NE(e.find("job.ngc:3:4: P is wanted by M62 and by another code"), std::string::npos) << e;
    EXPECT_NE(e.find("job.ngc:4:"), std::string::npos) << e;  // two codes of the output group
}

TEST(Gcode, DwellInABlockWithG0) {
    // G4 (step 14) runs before the motion (step 24); the axis words are G0's.
    const Job& j = ok(parse("G21 G0 G4 P1 X5\n"));
    ASSERT_EQ(j.blocks.size(), 2u);
    EXPECT_EQ(j.blocks[0].kind, MotionKind::dwell);
    EXPECT_EQ(j.blocks[1].end[0], 5);
}

TEST(Gcode, RotaryAxisInDegrees) {
    // A is in degrees whatever G20/G21 say; an A-only move takes F in degrees/min.
    const Job& j = ok(parse("G20 G0 X1 A90\nG1 A180 F600\n"));
    EXPECT_DOUBLE_EQ(j.blocks[0].end[0], 25.4);
    EXPECT_DOUBLE_EQ(j.blocks[0].end[3], 90);
    EXPECT_DOUBLE_EQ(j.blocks[1].feed, 10);  // 600 deg/min
}

TEST(Gcode, MachineFileOptionsAndZPolicy) {
    const std::string base =
        "[axes.x]\nsteps_per_mm = 80\ntravel_min_mm = 0\ntravel_max_mm = 100\nmax_velocity_mm_s = 50\n"
        "max_accel_mm_s2 = 500\nmax_jerk_mm_s3 = 5000\ndriver = \"TMC2209\"\n"
        "[axes.y]\nsteps_per_mm = 80\ntravel_min_mm = 0\ntravel_max_mm = 100\nmax_velocity_mm_s = 50\n"
        "max_accel_mm_s2 = 500\nmax_jerk_mm_s3 = 5000\ndriver = \"TMC2209\"\n";
    auto m = parse_machine(base + "[gcode]\nz_words = \"ignore\"\ng28_position = { x = 3, y = 4 }\n"
                                  "[gcode.tool_lengths]\n1 = 12.5\n",
                           "m.toml");
    ASSERT_TRUE(m.ok()) << join(m.errors);
    EXPECT_EQ(m->gcode.z_words, MissingZ::ignore);
    EXPECT_EQ(*m->gcode.g28_position, (PerAxis<double>{3, 4, 0, 0}));
    EXPECT_EQ(m->gcode.tool_lengths.at(1), 12.5);
    const GcodeOptions o = gcode_options(*m);
    auto r = parse_with("G21\nG0 Z5\nG1 X1 Z-1 F60\nG0 Z5\nG28\n", o);
    const Job& j = ok(r);
    ASSERT_EQ(j.blocks.size(), 2u);  // the Z-only moves vanish
    EXPECT_EQ(j.blocks[0].end, (PerAxis<double>{1, 0, 0, 0}));
    EXPECT_EQ(j.blocks[1].end, (PerAxis<double>{3, 4, 0, 0}));
    EXPECT_EQ(join(r.warnings), "job.ngc:2:4: Z word ignored: the machine has no Z axis (gcode.z_words = "
                                "\"ignore\") (3 times, lines 2-4)");
    auto refuse = parse_with("G21\nG0 Z5 A1\n", gcode_options(*parse_machine(base, "m.toml")));
    EXPECT_EQ(join(refuse.errors),
              "job.ngc:2:4: Z word on a machine without a Z axis; set [gcode] z_words = \"ignore\" in the "
              "machine file to drop Z words\n"
              "job.ngc:2:7: A word on a machine without an A axis");
    auto bad = parse_machine(base + "[gcode]\nz_words = \"drop\"\n", "m.toml");
    EXPECT_EQ(join(bad.errors), "m.toml:18:11: gcode.z_words: must be \"refuse\" or \"ignore\", not \"drop\"");
}

TEST(Gcode, ErrorsRecoverAtTheEndOfTheBlock) {
    // The undefined parameter is reported once; the arc after it, whose start
    // is unknown, reports nothing more.
    auto r = parse("G21 G0 X0 Y0\nG1 X#<nope> F60\nG2 X10 Y0 I5\nG1 X20\n");
    EXPECT_EQ(join(r.errors), "job.ngc:2:5: named parameter #<nope> is not defined");
    // A refused block still sets its modes: G20 holds for the next line.
    auto r2 = parse("G20 G0 X1 B2\nG0 X2\n");
    EXPECT_EQ(join(r2.errors), "job.ngc:1:11: axis B is not supported: the card drives X, Y, Z and A");
    // A failed assignment leaves its parameter unknown without new errors.
    auto r3 = parse("G21\n#<d> = [1/0]\nG0 X#<d>\nG0 Y#<d>\n");
    EXPECT_EQ(join(r3.errors), "job.ngc:2:10: division by zero");
    // One unreadable character costs one error for its line, not one per character.
    auto r4 = parse("G21\nG0 X1 \x01\x02\x03 Y2 Z3\nG0 X2\n");
    EXPECT_EQ(r4.errors.size(), 1u);
}

TEST(Gcode, AtMostTwentyErrorsThenACount) {
    std::string text = "G21\n";
    for (int i = 0; i < 30; ++i) text += "G0 X1 $\n";
    auto r = parse(text);
    ASSERT_EQ(r.errors.size(), 21u);
    EXPECT_EQ(r.errors[19].str(), "job.ngc:21:7: unexpected character '$'");
    EXPECT_EQ(r.errors[20].str(), "job.ngc: 10 more errors not shown (30 in total)");
}

TEST(Gcode, WarningsNoUnitsAndRepeatsSummarized) {
    auto r = parse("G0 X1\n/G0 X2\n/G0 X3\n");
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->blocks.size(), 3u);  // block delete off: the lines run
    EXPECT_EQ(join(r.warnings),
              "job.ngc:1:1: the program sets no units (G20/G21): millimetres assumed\n"
              "job.ngc:2:1: block delete '/' lines run (the block delete switch is off) (2 times, lines 2-3)");
    EXPECT_TRUE(parse("G21\nG0 X1\n").warnings.empty());
    std::vector<Diagnostic> d = {{"j", {1, 1}, "feed 100 mm/s lowered to 30 mm/s"},
                                 {"j", {2, 1}, "other"},
                                 {"j", {5, 1}, "feed 80 mm/s lowered to 30 mm/s"}};
    EXPECT_EQ(join(summarize_repeats(d)),
              "j:1:1: feed 100 mm/s lowered to 30 mm/s (2 times, lines 1-5)\nj:2:1: other");
}

// Found by fuzz/fuzz_gcode (docs/RELIABILITY.md): inputs that ran out of memory or
// time (a canned cycle's repeats and pecks) or of stack (nested brackets) are refused.
TEST(Gcode, FuzzFindingsRefused) {
    auto repeats = parse("G21 G90 G0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R1 F100 L100000000\n");
    EXPECT_EQ(join(repeats.errors),
              "job.ngc:2:1: G81: 1e+08 hole(s) of 1 peck(s) each; a block expands into at most 100000 holes x pecks");
    auto pecks = parse("G21 G90 G0 X0 Y0 Z5\nG83 X1 Y1 Z-1000 R1 Q0.00001 F100\n");
    EXPECT_EQ(join(pecks.errors),
              "job.ngc:2:1: G83: 1 hole(s) of 1.001e+08 peck(s) each; a block expands into at most 100000 holes x pecks");
    EXPECT_TRUE(parse("G21 G90 G0 X0 Y0 Z5\nG83 X1 Y1 Z-10 R1 Q1 F100 L900\n").ok());  // 9,900 holes x pecks
    // Finding 11: a few kilobytes of G81 ... L99999 lines, each within the block's
    // limit, made a job of gigabytes (> 10 s under ASan). The program's cycles are
    // limited together; the block that crosses the limit is refused, once.
    GcodeOptions small;
    small.max_cycle_job = 1000;
    const std::string holes = "G21 G90 G0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R1 F100 L600\nG81 X2 L400\n";
    const Job fits = ok(parse_with(holes, small));  // 1,000 holes: the limit itself
    // G0, then per line a rapid over the first hole and per hole (G98) a rapid to R,
    // the feed to Z and a rapid back to Z5 (over the same hole again: no XY move).
    EXPECT_EQ(fits.blocks.size(), 1u + (1u + 3u * 600) + (1u + 3u * 400));
    auto over = parse_with(holes + "G81 X3 L1\nG81 X4 L5\n", small);
    EXPECT_EQ(join(over.errors), "job.ngc:4:1: G81: the program's canned cycles expand into more than 1000 holes x "
                                 "pecks (1000 before this block, 1 in it)");
    auto nested = parse("G21 G1 X" + std::string(3000, '[') + "1" + std::string(3000, ']') + " F1\n");
    EXPECT_EQ(join(nested.errors), "job.ngc:1:73: expression nested more than 64 deep");
    EXPECT_TRUE(parse("G21 G1 X" + std::string(63, '[') + "1" + std::string(63, ']') + " F1\n").ok());
    // Tool numbers past int (the conversion was undefined): refused.
    EXPECT_EQ(join(parse("G21\nT100000000000000000000 M6\nG43 H100000 G0 Z0\n").errors),
              "job.ngc:2:1: tool number T must be a whole number in 0..99999\n"
              "job.ngc:3:5: H must be a whole tool number in 0..99999");
}

TEST(Gcode, ByteOrderMarkIsNotPartOfLineOne) {
    const Job j = ok(parse("\xEF\xBB\xBFG21 G90\nG1 X1 F100\n"));
    ASSERT_EQ(j.blocks.size(), 1u);
    EXPECT_DOUBLE_EQ(j.blocks[0].end[0], 1.0);
    // Columns on line 1 count from after the mark: the bad word is at 1:5.
    auto r = parse("\xEF\xBB\xBFG21 @\n");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.errors.at(0).loc.line, 1);
    EXPECT_EQ(r.errors.at(0).loc.col, 5) << join(r.errors);
    // Only at the very start: elsewhere its bytes are refused as any stray byte.
    EXPECT_FALSE(parse("G21\n\xEF\xBB\xBFG1 X1 F100\n").ok());
}

TEST(Gcode, BinaryDataIsRefusedWithOneError) {
    std::string bytes;
    uint32_t x = 12345;  // a fixed-seed xorshift: 20 kB of noise, NUL bytes included
    for (int i = 0; i < 20000; ++i) {
        x ^= x << 13, x ^= x >> 17, x ^= x << 5;
        bytes.push_back(static_cast<char>(x & 0xff));
    }
    auto r = parse(bytes);
    ASSERT_FALSE(r.ok());
    ASSERT_EQ(r.errors.size(), 1u) << join(r.errors);
    EXPECT_EQ(r.errors[0].loc.line, 1);
    EXPECT_NE(r.errors[0].message.find("binary data"), std::string::npos);
    // Control characters without a NUL (an 8-bit transfer of something else).
    std::string ctl;
    for (int i = 0; i < 1000; ++i) ctl += (i % 4 == 0) ? '\x01' : 'G';
    auto c = parse(ctl);
    ASSERT_EQ(c.errors.size(), 1u) << join(c.errors);
    EXPECT_NE(c.errors[0].message.find("control characters"), std::string::npos);
    // A real program with a stray control byte is read, the byte named at its place.
    auto one = parse("G21 G90\nG1 X1 F100\x01\nG1 X2\n");
    ASSERT_FALSE(one.ok());
    EXPECT_EQ(one.errors.at(0).loc.line, 2) << join(one.errors);
}

// A job is a probing job (`cpstep run`, docs/HOST.md "Probing") when a line has a
// G38.2..G38.5 word: not in a comment, not as another word's value, not G38.1.
TEST(Gcode, ProbeWordsAreFoundWordByWord) {
    EXPECT_TRUE(has_probe_words("G21 G90\nG0 Z5\ng38.3 z-2 F60\nM2\n"));
    EXPECT_TRUE(has_probe_words("G38.5 X1 F10"));
    EXPECT_FALSE(has_probe_words("G21 (G38.2 Z-5 in a comment)\n; G38.2 too\nG1 X38.2 F100\nG38.1 X1\n"));
    EXPECT_FALSE(has_probe_words(""));
}

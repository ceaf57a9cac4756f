// SPDX-License-Identifier: MIT
// The VCD reader (host/check/vcd): the dialects cpstep, simulators and
// sigrok-cli write, and malformed input refused with file:line:col.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "check/vcd.h"

namespace cpstep::tb {
namespace {

using check::parse_vcd;
using check::VcdChange;
using check::VcdTrace;

VcdTrace parse_ok(const std::string& text) {
  auto r = parse_vcd(text, "t.vcd");
  EXPECT_TRUE(r.ok()) << plan::join(r.errors);
  return r.ok() ? *r.value : VcdTrace{};
}

// (time, level) of every change of the one signal called `name`.
using Levels = std::vector<std::pair<uint64_t, uint64_t>>;
Levels levels(const VcdTrace& t, const std::string& name) {
  const auto found = t.find(name);
  EXPECT_EQ(found.size(), 1u) << name;
  Levels out;
  if (found.size() == 1)
    for (const VcdChange& c : t.changes[found[0]->code]) out.emplace_back(c.time, c.bits);
  return out;
}

TEST(Vcd, CpstepDialect) {
  // As host/sim/vcd_writer writes it: one scope, $dumpvars, identifier codes
  // that include '$' and '#'.
  const VcdTrace t = parse_ok(
      "$timescale 1ps $end\n"
      "$scope module cpstep $end\n"
      "$var wire 1 ! step_x $end\n"
      "$var wire 1 # dir_x $end\n"
      "$var wire 1 $ step_a $end\n"
      "$upscope $end\n"
      "$enddefinitions $end\n"
      "#0\n$dumpvars\n0!\n0#\n0$\n$end\n"
      "#20833\n1#\n"
      "#41667\n1!\n1$\n"
      "#83333\n0!\n");
  EXPECT_DOUBLE_EQ(*t.unit_s, 1e-12);
  EXPECT_EQ(t.end_time, 83333u);
  ASSERT_EQ(t.vars.size(), 3u);
  EXPECT_EQ(t.vars[0].path, "cpstep.step_x");
  EXPECT_EQ(t.vars[0].name, "step_x");
  EXPECT_EQ(t.vars[0].loc.line, 3);
  EXPECT_EQ(levels(t, "step_x"), (Levels{{0, 0}, {41667, 1}, {83333, 0}}));
  EXPECT_EQ(levels(t, "step_a"), (Levels{{0, 0}, {41667, 1}}));
  EXPECT_EQ(levels(t, "dir_x"), (Levels{{0, 0}, {20833, 1}}));
}

TEST(Vcd, SigrokDialect) {
  // sigrok-cli -O vcd: a multi-line $comment, "1 us" with a space, no
  // $dumpvars, the time and the changes on one line, a last bare timestamp.
  const VcdTrace t = parse_ok(
      "$date Mon Nov 24 10:00:00 2025 $end\n"
      "$version libsigrok 0.5.2 $end\n"
      "$comment\n  Acquisition with 2/8 channels at 1 MHz\n$end\n"
      "$timescale 1 us $end\n"
      "$scope module libsigrok $end\n"
      "$var wire 1 ! D0 $end\n"
      "$var wire 1 \" D1 $end\n"
      "$upscope $end\n"
      "$enddefinitions $end\n"
      "#0 0! 1\"\n"
      "#12 1!\n"
      "#14 0! 0\"\n"
      "#20\n");
  EXPECT_DOUBLE_EQ(*t.unit_s, 1e-6);
  EXPECT_EQ(t.end_time, 20u);
  EXPECT_EQ(levels(t, "D0"), (Levels{{0, 0}, {12, 1}, {14, 0}}));
  EXPECT_EQ(levels(t, "libsigrok.D1"), (Levels{{0, 1}, {14, 0}}));
}

TEST(Vcd, ScopesVectorsUnknownsAndAliases) {
  const VcdTrace t = parse_ok(
      "$timescale\n  10 ns\n$end\n"
      "$scope module top $end\n"
      " $scope module la $end\n"
      "  $var wire 1 a STEP $end\n"
      "  $var reg 4 b bus [3:0] $end\n"
      " $upscope $end\n"
      " $scope module other $end\n"
      "  $var wire 1 a STEP_ALIAS $end\n"
      "  $var wire 1 c STEP $end\n"
      " $upscope $end\n"
      "$upscope $end\n"
      "$enddefinitions $end\n"
      "$comment a comment in the dump $end\n"
      "#5 b0 a bx1z0 b r2.5e-3 c\n"
      "#6 b1 a b1010 b $dumpoff xa $end\n");
  EXPECT_DOUBLE_EQ(*t.unit_s, 10e-9);
  // The last component matches in every scope; the full path in one.
  EXPECT_EQ(t.find("STEP").size(), 2u);
  ASSERT_EQ(t.find("top.la.STEP").size(), 1u);
  EXPECT_EQ(t.find("bus[3:0]").size(), 1u);
  EXPECT_EQ(t.find("top.la.bus[3:0]").front()->width, 4u);
  // One code, two names: the same changes.
  EXPECT_EQ(t.find("STEP_ALIAS").front()->code, t.find("top.la.STEP").front()->code);
  const auto& a = t.changes[t.find("top.la.STEP").front()->code];
  ASSERT_EQ(a.size(), 3u);
  EXPECT_TRUE(a[0].known);
  EXPECT_EQ(a[1].bits, 1u);
  EXPECT_FALSE(a[2].known);
  const auto& bus = t.changes[t.find("bus[3:0]").front()->code];
  ASSERT_EQ(bus.size(), 2u);
  EXPECT_FALSE(bus[0].known);
  EXPECT_TRUE(bus[1].known);
  EXPECT_EQ(bus[1].bits, 0b1010u);
  // The real value is read and dropped.
  EXPECT_TRUE(t.changes[t.find("top.other.STEP").front()->code].empty());
}

TEST(Vcd, MalformedInputNamesFileLineAndColumn) {
  const std::string head = "$timescale 1ns $end\n$scope module m $end\n$var wire 1 ! s $end\n$upscope $end\n"
                           "$enddefinitions $end\n";  // lines 1-5
  const std::pair<std::string, std::string> cases[] = {
      {head + "#10\n1!\n#5\n0!\n",
       "bad.vcd:8:1: time #5 goes back (the time before was #10)"},
      {head + "#1\n1?\n",
       "bad.vcd:7:1: unknown identifier code '?' (not declared by a $var)"},
      {head + "#1\n  b2 !\n",
       "bad.vcd:7:3: bad bit '2' in vector value 'b2'"},
      {head + "#1\nb1\n",
       "bad.vcd:7:1: vector value 'b1' without an identifier code"},
      {head + "#1\nb10 !\n",  // found by fuzz/fuzz_vcd (docs/RELIABILITY.md)
       "bad.vcd:7:1: vector value 'b10' has more bits than its variable's width 1"},
      {head + "#1x\n",
       "bad.vcd:6:1: bad time '#1x'"},
      {head + "#1 hello\n",
       "bad.vcd:6:4: unexpected 'hello': expected #time or a value change"},
      {head + "$end\n",
       "bad.vcd:6:1: $end without an open $dumpvars, $dumpall, $dumpon or $dumpoff"},
      {head + "$dumpvars\n0!\n",
       "bad.vcd:8:1: end of file inside $dumpvars (opened at line 6): missing $end"},
      {head + "$var wire 1 \" t $end\n",
       "bad.vcd:6:1: unexpected $var after $enddefinitions"},
      {"$timescale 1 parsec $end\n",
       "bad.vcd:1:1: bad $timescale '1parsec': expected a whole number and s, ms, us, ns, ps or fs"},
      {"$timescale 2.5ns $end\n",
       "bad.vcd:1:1: bad $timescale '2.5ns': expected a whole number and s, ms, us, ns, ps or fs"},
      {"$scope module m $end\n$var wire 0 ! s $end\n",
       "bad.vcd:2:11: $var width '0' is not a whole number in 1..64"},
      {"$var wire 1 ! $end\n",
       "bad.vcd:1:1: $var needs a type, a width, an identifier code and a name: $var wire 1 ! step_x $end"},
      {"$var wire 1 ! s\n$var wire 1 \" t $end\n",
       "bad.vcd:2:1: $var inside $var (opened at line 1) before its $end"},
      {"$var wire 1 ! s $end\n$var wire 2 ! t $end\n",
       "bad.vcd:2:13: identifier code '!' declared again with width 2 (was 1)"},
      {"$upscope $end\n",
       "bad.vcd:1:1: $upscope without an open $scope"},
      {"$scope module m $end\n$enddefinitions $end\n",
       "bad.vcd:2:1: $enddefinitions with $scope m still open"},
      {"$var wire 1 ! s $end\n#0\n",
       "bad.vcd:2:1: '#0' before $enddefinitions: expected a $keyword"},
      {"$vra wire 1 ! s $end\n",
       "bad.vcd:1:1: unknown declaration $vra"},
      {"$comment never closed\n",
       "bad.vcd:2:1: end of file inside $comment (opened at line 1): missing $end"},
      {"",
       "bad.vcd:1:1: end of file before $enddefinitions"},
  };
  for (const auto& [text, error] : cases) {
    auto r = parse_vcd(text, "bad.vcd");
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(plan::join(r.errors), error) << text;
  }
}

TEST(Vcd, NoTimescale) {
  const VcdTrace t = parse_ok("$var wire 1 ! s $end\n$enddefinitions $end\n#3 1!\n");
  EXPECT_FALSE(t.unit_s);
  EXPECT_EQ(t.end_time, 3u);
}

TEST(Vcd, UnreadableFile) {
  auto r = check::read_vcd("/nonexistent/trace.vcd");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors.front().str(), "/nonexistent/trace.vcd: cannot read the file");
}

TEST(Vcd, Durations) {
  EXPECT_DOUBLE_EQ(*check::parse_duration("1ps"), 1e-12);
  EXPECT_DOUBLE_EQ(*check::parse_duration(" 100 us "), 1e-4);
  EXPECT_DOUBLE_EQ(*check::parse_duration("20.833ns"), 20.833e-9);
  EXPECT_DOUBLE_EQ(*check::parse_duration("1 s"), 1);
  EXPECT_FALSE(check::parse_duration("ns"));
  EXPECT_FALSE(check::parse_duration("0 ns"));
  EXPECT_FALSE(check::parse_duration("1 ks"));
  EXPECT_FALSE(check::parse_duration("1.2.3 ns"));
  EXPECT_FALSE(check::parse_duration("-1 ns"));
}

}  // namespace
}  // namespace cpstep::tb

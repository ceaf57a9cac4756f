// SPDX-License-Identifier: MIT
// Pin maps (host/check/pin_map): defaults, every field, and bad maps refused
// with file, line, column and field.
#include <gtest/gtest.h>

#include <string>

#include "check/pin_map.h"

namespace cpstep::tb {
namespace {

using check::parse_pin_map;

std::string errors_of(const std::string& text) {
  auto r = parse_pin_map(text, "pins.toml");
  EXPECT_FALSE(r.ok());
  return plan::join(r.errors);
}

TEST(PinMap, DefaultsAreCpstepsNames) {
  const check::PinMap m = check::default_pin_map();
  EXPECT_EQ(m.axes[0].step, "step_x");
  EXPECT_EQ(m.axes[1].dir, "dir_y");
  EXPECT_EQ(m.axes[3].step, "step_a");
  EXPECT_FALSE(m.axes[0].step_active_high);
  EXPECT_FALSE(m.unit_s);
  EXPECT_FALSE(m.sample_s);
}

TEST(PinMap, EveryField) {
  auto r = parse_pin_map(
      "timescale = \"10 ns\"\n"
      "sample_hz = 25_000_000\n"
      "[axes.x]\n"
      "step = \"D0\"\n"
      "dir = \"top.la.D1\"\n"
      "step_active_high = false\n"
      "dir_positive_high = false\n"
      "[axes.z]\n"
      "step = \"D4\"\n",
      "pins.toml");
  ASSERT_TRUE(r.ok()) << plan::join(r.errors);
  const check::PinMap& m = *r.value;
  EXPECT_EQ(m.file, "pins.toml");
  EXPECT_DOUBLE_EQ(*m.unit_s, 10e-9);
  EXPECT_DOUBLE_EQ(*m.sample_s, 40e-9);
  EXPECT_EQ(m.axes[0].step, "D0");
  EXPECT_EQ(m.axes[0].step_loc.line, 4);
  EXPECT_EQ(m.axes[0].dir, "top.la.D1");
  EXPECT_EQ(m.axes[0].step_active_high, false);
  EXPECT_EQ(m.axes[0].dir_positive_high, false);
  // Unnamed pins and axes keep the defaults.
  EXPECT_EQ(m.axes[2].step, "D4");
  EXPECT_EQ(m.axes[2].dir, "dir_z");
  EXPECT_EQ(m.axes[2].dir_loc.line, 0);
  EXPECT_FALSE(m.axes[2].step_active_high);
  EXPECT_EQ(m.axes[1].step, "step_y");

  auto clock = parse_pin_map("clock_hz = 48e6\n", "pins.toml");
  ASSERT_TRUE(clock.ok()) << plan::join(clock.errors);
  EXPECT_DOUBLE_EQ(*clock.value->unit_s, 1 / 48e6);
}

TEST(PinMap, BadMapsNameLineColumnAndField) {
  const std::pair<std::string, std::string> cases[] = {
      {"[axes.x]\nstep_active_high = \"yes\"\n",
       "pins.toml:2:20: axes.x.step_active_high: must be true or false"},
      {"[axes.x]\nstep = 3\n",
       "pins.toml:2:8: axes.x.step: must be a signal name (a string)"},
      {"[axes.y]\ndir = \"\"\n",
       "pins.toml:2:7: axes.y.dir: must be a signal name (a string)"},
      {"[axes.x]\nsetp = \"D0\"\n",
       "pins.toml:2:1: axes.x.setp: unknown key (known: step, dir, step_active_high, dir_positive_high)"},
      {"[axes.q]\nstep = \"D0\"\n",
       "pins.toml:1:7: axes.q: unknown key (known: x, y, z, a)"},
      {"clock_hz = -5\n",
       "pins.toml:1:12: clock_hz: must be a number > 0"},
      {"sample_hz = \"fast\"\n",
       "pins.toml:1:13: sample_hz: must be a number > 0"},
      {"timescale = \"1 parsec\"\n",
       "pins.toml:1:13: timescale: must be a duration such as \"1 ns\" or \"20.833ns\" (s, ms, us, ns, ps, fs)"},
      {"clock_hz = 1e6\ntimescale = \"1 us\"\n",
       "pins.toml:1:12: clock_hz: give clock_hz or timescale, not both"},
      {"axes = 3\n",
       "pins.toml:1:8: axes: must be a table of axes ([axes.x], [axes.y], ...)"},
      {"[axes]\nx = 1\n",
       "pins.toml:2:5: axes.x: must be a table ([axes.x])"},
      {"colck_hz = 1\n",
       "pins.toml:1:1: colck_hz: unknown key (known: timescale, clock_hz, sample_hz, axes)"},
  };
  for (const auto& [text, error] : cases) EXPECT_EQ(errors_of(text), error) << text;
  // Every problem, not only the first.
  EXPECT_EQ(errors_of("[axes.x]\nstep = 1\ndir = 2\n"),
            "pins.toml:2:8: axes.x.step: must be a signal name (a string)\n"
            "pins.toml:3:7: axes.x.dir: must be a signal name (a string)");
  // TOML syntax.
  EXPECT_EQ(errors_of("[axes.x\nstep = \"D0\"\n").rfind("pins.toml:1:", 0), 0u);
}

TEST(PinMap, UnreadableFile) {
  auto r = check::load_pin_map("/nonexistent/pins.toml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors.front().str(), "/nonexistent/pins.toml: cannot read the file");
}

}  // namespace
}  // namespace cpstep::tb

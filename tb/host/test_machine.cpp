// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <string>

#include "plan/machine.h"

using namespace cpstep::plan;

namespace {

const char* kGood = R"([card]
clock_hz = 50_000_000

[axes.x]
steps_per_mm = 80
travel_min_mm = 0
travel_max_mm = 300
max_velocity_mm_s = 60
max_accel_mm_s2 = 500
max_jerk_mm_s3 = 2000
driver = "dm556"

[axes.y]
steps_per_mm = 100.5
travel_min_mm = -10
travel_max_mm = 200
max_velocity_mm_s = 50
max_accel_mm_s2 = 400
max_jerk_mm_s3 = 1500
step_high_ns = 1000
step_low_ns = 1010
dir_setup_ns = 0
dir_hold_ns = 33
step_active_high = false
dir_positive_high = false
)";

Result<Machine> parse(const std::string& s) { return parse_machine(s, "mach.toml"); }

// Replace the first occurrence of `from` in the good file.
std::string edit(const std::string& from, const std::string& to) {
    std::string s = kGood;
    auto pos = s.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    s.replace(pos, from.size(), to);
    return s;
}

}  // namespace

TEST(Machine, ParsesGoodFileWithDefaults) {
    auto r = parse(kGood);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    const Machine& m = *r;
    EXPECT_EQ(m.card.clock_hz, 50e6);
    EXPECT_EQ(m.card.pattern_capacity, 1024u);
    EXPECT_EQ(m.card.max_doubling, 8u);
    EXPECT_EQ(m.planner.on_limit, OnLimit::refuse);
    EXPECT_DOUBLE_EQ(m.planner.chunk_tolerance_s, 1e-6);
    EXPECT_TRUE(m.planner.chunk_add2);
    const auto& x = m.axes[0];
    EXPECT_TRUE(x.present);
    EXPECT_EQ(x.driver, "DM556");
    // DM556: 2.5 us high/low, 5 us setup, 10 us hold at 20 ns per cycle.
    EXPECT_EQ(x.pulse.step_high, 125u);
    EXPECT_EQ(x.pulse.step_low, 125u);
    EXPECT_EQ(x.pulse.dir_setup, 250u);
    EXPECT_EQ(x.pulse.dir_hold, 500u);
    EXPECT_TRUE(x.step_active_high);
    EXPECT_TRUE(x.dir_positive_high);
    const auto& y = m.axes[1];
    EXPECT_DOUBLE_EQ(y.steps_per_mm, 100.5);
    EXPECT_EQ(y.travel_min_mm, -10);
    // 1010 ns = 50.5 cycles -> 51; 33 ns = 1.65 -> 2; 0 -> 0.
    EXPECT_EQ(y.pulse.step_high, 50u);
    EXPECT_EQ(y.pulse.step_low, 51u);
    EXPECT_EQ(y.pulse.dir_setup, 0u);
    EXPECT_EQ(y.pulse.dir_hold, 2u);
    EXPECT_FALSE(y.step_active_high);
    EXPECT_FALSE(y.dir_positive_high);
    EXPECT_FALSE(m.axes[2].present);
    EXPECT_FALSE(m.axes[3].present);
    // 125 + 125 cycles per step at 50 MHz.
    EXPECT_DOUBLE_EQ(x.max_step_rate_hz(m.card.clock_hz), 200000.0);
}

TEST(Machine, DriverPresetTable) {
    struct Row { const char* name; double hi, lo, hold, setup; };
    // The brief's table, in its order: high / low / DIR hold / DIR setup.
    const Row rows[] = {
        {"DM556", 2500, 2500, 10000, 5000}, {"M542", 1500, 1500, 8000, 5000},
        {"DM860T", 5000, 5000, 5000, 5000}, {"TB6600", 5000, 5000, 20000, 20000},
        {"A4988", 1000, 1000, 200, 200},    {"DRV8825", 1900, 1900, 650, 650},
        {"DRV8884", 970, 970, 200, 200},    {"TMC2209", 100, 100, 20, 20},
    };
    EXPECT_EQ(driver_presets().size(), std::size(rows));
    for (const auto& row : rows) {
        const DriverPreset* p = find_driver(row.name);
        ASSERT_NE(p, nullptr) << row.name;
        EXPECT_EQ(p->timing.step_high, row.hi) << row.name;
        EXPECT_EQ(p->timing.step_low, row.lo) << row.name;
        EXPECT_EQ(p->timing.dir_hold, row.hold) << row.name;
        EXPECT_EQ(p->timing.dir_setup, row.setup) << row.name;
    }
    EXPECT_NE(find_driver("tmc2209"), nullptr);
    EXPECT_EQ(find_driver("L298"), nullptr);
}

TEST(Machine, NsToCyclesRoundsUp) {
    EXPECT_EQ(ns_to_cycles(0, 50e6), 0u);
    EXPECT_EQ(ns_to_cycles(20, 50e6), 1u);
    EXPECT_EQ(ns_to_cycles(21, 50e6), 2u);
    EXPECT_EQ(ns_to_cycles(19, 50e6), 1u);
    EXPECT_EQ(ns_to_cycles(970, 48e6), 47u);  // 46.56 -> 47
    EXPECT_EQ(ns_to_cycles(1900, 12e6), 23u); // 22.8 -> 23
    // Found by fuzz/fuzz_machine: past 2^32 - 1 cycles the count saturates (it was an
    // undefined double-to-unsigned conversion); bind_card refuses it.
    EXPECT_EQ(ns_to_cycles(2500, 4e101), UINT32_MAX);
    EXPECT_EQ(ns_to_cycles(1e300, 1e300), UINT32_MAX);
    EXPECT_EQ(ns_to_cycles(4294967294.0, 1e9), 4294967294u);
    // Every preset: cycles * period >= ns and (cycles - 1) * period < ns.
    for (double clk : {12e6, 25e6, 48e6, 50e6, 100e6, 133.33e6}) {
        for (const auto& p : driver_presets()) {
            for (double ns : {p.timing.step_high, p.timing.step_low, p.timing.dir_setup,
                              p.timing.dir_hold}) {
                const auto c = ns_to_cycles(ns, clk);
                EXPECT_GE(c * 1e9 / clk, ns * (1 - 1e-12)) << p.name << " " << clk;
                EXPECT_LT((c - 1.0) * 1e9 / clk, ns) << p.name << " " << clk;
            }
        }
    }
}

TEST(Machine, PlannerSection) {
    auto r = parse(std::string(kGood) +
                   "[planner]\narc_tolerance_mm = 0.01\njunction_deviation_mm = 0.05\n"
                   "chunk_tolerance_us = 2.5\non_limit = \"slow\"\nchunk_add2 = false\n"
                   "split_epsilon_steps = 0.1\ncurvature_step_ms = 8\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    EXPECT_EQ(r->planner.arc_tolerance_mm, 0.01);
    EXPECT_EQ(r->planner.junction_deviation_mm, 0.05);
    EXPECT_DOUBLE_EQ(r->planner.chunk_tolerance_s, 2.5e-6);
    EXPECT_DOUBLE_EQ(r->chunk_tolerance_cycles(), 125.0);
    EXPECT_EQ(r->planner.on_limit, OnLimit::slow);
    EXPECT_FALSE(r->planner.chunk_add2);
    EXPECT_EQ(r->planner.split_epsilon_steps, 0.1);
    EXPECT_DOUBLE_EQ(r->planner.curvature_step_s, 0.008);
}

struct BadCase {
    std::string text;
    std::string message;  // exact, whole diagnostic list
};

// [card] is optional (the card reports its clock, W and KMAX): without it the
// machine is unbound until bind_card(), which takes the card's values.
TEST(Machine, CardTableIsOptionalAndBindTakesTheCards) {
    auto r = parse(edit("[card]\nclock_hz = 50_000_000\n", ""));
    ASSERT_TRUE(r.ok()) << join(r.errors);
    Machine m = *r;
    EXPECT_EQ(m.card.clock_hz, 0.0);
    EXPECT_FALSE(m.card.bound);
    const auto errors = bind_card(m, {"test card", 20e6, 300, 5, 16});
    ASSERT_TRUE(errors.empty()) << join(errors);
    EXPECT_TRUE(m.card.bound);
    EXPECT_EQ(m.card.clock_hz, 20e6);
    EXPECT_EQ(m.card.pattern_capacity, 300u);
    EXPECT_EQ(m.card.max_doubling, 5u);
    // DM556 step_high 2500 ns at 20 MHz: 50 cycles.
    EXPECT_EQ(m.axes[0].pulse.step_high, 50u);
    // More than 2^32 - 1 cycles is refused, with 32-bit timing fields too (found by
    // fuzz/fuzz_machine: the count was an undefined double-to-unsigned conversion).
    Machine fast = *r;
    const auto refused = bind_card(fast, {"card D", 1e20, 1024, 8, 32});
    EXPECT_NE(join(refused).find("step_high is 4294967295 cycles at the card's 1e+20 Hz; the card, card D, times at "
                                 "most 4294967294 cycles (TW = 32 bits)"),
              std::string::npos)
        << join(refused);
    EXPECT_FALSE(fast.card.bound);
}

// Stated [card] keys are checked against the card; pulse times against its TW.
TEST(Machine, BindRefusesWhatTheCardCannotDo) {
    auto r = parse(kGood);
    ASSERT_TRUE(r.ok()) << join(r.errors);
    Machine m = *r;  // states clock_hz = 50 MHz
    auto errors = bind_card(m, {"card A", 40e6, 1024, 8, 16});
    EXPECT_EQ(join(errors),
              "mach.toml:2:12: card.clock_hz = 50000000, but the card, card A, runs at 40000000 Hz (leave the key "
              "out to plan with the card's clock)");
    EXPECT_FALSE(m.card.bound);
    EXPECT_EQ(m.card.clock_hz, 50e6) << "a refused bind leaves the machine as it was";
    // The card's clock, but timing fields of 6 bits (at most 63 cycles): DM556's
    // 2500 ns is 125 cycles at 50 MHz.
    errors = bind_card(m, {"card B", 50e6, 1024, 8, 6});
    ASSERT_FALSE(errors.empty());
    EXPECT_NE(join(errors).find("mach.toml:4:1: axes.x: step_high is 125 cycles at the card's 50000000 Hz; the card, "
                                "card B, times at most 63 cycles (TW = 6 bits)"),
              std::string::npos)
        << join(errors);
    EXPECT_TRUE(bind_card(m, {"card C", 50e6, 1024, 8, 16}).empty());
}

TEST(Machine, ErrorsNameFileLineColumn) {
    const BadCase cases[] = {
        {edit("steps_per_mm = 80", "steps_per_mm = 0"),
         "mach.toml:5:16: axes.x.steps_per_mm: must be > 0"},
        {edit("steps_per_mm = 80", "steps_per_mm = \"80\""),
         "mach.toml:5:16: axes.x.steps_per_mm: must be a number"},
        {edit("steps_per_mm = 80\n", ""), "mach.toml:4:1: axes.x.steps_per_mm: missing"},
        {edit("travel_max_mm = 300", "travel_max_mm = -5"),
         "mach.toml:7:17: axes.x.travel_max_mm: must be > travel_min_mm (0)"},
        {edit("travel_max_mm = 300", "travel_max_mm = 30000000"),
         "mach.toml:7:17: axes.x.travel_max_mm: 30000000 mm is 2.4e+09 steps at 80 steps/mm, past the card's "
         "signed 32-bit position (at most 2147483647 steps either way)"},
        {edit("travel_min_mm = 0", "travel_min_mm = -1e300"),
         "mach.toml:6:17: axes.x.travel_min_mm: -1e+300 mm is -8e+301 steps at 80 steps/mm, past the card's "
         "signed 32-bit position (at most 2147483647 steps either way)"},
        {edit("driver = \"dm556\"", "driver = \"L298\""),
         "mach.toml:11:10: axes.x.driver: unknown driver \"L298\" (known: DM556, M542, DM860T, "
         "TB6600, A4988, DRV8825, DRV8884, TMC2209)"},
        {edit("driver = \"dm556\"", "driver = \"dm556\"\nstep_low_ns = 5"),
         "mach.toml:11:10: axes.x.driver: give either driver or the four *_ns fields, not both"},
        {edit("driver = \"dm556\"\n", ""),
         "mach.toml:4:1: axes.x: missing pulse timing: give driver = \"NAME\" or step_high_ns, "
         "step_low_ns, dir_setup_ns, dir_hold_ns"},
        {edit("dir_hold_ns = 33\n", ""), "mach.toml:13:1: axes.y.dir_hold_ns: missing"},
        {edit("step_active_high = false", "step_active_high = 0"),
         "mach.toml:24:20: axes.y.step_active_high: must be true or false"},
        {edit("max_jerk_mm_s3 = 2000", "max_jerk = 2000"),
         "mach.toml:10:1: axes.x.max_jerk: unknown key\n"
         "mach.toml:4:1: axes.x.max_jerk_mm_s3: missing"},
        {edit("clock_hz = 50_000_000", "clock_hz = 50_000_000\nwidth = 3"),
         "mach.toml:3:1: card.width: unknown key"},
        {edit("clock_hz = 50_000_000", "clock_hz = -1"), "mach.toml:2:12: card.clock_hz: must be > 0"},
        {edit("clock_hz = 50_000_000", "clock_hz = 5e7\npattern_capacity = 1.5"),
         "mach.toml:3:20: card.pattern_capacity: must be an integer in 2..65536"},
        {edit("clock_hz = 50_000_000", "clock_hz = 5e7\nmax_doubling = 17"),
         "mach.toml:3:16: card.max_doubling: must be an integer in 0..16"},
        {edit("[axes.y]", "[axes.b]"), "mach.toml:13:7: axes.b: unknown key"},
        {std::string(kGood) + "[planner]\non_limit = \"fast\"\n",
         "mach.toml:27:12: planner.on_limit: must be \"refuse\" or \"slow\", not \"fast\""},
        {std::string(kGood) + "[planner]\nchunk_tolerance_us = 0.01\n",
         "mach.toml:27:22: planner.chunk_tolerance_us: must be at least one card clock cycle "
         "(0.02 us)"},
        {std::string(kGood) + "[planner]\nsplit_epsilon_steps = 0.5\n",
         "mach.toml:27:23: planner.split_epsilon_steps: must be in [0, 0.5)"},
        {std::string(kGood) + "[planner]\ncurvature_step_ms = 0\n",
         "mach.toml:27:21: planner.curvature_step_ms: must be > 0"},
        {std::string(kGood) + "[planner]\narc_tolerance_mm = 0\njunction_deviation_mm = -1\n",
         "mach.toml:27:20: planner.arc_tolerance_mm: must be > 0\nmach.toml:28:25: "
         "planner.junction_deviation_mm: must be >= 0"},
        {"[card]\nclock_hz = 1e6\n[axes]\n", "mach.toml:3:1: axes: at least one of axes.x, "
                                              "axes.y, axes.z, axes.a is needed"},
    };
    for (const auto& c : cases) {
        auto r = parse(c.text);
        EXPECT_FALSE(r.ok());
        EXPECT_EQ(join(r.errors), c.message) << c.text;
    }
}

TEST(Machine, AllErrorsAreCollected) {
    std::string s = edit("steps_per_mm = 80", "steps_per_mm = -1");
    auto pos = s.find("max_accel_mm_s2 = 400");
    s.replace(pos, 21, "max_accel_mm_s2 = 0");
    auto r = parse(s);
    ASSERT_EQ(r.errors.size(), 2u);
    EXPECT_EQ(r.errors[0].str(), "mach.toml:5:16: axes.x.steps_per_mm: must be > 0");
    EXPECT_EQ(r.errors[1].str(), "mach.toml:18:19: axes.y.max_accel_mm_s2: must be > 0");
}

TEST(Machine, TomlSyntaxErrorHasPosition) {
    auto r = parse("[card]\nclock_hz = = 3\n");
    ASSERT_EQ(r.errors.size(), 1u);
    // The message text is toml++'s; the position is ours to guarantee.
    EXPECT_EQ(r.errors[0].str().rfind("mach.toml:2:12: ", 0), 0u) << r.errors[0].str();
    EXPECT_GT(r.errors[0].message.size(), 5u);
}

TEST(Machine, LoadMissingFile) {
    auto r = load_machine("/nonexistent/m.toml");
    EXPECT_EQ(join(r.errors), "/nonexistent/m.toml: cannot open file");
}

// Limit switches and the probe (docs/CORE.md "Inputs", docs/PLANNING.md): each axis's
// limit_min / limit_max and [inputs]; a card without inputs refuses them at their
// key; the filter in card cycles, rounded up, within the 16-bit field.
TEST(Machine, LimitSwitchesAndTheInputsTable) {
    auto r = parse(edit("driver = \"dm556\"\n", "driver = \"dm556\"\nlimit_min = \"active_low\"\nlimit_max = \"active_high\"\n") +
                   "\n[inputs]\nfilter_us = 10.01\nprobe = \"active_low\"\n");
    ASSERT_TRUE(r.ok()) << join(r.errors);
    Machine m = *r;
    EXPECT_EQ(m.axes[0].limit_min, SwitchLevel::active_low);
    EXPECT_EQ(m.axes[0].limit_max, SwitchLevel::active_high);
    EXPECT_EQ(m.axes[1].limit_min, SwitchLevel::none) << "not given: not wired";
    EXPECT_FALSE(m.inputs.probe_active_high);

    CardFacts without{"card E", 50e6, 1024, 8, 16};
    const std::string refused = join(bind_card(m, without));
    EXPECT_NE(refused.find("mach.toml:12:13: axes.x: limit switches, but the card, card E, has no limit or probe inputs"),
              std::string::npos)
        << refused;
    EXPECT_NE(refused.find("mach.toml:29:1: inputs: the card, card E, has no limit or probe inputs"), std::string::npos)
        << refused;
    CardFacts with = without;
    with.inputs = true;
    ASSERT_TRUE(bind_card(m, with).empty());
    EXPECT_EQ(m.inputs.filter_cycles, 501u) << "10.01 us at 50 MHz is 500.5 cycles: rounded up";
    EXPECT_TRUE(m.card.inputs);

    auto slow = parse(std::string(kGood) + "\n[inputs]\nfilter_us = 2000\n");
    ASSERT_TRUE(slow.ok());
    Machine s = *slow;
    EXPECT_NE(join(bind_card(s, with)).find("inputs.filter_us: 2000 us is 100000 cycles"), std::string::npos);

    const auto bad = parse(edit("driver = \"dm556\"\n", "driver = \"dm556\"\nlimit_max = \"closed\"\n"));
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(join(bad.errors),
              "mach.toml:12:13: axes.x.limit_max: \"closed\" is none of \"none\", \"active_high\", \"active_low\"");
}

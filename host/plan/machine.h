// SPDX-License-Identifier: MIT
// The machine file: axes, card and planner settings, read from TOML.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "plan/common.h"
#include "plan/feed.h"

namespace cpstep::plan {

// STEP/DIR timing of one axis in nanoseconds, as a driver datasheet gives it.
struct PulseTimingNs {
    double step_high = 0;
    double step_low = 0;
    double dir_setup = 0;
    double dir_hold = 0;
};

// The same timing in card clock cycles, each rounded up (never shorter than
// the datasheet minimum).
struct PulseTimingCycles {
    std::uint32_t step_high = 0;
    std::uint32_t step_low = 0;
    std::uint32_t dir_setup = 0;
    std::uint32_t dir_hold = 0;
};

// A named driver's minimum timing (datasheet figures, ns).
struct DriverPreset {
    std::string_view name;
    PulseTimingNs timing;
};

// The built-in presets (DM556, M542, DM860T, TB6600, A4988, DRV8825,
// DRV8884, TMC2209).
std::span<const DriverPreset> driver_presets();
// Case-insensitive look-up; nullptr when unknown.
const DriverPreset* find_driver(std::string_view name);

// ceil(ns * clock_hz / 1e9), computed so that an exact product is not bumped
// up by floating-point noise; UINT32_MAX (saturated) when it is 2^32 - 1 or more.
std::uint32_t ns_to_cycles(double ns, double clock_hz);
PulseTimingCycles to_cycles(const PulseTimingNs& ns, double clock_hz);

// A limit switch of an axis (docs/CORE.md "Inputs"): not wired (the card ignores
// its pin), or active at a high or a low level.
enum class SwitchLevel { none, active_high, active_low };

// [axes.X.home]: the axis's homing cycle (docs/HOST.md "Homing"): fast approach to
// its limit switch, back off, slow approach, the trip there is `position_mm`, back
// off. The card stops an approach at the switch's trip at once (the seek, docs/CORE.md
// "Seek: homing and probing"), so both speeds must be ones the axis can stop from
// without a ramp.
struct HomeConfig {
    bool present = false;
    bool at_max = false;             // switch = "max": homes toward travel_max_mm
    double position_mm = 0;          // machine coordinate of the switch's trip (default: that end of the travel)
    double search_mm_s = 0;          // the fast approach
    double latch_mm_s = 0;           // the slow approach (<= search)
    double backoff_mm = 0;           // off the switch, between the approaches and at the end
    int sequence = 0;                // axes home in this order (ties: x, y, z, a)
    // `cpstep home` on the simulated card: where the simulated switch trips, mm from
    // where the simulated machine starts (its counters at 0). Not used on a real card.
    std::optional<double> sim_switch_mm;
    SourceLoc loc;                   // where [axes.X.home] starts
};

struct AxisConfig {
    bool present = false;
    double steps_per_mm = 0;        // card output steps (microsteps) per mm
    double travel_min_mm = 0;
    double travel_max_mm = 0;
    double max_velocity = 0;        // mm/s
    double max_accel = 0;           // mm/s^2
    double max_jerk = 0;            // mm/s^3
    std::string driver;             // preset name, empty when explicit
    PulseTimingNs pulse_ns;
    PulseTimingCycles pulse;        // derived from pulse_ns and card.clock_hz
    bool step_active_high = true;
    bool dir_positive_high = true;
    SwitchLevel limit_min = SwitchLevel::none, limit_max = SwitchLevel::none;
    SourceLoc limit_loc;            // the first limit_* key given (line 0: none)
    HomeConfig home;                // [axes.X.home] (present: the axis homes)
    SourceLoc loc;                  // where [axes.X] starts

    // Fastest step rate the card can emit without violating the pulse
    // timing: one step per (step_high + step_low) cycles.
    [[nodiscard]] double max_step_rate_hz(double clock_hz) const;
};

// The card the job is planned for. The values come from the card itself
// (bind_card(), with what it reports at connect); the machine file's [card] keys
// are optional and, where given, checked against the card, never trusted.
struct CardConfig {
    double clock_hz = 0;
    std::uint32_t pattern_capacity = 1024;  // W: longest reduced pattern
    std::uint32_t max_doubling = 8;         // k: largest step-doubling exponent
    std::uint32_t max_moves = 1048575;      // UMAX: most moves of one card segment
    unsigned conic_width = 0;               // CIW: the card's conic walker (0: none, arcs are chords)
    bool inputs = false;                    // the card has limit and probe inputs
    bool feed = false;                      // the card has feed hold and override
    bool bound = false;                     // set by bind_card()
    // What the machine file says, and where (line 0: not given).
    double stated_clock_hz = 0;
    std::uint32_t stated_pattern_capacity = 0, stated_max_doubling = 0;
    SourceLoc clock_loc, pattern_capacity_loc, max_doubling_loc;
};

// What a card reports of itself that the planner uses (card::CardCaps).
struct CardFacts {
    std::string name;            // e.g. "icebreaker (build b5ca169b)", for messages
    double clock_hz = 0;
    std::uint32_t pattern_capacity = 0;  // W
    std::uint32_t max_doubling = 0;      // KMAX
    unsigned timing_bits = 16;           // TW: pulse timing fields hold up to 2^TW - 1 cycles
    std::uint32_t max_moves = 1048575;   // UMAX
    unsigned conic_width = 0;            // CIW (READ 0x26): CONIC segments, 0: none
    bool inputs = false;                 // limit and probe inputs (READ 0x23 [24])
    bool feed = false;                   // feed hold and override (READ 0x23 [25])
};

// [feed]: feed hold and override on the card (docs/CORE.md "Feed hold and override").
struct FeedConfig {
    double max_override = 1.0;  // the largest override (max_override_pct / 100; 1..2)
    FeedRamp ramp;              // derived by bind_card on a card with FEED (CONFIG field 9)
    SourceLoc loc;              // where [feed] starts (line 0: not given)
};

// [inputs]: the card's input filter and the probe's level (docs/CORE.md "Inputs").
struct InputsConfig {
    double filter_us = 0;                // an input must hold ~3 samples this far apart
    std::uint32_t filter_cycles = 0;     // derived by bind_card (CONFIG field 6)
    bool probe_active_high = true;
    // G38 on the simulated card: the probe touches a plane across this axis at
    // sim_probe_mm from where the simulated machine starts; in contact on the far side
    // of it (-1: no simulated probe).
    int sim_probe_axis = -1;
    double sim_probe_mm = 0;
    SourceLoc loc;                       // where [inputs] starts (line 0: not given)
};

enum class OnLimit { refuse, slow };
// How G2/G3 arcs reach the card: as CONIC segments its walker steps (where the card
// has one and the arc qualifies, docs/PLANNING.md "Arcs as conics"), or as chords.
enum class ArcMode { conic, chords };

struct PlannerConfig {
    double arc_tolerance_mm = 0.002;        // max chord-to-arc distance
    double junction_deviation_mm = 0.01;    // Grbl-style corner model
    double chunk_tolerance_s = 1e-6;        // a move may be this much early, never late
    OnLimit on_limit = OnLimit::refuse;
    bool chunk_add2 = true;                 // allow the add2 chunk term
    double split_epsilon_steps = 0.02;      // target extra deviation of GCD splits
    // An acceleration step where the path's curvature jumps (a line into a
    // tangent arc) counts as a ramp over this time: each axis's share of it at
    // most its max_jerk times this (planner.cpp, docs/PLANNING.md).
    double curvature_step_s = 0.02;
    ArcMode arcs = ArcMode::conic;          // planner.arcs = "conic" | "chords"
    // Chains of G1 lines fitted with arcs (and collinear runs merged) within this
    // distance, mm (plan/arc_fit.h); 0: off.
    double fit_arcs_mm = 0;
};

// What the G-code reader takes from the machine file: the optional [gcode]
// table (docs/PLANNING.md, G-code). Every key is optional.
enum class MissingZ { refuse, ignore };

struct GcodeConfig {
    // Z words on a machine without axes.z: an error (refuse) or dropped with one
    // summarized warning (ignore). gcode.z_words = "refuse" | "ignore".
    MissingZ z_words = MissingZ::refuse;
    // G28 / G30 home positions in machine mm (A in degrees); axes not given are 0.
    // gcode.g28_position = { x = 0, y = 0, z = 0 }. Unset: the machine origin.
    std::optional<PerAxis<double>> g28_position;
    std::optional<PerAxis<double>> g30_position;
    // Tool lengths for G43 H<n>, mm: [gcode.tool_lengths] 1 = 25.4. Empty: G43
    // with a tool other than 0 is refused.
    std::map<int, double> tool_lengths;
    SourceLoc loc;  // where [gcode] starts (line 0: not given)
};

struct Machine {
    std::string file;
    PerAxis<AxisConfig> axes;
    CardConfig card;
    PlannerConfig planner;
    GcodeConfig gcode;
    InputsConfig inputs;
    FeedConfig feed;

    [[nodiscard]] double chunk_tolerance_cycles() const {
        return planner.chunk_tolerance_s * card.clock_hz;
    }
};

// Plans `m` for this card: its clock, W and KMAX, and every axis's pulse timing
// in its cycles. Errors (each at the machine file's line and column): a stated
// [card] clock_hz other than the card's, a stated pattern_capacity or
// max_doubling above the card's (a smaller one is kept: the planner uses it), a
// pulse time longer than the card's timing fields hold, a chunk tolerance below
// one card cycle. On error `m` is left as it was.
std::vector<Diagnostic> bind_card(Machine& m, const CardFacts& card);

// Parse a machine file held in memory; `file` names it in diagnostics.
Result<Machine> parse_machine(std::string_view text, std::string_view file);
// Read and parse a machine file from disk.
Result<Machine> load_machine(const std::filesystem::path& path);

}  // namespace cpstep::plan

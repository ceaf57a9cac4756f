// SPDX-License-Identifier: MIT
#include "plan/machine.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

namespace cpstep::plan {

namespace {

// Datasheet minimums. Order in the brief's table is high/low/hold/setup.
constexpr DriverPreset kPresets[] = {
    {"DM556", {2500, 2500, 5000, 10000}},
    {"M542", {1500, 1500, 5000, 8000}},
    {"DM860T", {5000, 5000, 5000, 5000}},
    {"TB6600", {5000, 5000, 20000, 20000}},
    {"A4988", {1000, 1000, 200, 200}},
    {"DRV8825", {1900, 1900, 650, 650}},
    {"DRV8884", {970, 970, 200, 200}},
    {"TMC2209", {100, 100, 20, 20}},
};

SourceLoc loc_of(const toml::node& n) {
    const auto& src = n.source();
    return {static_cast<int>(src.begin.line), static_cast<int>(src.begin.column)};
}

// Reads typed fields out of a table, recording every problem with its path
// and position; never stops at the first error.
class Reader {
public:
    explicit Reader(std::string file) : file_(std::move(file)) {}

    void error(SourceLoc loc, std::string msg) { errors_.push_back({file_, loc, std::move(msg)}); }

    const toml::node* field(const toml::table& t, std::string_view path, std::string_view key,
                            bool required) {
        const toml::node* n = t.get(key);
        if (n == nullptr && required) {
            error(loc_of(t), fmt::format("{}.{}: missing", path, key));
        }
        return n;
    }

    // A number (integer or float) that must satisfy `pred`; `what` says how.
    std::optional<double> number(const toml::table& t, std::string_view path,
                                 std::string_view key, bool required, bool (*pred)(double),
                                 std::string_view what) {
        const toml::node* n = field(t, path, key, required);
        if (n == nullptr) return std::nullopt;
        if (!n->is_number()) {
            error(loc_of(*n), fmt::format("{}.{}: must be a number", path, key));
            return std::nullopt;
        }
        const double v = n->value<double>().value_or(0.0);
        if (!std::isfinite(v) || !pred(v)) {
            error(loc_of(*n), fmt::format("{}.{}: must be {}", path, key, what));
            return std::nullopt;
        }
        return v;
    }

    std::optional<bool> boolean(const toml::table& t, std::string_view path, std::string_view key) {
        const toml::node* n = field(t, path, key, false);
        if (n == nullptr) return std::nullopt;
        if (!n->is_boolean()) {
            error(loc_of(*n), fmt::format("{}.{}: must be true or false", path, key));
            return std::nullopt;
        }
        return n->value<bool>();
    }

    std::optional<std::string> string(const toml::table& t, std::string_view path,
                                      std::string_view key) {
        const toml::node* n = field(t, path, key, false);
        if (n == nullptr) return std::nullopt;
        if (!n->is_string()) {
            error(loc_of(*n), fmt::format("{}.{}: must be a string", path, key));
            return std::nullopt;
        }
        return n->value<std::string>();
    }

    const toml::table* table(const toml::table& t, std::string_view path, std::string_view key,
                             bool required) {
        const toml::node* n = t.get(key);
        if (n == nullptr) {
            if (required) errors_.push_back({file_, {}, fmt::format("{}: missing table", path)});
            return nullptr;
        }
        if (!n->is_table()) {
            error(loc_of(*n), fmt::format("{}: must be a table", path));
            return nullptr;
        }
        return n->as_table();
    }

    // Typos must not silently become defaults.
    void only_keys(const toml::table& t, std::string_view path,
                   std::initializer_list<std::string_view> allowed) {
        for (auto&& [k, v] : t) {
            if (std::find(allowed.begin(), allowed.end(), k.str()) == allowed.end()) {
                const auto& src = k.source();
                SourceLoc loc{static_cast<int>(src.begin.line), static_cast<int>(src.begin.column)};
                if (loc.line == 0) loc = loc_of(v);
                error(loc, fmt::format("{}{}{}: unknown key", path, path.empty() ? "" : ".",
                                       k.str()));
            }
        }
    }

    std::vector<Diagnostic>& errors() { return errors_; }
    const std::string& file() const { return file_; }

private:
    std::string file_;
    std::vector<Diagnostic> errors_;
};

bool positive(double v) { return v > 0; }
bool non_negative(double v) { return v >= 0; }
bool any_value(double) { return true; }
bool capacity_ok(double v) { return v >= 2 && v <= 65536 && v == std::floor(v); }
bool doubling_ok(double v) { return v >= 0 && v <= 16 && v == std::floor(v); }
bool split_eps_ok(double v) { return v >= 0 && v < 0.5; }
bool fit_ok(double v) { return v >= 0 && v <= 1; }

std::string upper(std::string_view s) {
    std::string out(s);
    for (auto& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return out;
}

// [axes.X.home]: switch, position_mm, search_mm_s, latch_mm_s, backoff_mm, sequence,
// sim_switch_mm; checked against the axis (its switch wired, speeds within its limit).
void read_home(Reader& r, const toml::table& t, const std::string& path, AxisConfig& ax) {
    HomeConfig& h = ax.home;
    h.present = true;
    h.loc = loc_of(t);
    r.only_keys(t, path, {"switch", "position_mm", "search_mm_s", "latch_mm_s", "backoff_mm", "sequence",
                          "sim_switch_mm"});
    const auto sw = r.string(t, path, "switch");
    if (!sw && !t.contains("switch")) r.error(h.loc, fmt::format("{}.switch: missing (\"min\" or \"max\")", path));
    if (sw && *sw != "min" && *sw != "max")
        r.error(loc_of(*t.get("switch")), fmt::format("{}.switch: \"{}\" is neither \"min\" nor \"max\"", path, *sw));
    h.at_max = sw && *sw == "max";
    if (sw && (h.at_max ? ax.limit_max : ax.limit_min) == SwitchLevel::none)
        r.error(loc_of(*t.get("switch")),
                fmt::format("{}.switch: homing on the {} switch needs it wired (limit_{} = \"active_high\" or "
                            "\"active_low\")", path, *sw, *sw));
    h.position_mm = r.number(t, path, "position_mm", false, any_value, "finite")
                        .value_or(h.at_max ? ax.travel_max_mm : ax.travel_min_mm);
    h.search_mm_s = r.number(t, path, "search_mm_s", true, positive, "> 0").value_or(0);
    h.latch_mm_s = r.number(t, path, "latch_mm_s", true, positive, "> 0").value_or(0);
    h.backoff_mm = r.number(t, path, "backoff_mm", true, positive, "> 0").value_or(0);
    if (ax.max_velocity > 0 && h.search_mm_s > ax.max_velocity)
        r.error(loc_of(*t.get("search_mm_s")), fmt::format("{}.search_mm_s: {} is above the axis's max_velocity_mm_s ({})",
                                                          path, h.search_mm_s, ax.max_velocity));
    if (h.latch_mm_s > 0 && h.search_mm_s > 0 && h.latch_mm_s > h.search_mm_s)
        r.error(loc_of(*t.get("latch_mm_s")),
                fmt::format("{}.latch_mm_s: {} is above search_mm_s ({}): the slow approach must be the slower",
                            path, h.latch_mm_s, h.search_mm_s));
    const auto seq = r.number(t, path, "sequence", false, [](double v) { return v >= 0 && v <= 9 && v == std::floor(v); },
                              "a whole number 0..9");
    h.sequence = int(seq.value_or(0));
    h.sim_switch_mm = r.number(t, path, "sim_switch_mm", false, any_value, "finite");
}

void read_axis(Reader& r, const toml::table& t, std::string_view path, AxisConfig& ax) {
    ax.present = true;
    ax.loc = loc_of(t);
    r.only_keys(t, path,
                {"steps_per_mm", "travel_min_mm", "travel_max_mm", "max_velocity_mm_s",
                 "max_accel_mm_s2", "max_jerk_mm_s3", "driver", "step_high_ns", "step_low_ns",
                 "dir_setup_ns", "dir_hold_ns", "step_active_high", "dir_positive_high", "limit_min",
                 "limit_max", "home"});
    const auto gt0 = "> 0";
    ax.steps_per_mm = r.number(t, path, "steps_per_mm", true, positive, gt0).value_or(0);
    auto tmin = r.number(t, path, "travel_min_mm", true, any_value, "finite");
    auto tmax = r.number(t, path, "travel_max_mm", true, any_value, "finite");
    if (tmin && tmax && !(*tmax > *tmin)) {
        r.error(loc_of(*t.get("travel_max_mm")),
                fmt::format("{}.travel_max_mm: must be > travel_min_mm ({})", path, *tmin));
    }
    // The card counts each axis's position in a signed 32-bit register (READ
    // 0x10 + i, docs/CORE.md): every point of the travel must have a step
    // count it can hold, or the position it reports wraps.
    constexpr double kPosMax = 2147483647.0;
    for (const auto& [key, v] : {std::pair{"travel_min_mm", tmin}, std::pair{"travel_max_mm", tmax}}) {
        if (!v || !(ax.steps_per_mm > 0)) continue;
        if (!(std::abs(*v * ax.steps_per_mm) <= kPosMax)) {
            r.error(loc_of(*t.get(key)),
                    fmt::format("{}.{}: {} mm is {:.6g} steps at {} steps/mm, past the card's "
                                "signed 32-bit position (at most {:.0f} steps either way)",
                                path, key, *v, *v * ax.steps_per_mm, ax.steps_per_mm, kPosMax));
        }
    }
    ax.travel_min_mm = tmin.value_or(0);
    ax.travel_max_mm = tmax.value_or(0);
    ax.max_velocity = r.number(t, path, "max_velocity_mm_s", true, positive, gt0).value_or(0);
    ax.max_accel = r.number(t, path, "max_accel_mm_s2", true, positive, gt0).value_or(0);
    ax.max_jerk = r.number(t, path, "max_jerk_mm_s3", true, positive, gt0).value_or(0);

    static constexpr std::string_view kTiming[] = {"step_high_ns", "step_low_ns", "dir_setup_ns",
                                                   "dir_hold_ns"};
    const bool any_explicit = std::any_of(std::begin(kTiming), std::end(kTiming),
                                          [&](std::string_view k) { return t.contains(k); });
    if (auto drv = r.string(t, path, "driver")) {
        if (any_explicit) {
            r.error(loc_of(*t.get("driver")),
                    fmt::format("{}.driver: give either driver or the four *_ns fields, not both",
                                path));
        }
        if (const DriverPreset* p = find_driver(*drv)) {
            ax.driver = std::string(p->name);
            ax.pulse_ns = p->timing;
        } else {
            std::string names;
            for (const auto& pr : driver_presets()) {
                names += names.empty() ? "" : ", ";
                names += pr.name;
            }
            r.error(loc_of(*t.get("driver")),
                    fmt::format("{}.driver: unknown driver \"{}\" (known: {})", path, *drv, names));
        }
    } else if (t.contains("driver")) {
        // wrong type, already reported
    } else if (!any_explicit) {
        r.error(loc_of(t), fmt::format("{}: missing pulse timing: give driver = \"NAME\" or "
                                       "step_high_ns, step_low_ns, dir_setup_ns, dir_hold_ns",
                                       path));
    } else {
        ax.pulse_ns.step_high = r.number(t, path, "step_high_ns", true, positive, gt0).value_or(0);
        ax.pulse_ns.step_low = r.number(t, path, "step_low_ns", true, positive, gt0).value_or(0);
        ax.pulse_ns.dir_setup =
            r.number(t, path, "dir_setup_ns", true, non_negative, ">= 0").value_or(0);
        ax.pulse_ns.dir_hold =
            r.number(t, path, "dir_hold_ns", true, non_negative, ">= 0").value_or(0);
    }
    ax.step_active_high = r.boolean(t, path, "step_active_high").value_or(true);
    ax.dir_positive_high = r.boolean(t, path, "dir_positive_high").value_or(true);
    for (const auto& [key, level] : {std::pair{"limit_min", &ax.limit_min}, std::pair{"limit_max", &ax.limit_max}}) {
        const auto s = r.string(t, path, key);
        if (!s) continue;
        if (ax.limit_loc.line == 0) ax.limit_loc = loc_of(*t.get(key));
        if (*s == "none") *level = SwitchLevel::none;
        else if (*s == "active_high") *level = SwitchLevel::active_high;
        else if (*s == "active_low") *level = SwitchLevel::active_low;
        else
            r.error(loc_of(*t.get(key)),
                    fmt::format("{}.{}: \"{}\" is none of \"none\", \"active_high\", \"active_low\"", path, key, *s));
    }
    const std::string hpath = std::string(path) + ".home";
    if (const toml::table* h = r.table(t, hpath, "home", false)) read_home(r, *h, hpath, ax);
}

// [gcode]: z_words, g28_position, g30_position, [gcode.tool_lengths].
void read_gcode(Reader& r, const toml::table& t, GcodeConfig& g) {
    g.loc = loc_of(t);
    r.only_keys(t, "gcode", {"z_words", "g28_position", "g30_position", "tool_lengths"});
    if (auto s = r.string(t, "gcode", "z_words")) {
        if (*s == "refuse") {
            g.z_words = MissingZ::refuse;
        } else if (*s == "ignore") {
            g.z_words = MissingZ::ignore;
        } else {
            r.error(loc_of(*t.get("z_words")),
                    fmt::format("gcode.z_words: must be \"refuse\" or \"ignore\", not \"{}\"", *s));
        }
    }
    for (const char* key : {"g28_position", "g30_position"}) {
        const std::string path = std::string("gcode.") + key;
        if (const toml::table* pt = r.table(t, path, key, false)) {
            r.only_keys(*pt, path, {"x", "y", "z", "a"});
            PerAxis<double> p{};
            for (std::size_t i = 0; i < kAxes; ++i) {
                p[i] = r.number(*pt, path, std::string_view(&kAxisLetters[i], 1), false, any_value,
                                "finite")
                           .value_or(0.0);
            }
            (std::string_view(key) == "g28_position" ? g.g28_position : g.g30_position) = p;
        }
    }
    if (const toml::table* tl = r.table(t, "gcode.tool_lengths", "tool_lengths", false)) {
        for (auto&& [k, v] : *tl) {
            const std::string key(k.str());
            int n = -1;
            if (!key.empty() && key.size() < 6 &&
                std::all_of(key.begin(), key.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; })) {
                n = std::stoi(key);
            }
            if (n < 1) {
                r.error(loc_of(v), fmt::format("gcode.tool_lengths.{}: the key must be a tool number "
                                               "1..99999", key));
                continue;
            }
            if (auto len = r.number(*tl, "gcode.tool_lengths", key, true, any_value, "finite")) {
                g.tool_lengths[n] = *len;
            }
        }
    }
}

}  // namespace

std::span<const DriverPreset> driver_presets() { return kPresets; }

const DriverPreset* find_driver(std::string_view name) {
    const std::string want = upper(name);
    for (const auto& p : kPresets) {
        if (p.name == want) return &p;
    }
    return nullptr;
}

std::uint32_t ns_to_cycles(double ns, double clock_hz) {
    const double exact = ns * clock_hz / 1e9;
    // Saturated (bind_card refuses it): converting a double past 2^32 - 1 is undefined.
    if (!(exact < 4294967295.0)) return UINT32_MAX;
    // A product like 2500 ns * 50 MHz = 125.00000000000001 must stay 125.
    const double rounded = std::round(exact);
    if (std::abs(exact - rounded) <= 1e-9 * std::max(1.0, rounded)) {
        return static_cast<std::uint32_t>(rounded);
    }
    return static_cast<std::uint32_t>(std::ceil(exact));
}

PulseTimingCycles to_cycles(const PulseTimingNs& ns, double clock_hz) {
    return {ns_to_cycles(ns.step_high, clock_hz), ns_to_cycles(ns.step_low, clock_hz),
            ns_to_cycles(ns.dir_setup, clock_hz), ns_to_cycles(ns.dir_hold, clock_hz)};
}

double AxisConfig::max_step_rate_hz(double clock_hz) const {
    const double period = static_cast<double>(pulse.step_high) + static_cast<double>(pulse.step_low);
    return clock_hz / std::max(1.0, period);
}

Result<Machine> parse_machine(std::string_view text, std::string_view file) {
    Result<Machine> result;
    Reader r{std::string(file)};
    toml::table root;
    try {
        root = toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        result.errors.push_back({std::string(file),
                                 {static_cast<int>(b.line), static_cast<int>(b.column)},
                                 std::string(e.description())});
        return result;
    }

    Machine m;
    m.file = std::string(file);
    r.only_keys(root, "", {"card", "planner", "axes", "gcode", "inputs", "feed"});
    if (const toml::table* fd = r.table(root, "feed", "feed", false)) {
        r.only_keys(*fd, "feed", {"max_override_pct"});
        m.feed.loc = loc_of(*fd);
        m.feed.max_override =
            r.number(*fd, "feed", "max_override_pct", false, [](double v) { return v >= 100 && v <= 200; },
                     "from 100 to 200")
                .value_or(100) /
            100.0;
    }
    if (const toml::table* in = r.table(root, "inputs", "inputs", false)) {
        r.only_keys(*in, "inputs", {"filter_us", "probe", "sim_probe_mm"});
        m.inputs.loc = loc_of(*in);
        m.inputs.filter_us = r.number(*in, "inputs", "filter_us", false, non_negative, ">= 0").value_or(0);
        if (const auto s = r.string(*in, "inputs", "probe")) {
            if (*s == "active_high" || *s == "active_low") m.inputs.probe_active_high = *s == "active_high";
            else
                r.error(loc_of(*in->get("probe")),
                        fmt::format("inputs.probe: \"{}\" is neither \"active_high\" nor \"active_low\"", *s));
        }
        // The simulated probe: one axis's place, mm from the start (a touch plate).
        if (const toml::table* sp = r.table(*in, "inputs.sim_probe_mm", "sim_probe_mm", false)) {
            r.only_keys(*sp, "inputs.sim_probe_mm", {"x", "y", "z", "a"});
            for (std::size_t i = 0; i < kAxes; ++i) {
                const auto v = r.number(*sp, "inputs.sim_probe_mm", std::string_view(&kAxisLetters[i], 1), false,
                                        any_value, "finite");
                if (!v) continue;
                if (m.inputs.sim_probe_axis >= 0)
                    r.error(loc_of(*sp), "inputs.sim_probe_mm: give one axis (the simulated probe is a plane across it)");
                m.inputs.sim_probe_axis = int(i);
                m.inputs.sim_probe_mm = *v;
            }
        }
    }

    // [card] is optional: the card reports its clock, W and KMAX at connect
    // (bind_card()); what is stated here is checked against it.
    if (const toml::table* card = r.table(root, "card", "card", false)) {
        r.only_keys(*card, "card", {"clock_hz", "pattern_capacity", "max_doubling"});
        auto& c = m.card;
        if (auto v = r.number(*card, "card", "clock_hz", false, positive, "> 0")) {
            c.stated_clock_hz = c.clock_hz = *v;
            c.clock_loc = loc_of(*card->get("clock_hz"));
        }
        if (auto v = r.number(*card, "card", "pattern_capacity", false, capacity_ok,
                              "an integer in 2..65536")) {
            c.stated_pattern_capacity = c.pattern_capacity = static_cast<std::uint32_t>(*v);
            c.pattern_capacity_loc = loc_of(*card->get("pattern_capacity"));
        }
        if (auto v = r.number(*card, "card", "max_doubling", false, doubling_ok, "an integer in 0..16")) {
            c.stated_max_doubling = c.max_doubling = static_cast<std::uint32_t>(*v);
            c.max_doubling_loc = loc_of(*card->get("max_doubling"));
        }
    }

    if (const toml::table* pl = r.table(root, "planner", "planner", false)) {
        r.only_keys(*pl, "planner",
                    {"arc_tolerance_mm", "junction_deviation_mm", "chunk_tolerance_us",
                     "on_limit", "chunk_add2", "split_epsilon_steps", "curvature_step_ms", "arcs",
                     "fit_arcs_mm"});
        auto& p = m.planner;
        p.arc_tolerance_mm = r.number(*pl, "planner", "arc_tolerance_mm", false, positive, "> 0")
                                 .value_or(p.arc_tolerance_mm);
        p.junction_deviation_mm =
            r.number(*pl, "planner", "junction_deviation_mm", false, non_negative, ">= 0")
                .value_or(p.junction_deviation_mm);
        if (auto us = r.number(*pl, "planner", "chunk_tolerance_us", false, positive, "> 0")) {
            p.chunk_tolerance_s = *us * 1e-6;
            if (m.card.clock_hz > 0 && p.chunk_tolerance_s * m.card.clock_hz < 1.0) {
                r.error(loc_of(*pl->get("chunk_tolerance_us")),
                        fmt::format("planner.chunk_tolerance_us: must be at least one card "
                                    "clock cycle ({} us)",
                                    1e6 / m.card.clock_hz));
            }
        }
        if (auto s = r.string(*pl, "planner", "on_limit")) {
            if (*s == "refuse") {
                p.on_limit = OnLimit::refuse;
            } else if (*s == "slow") {
                p.on_limit = OnLimit::slow;
            } else {
                r.error(loc_of(*pl->get("on_limit")),
                        fmt::format("planner.on_limit: must be \"refuse\" or \"slow\", not \"{}\"",
                                    *s));
            }
        }
        if (auto s = r.string(*pl, "planner", "arcs")) {
            if (*s == "conic") {
                p.arcs = ArcMode::conic;
            } else if (*s == "chords") {
                p.arcs = ArcMode::chords;
            } else {
                r.error(loc_of(*pl->get("arcs")),
                        fmt::format("planner.arcs: must be \"conic\" or \"chords\", not \"{}\"", *s));
            }
        }
        p.fit_arcs_mm = r.number(*pl, "planner", "fit_arcs_mm", false, fit_ok, "in [0, 1]")
                            .value_or(p.fit_arcs_mm);
        if (auto ms = r.number(*pl, "planner", "curvature_step_ms", false, positive, "> 0"))
            p.curvature_step_s = *ms * 1e-3;
        p.chunk_add2 = r.boolean(*pl, "planner", "chunk_add2").value_or(p.chunk_add2);
        p.split_epsilon_steps =
            r.number(*pl, "planner", "split_epsilon_steps", false, split_eps_ok, "in [0, 0.5)")
                .value_or(p.split_epsilon_steps);
    }

    // [gcode] is optional: what the G-code reader takes from the machine.
    if (const toml::table* gc = r.table(root, "gcode", "gcode", false)) {
        read_gcode(r, *gc, m.gcode);
    }

    if (const toml::table* axes = r.table(root, "axes", "axes", true)) {
        r.only_keys(*axes, "axes", {"x", "y", "z", "a"});
        bool any = false;
        for (int i = 0; i < kAxes; ++i) {
            const std::string key(1, kAxisLetters[static_cast<std::size_t>(i)]);
            const std::string path = "axes." + key;
            if (const toml::table* t = r.table(*axes, path, key, false)) {
                read_axis(r, *t, path, m.axes[static_cast<std::size_t>(i)]);
                any = true;
            }
        }
        if (!any && r.errors().empty()) {
            r.error(loc_of(*axes), "axes: at least one of axes.x, axes.y, axes.z, axes.a is needed");
        }
    }

    for (auto& ax : m.axes) {
        if (ax.present && m.card.clock_hz > 0) ax.pulse = to_cycles(ax.pulse_ns, m.card.clock_hz);
    }

    result.errors = std::move(r.errors());
    if (result.errors.empty()) result.value = std::move(m);
    return result;
}

std::vector<Diagnostic> bind_card(Machine& m, const CardFacts& card) {
    std::vector<Diagnostic> errors;
    const auto error = [&](SourceLoc loc, std::string message) {
        errors.push_back({m.file, loc, std::move(message)});
    };
    const CardConfig& c = m.card;
    if (c.stated_clock_hz > 0 && c.stated_clock_hz != card.clock_hz)
        error(c.clock_loc, fmt::format("card.clock_hz = {}, but the card, {}, runs at {} Hz "
                                       "(leave the key out to plan with the card's clock)",
                                       c.stated_clock_hz, card.name, card.clock_hz));
    if (c.stated_pattern_capacity > card.pattern_capacity)
        error(c.pattern_capacity_loc,
              fmt::format("card.pattern_capacity = {}, but the card, {}, builds patterns of at most {} moves",
                          c.stated_pattern_capacity, card.name, card.pattern_capacity));
    if (c.stated_max_doubling > card.max_doubling)
        error(c.max_doubling_loc,
              fmt::format("card.max_doubling = {}, but the card, {}, doubles at most k = {}",
                          c.stated_max_doubling, card.name, card.max_doubling));
    const double cycles = m.planner.chunk_tolerance_s * card.clock_hz;
    if (cycles < 1.0)
        error({}, fmt::format("planner.chunk_tolerance_us: {} us is less than one cycle of the card, {} ({} us)",
                              m.planner.chunk_tolerance_s * 1e6, card.name, 1e6 / card.clock_hz));
    // UINT32_MAX is ns_to_cycles' saturation: never a time the card can hold.
    const std::uint64_t max_cycles =
        card.timing_bits >= 32 ? UINT32_MAX - 1 : (std::uint64_t(1) << card.timing_bits) - 1;
    PerAxis<PulseTimingCycles> pulse{};
    for (int a = 0; a < kAxes; ++a) {
        const AxisConfig& ax = m.axes[static_cast<std::size_t>(a)];
        if (!ax.present) continue;
        pulse[static_cast<std::size_t>(a)] = to_cycles(ax.pulse_ns, card.clock_hz);
        const PulseTimingCycles& p = pulse[static_cast<std::size_t>(a)];
        const std::pair<const char*, std::uint32_t> fields[] = {
            {"step_high", p.step_high}, {"step_low", p.step_low}, {"dir_setup", p.dir_setup}, {"dir_hold", p.dir_hold}};
        for (const auto& [name, v] : fields)
            if (v > max_cycles)
                error(ax.loc, fmt::format("axes.{}: {} is {} cycles at the card's {} Hz; the card, {}, times at "
                                          "most {} cycles (TW = {} bits)",
                                          kAxisLetters[static_cast<std::size_t>(a)], name, v, card.clock_hz,
                                          card.name, max_cycles, card.timing_bits));
    }
    // Limit switches and the probe need a card with inputs; the filter, a period its
    // 16-bit field holds.
    const double filter_cycles = std::ceil(m.inputs.filter_us * 1e-6 * card.clock_hz);
    for (int a = 0; a < kAxes && !card.inputs; ++a) {
        const AxisConfig& ax = m.axes[static_cast<std::size_t>(a)];
        if (ax.present && (ax.limit_min != SwitchLevel::none || ax.limit_max != SwitchLevel::none))
            error(ax.limit_loc, fmt::format("axes.{}: limit switches, but the card, {}, has no limit or probe inputs",
                                            kAxisLetters[static_cast<std::size_t>(a)], card.name));
    }
    if (!card.inputs && m.inputs.loc.line != 0)
        error(m.inputs.loc, fmt::format("inputs: the card, {}, has no limit or probe inputs", card.name));
    if (filter_cycles > 65535)
        error(m.inputs.loc, fmt::format("inputs.filter_us: {} us is {:.0f} cycles at the card's {} Hz; the filter "
                                        "holds at most 65535",
                                        m.inputs.filter_us, filter_cycles, card.clock_hz));
    // Feed hold and override: a card that has them, and a ramp its fields hold.
    std::optional<FeedRamp> ramp;
    if (!card.feed && m.feed.loc.line != 0)
        error(m.feed.loc, fmt::format("feed: the card, {}, has no feed hold or override", card.name));
    if (card.feed) {
        const FeedLimits l = feed_limits(m);
        ramp = feed_ramp(card.clock_hz, l.rate_per_s, l.accel_per_s2, l.span);
        if (!ramp)
            error(m.feed.loc, fmt::format("feed: the axes' limits ask a scale rate of at most {:.4g}/s and "
                                          "{:.4g}/s^2, a ramp slower than the card's tick field holds at {} Hz",
                                          l.rate_per_s, l.accel_per_s2, card.clock_hz));
    }
    if (!errors.empty()) return errors;
    m.card.feed = card.feed;
    m.feed.ramp = ramp.value_or(FeedRamp{});
    m.inputs.filter_cycles = static_cast<std::uint32_t>(filter_cycles);
    m.card.inputs = card.inputs;
    m.card.clock_hz = card.clock_hz;
    m.card.pattern_capacity = c.stated_pattern_capacity ? c.stated_pattern_capacity : card.pattern_capacity;
    m.card.max_doubling = c.stated_max_doubling ? c.stated_max_doubling : card.max_doubling;
    m.card.max_moves = card.max_moves;
    m.card.conic_width = card.conic_width;
    m.card.bound = true;
    for (int a = 0; a < kAxes; ++a)
        if (m.axes[static_cast<std::size_t>(a)].present)
            m.axes[static_cast<std::size_t>(a)].pulse = pulse[static_cast<std::size_t>(a)];
    return errors;
}

Result<Machine> load_machine(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        Result<Machine> r;
        r.errors.push_back({path.string(), {}, "cannot open file"});
        return r;
    }
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_machine(ss.str(), path.string());
}

}  // namespace cpstep::plan

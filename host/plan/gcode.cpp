// SPDX-License-Identifier: MIT
#include "plan/gcode.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "plan/gcode_expr.h"
#include "plan/nurbs.h"

namespace cpstep::plan {

namespace {

using gcode::Word;

// G codes are compared as integers in tenths (G61.1 -> 611).
constexpr int g(int whole, int tenth = 0) { return whole * 10 + tenth; }

constexpr std::string_view kIgnored[] = {"G40", "G49", "G54", "G61", "G61.1", "G64", "G80",
                                         "G94", "G97", "M6",  "M7",  "M8",    "M9",  "M48",
                                         "M49", "T"};

constexpr std::size_t X = 0, Y = 1, Z = 2, A = 3;

// LinuxCNC's arc tolerances (interp_internal.hh), in mm.
constexpr double kRadiusTolerance = 0.00005 * 25.4;  // R arcs may fall this short; smaller radius = zero
constexpr double kSpiralAbs = 0.005;                  // centre arcs: end radius may differ by this ...
constexpr double kSpiralRel = 0.001;                  // ... or by this fraction of the radius
constexpr double kPeckRetract = 0.010 * 25.4;         // G73 retract, G83 rapid-down clearance
// T and H: tool numbers as the machine file's [gcode.tool_lengths] keys (1..99999), or 0.
constexpr double kMaxTool = 99999;

bool is_probe(int m) { return m >= g(38, 2) && m <= g(38, 5); }
bool is_spline(int m) { return m == g(5) || m == g(5, 1) || m == g(5, 2) || m == g(5, 3); }

bool is_cycle(int m) {
    return m == g(73) || m == g(81) || m == g(82) || m == g(83) || m == g(85) || m == g(86) ||
           m == g(89);
}

std::string gname(int code) {
    return code % 10 ? fmt::format("G{}.{}", code / 10, code % 10) : fmt::format("G{}", code / 10);
}

// Modal state carried from line to line.
struct State {
    std::optional<int> motion;     // g(0..3), a cycle, or nullopt (none / G80)
    Plane plane = Plane::xy;
    double unit = 1.0;             // mm per program unit (25.4 after G20)
    bool units_set = false;
    bool absolute = true;          // G90 / G91
    bool arc_absolute = false;     // G90.1 / G91.1
    bool retract_old_z = true;     // G98 (true) / G99
    int cs = 1;                    // G54 = 1 ... G59.3 = 9
    std::array<PerAxis<double>, 9> cs_offset{};  // machine mm
    PerAxis<double> g92{};         // G92 offset, machine mm
    bool g92_on = false;
    double tlo = 0;                // tool length offset (Z), mm
    PerAxis<double> pos{};         // current machine position, mm (A: degrees)
    PerAxis<bool> known{true, true, true, true};  // false after a refused block left it unknown
    std::optional<double> feed;    // F in program units per minute
    bool feed_known = true;
    bool spindle_on = false;
    bool spindle_ccw = false;
    double spindle_speed = 0;
    // Digital output P0 (the card's torch output, with the spindle): M64/M65 set it
    // for the blocks after them; M62/M63 from the next motion on (LinuxCNC's "at the
    // beginning of the next motion command"), held here until then.
    bool output0 = false;
    std::optional<bool> output0_sync;
    int tool = 0, selected_tool = 0;
    PerAxis<double> g28{}, g30{};
    // The last G38 probe: where it stopped (machine mm) and whether it tripped.
    PerAxis<double> probe_at{};
    bool probe_tripped = false;
    // Canned cycle values, sticky while a cycle mode is active (program units).
    std::optional<double> cycle_r, cycle_z, cycle_p, cycle_q;
};

class Parser {
public:
    Parser(std::string_view file, const GcodeOptions& opt) : file_(file), opt_(opt) {
        st_.pos = opt.start_position;
        if (opt.g28_position) st_.g28 = *opt.g28_position;
        if (opt.g30_position) st_.g30 = *opt.g30_position;
        job_.file = std::string(file);
        params_.system = [this](int n) { return system_param(n); };
        params_.writable = [](int n) { return n < 5161; };
    }

    void error(int line, int col, std::string msg) {
        errors_.push_back({file_, {line, col}, std::move(msg)});
    }
    void warn(int line, int col, std::string msg) {
        warnings_.push_back({file_, {line, col}, std::move(msg)});
    }

    // Numbered parameters LinuxCNC sets itself, read from the state (in program units).
    std::optional<double> system_param(int n) const {
        auto prog_units = [&](std::size_t a, double mm) { return a == A ? mm : mm / st_.unit; };
        if (n >= 5161 && n <= 5164) return prog_units(static_cast<std::size_t>(n - 5161), st_.g28[static_cast<std::size_t>(n - 5161)]);
        if (n >= 5181 && n <= 5184) return prog_units(static_cast<std::size_t>(n - 5181), st_.g30[static_cast<std::size_t>(n - 5181)]);
        if (n >= 5211 && n <= 5214) return prog_units(static_cast<std::size_t>(n - 5211), st_.g92[static_cast<std::size_t>(n - 5211)]);
        if (n == 5210) return st_.g92_on ? 1.0 : 0.0;
        if (n == 5220) return static_cast<double>(st_.cs);
        if (n >= 5221 && n <= 5400 - 1) {
            const int k = n - 5221, cs = k / 20, ax = k % 20;
            if (ax < kAxes) return prog_units(static_cast<std::size_t>(ax), st_.cs_offset[static_cast<std::size_t>(cs)][static_cast<std::size_t>(ax)]);
            return 0.0;
        }
        if (n == 5400) return static_cast<double>(st_.tool);
        if (n == 5403) return st_.tlo / st_.unit;
        // The last probe: #5061..#5064 where it stopped, in the coordinate system in
        // effect now, program units; #5070 1 when it tripped (LinuxCNC).
        if (n >= 5061 && n <= 5064) {
            const auto a = static_cast<std::size_t>(n - 5061);
            return program(a, st_.probe_at[a]);
        }
        if (n == 5070) return st_.probe_tripped ? 1.0 : 0.0;
        if (n >= 5420 && n <= 5423) {
            const auto a = static_cast<std::size_t>(n - 5420);
            return program(a, st_.pos[a]);
        }
        if (n >= 5161 && n <= kMaxSystem) return 0.0;
        return std::nullopt;
    }
    static constexpr int kMaxSystem = gcode::kMaxParameter;

    double unit_for(std::size_t a) const { return a == A ? 1.0 : st_.unit; }
    double offset(std::size_t a) const {
        return st_.cs_offset[static_cast<std::size_t>(st_.cs - 1)][a] + (st_.g92_on ? st_.g92[a] : 0.0) +
               (a == Z ? st_.tlo : 0.0);
    }
    double machine(std::size_t a, double program_value) const {
        return program_value * unit_for(a) + offset(a);
    }
    double program(std::size_t a, double machine_mm) const {
        return (machine_mm - offset(a)) / unit_for(a);
    }

    void run_line(std::string_view s, int line) {
        gcode::ReadLine rl = gcode::read_line(s, params_);
        line_ = line;
        if (rl.tape) return;
        const bool read_failed = rl.error.has_value();
        if (rl.error) error(line, rl.error->col, rl.error->message);
        for (const auto& e : gcode::apply_assignments(rl, params_)) error(line, e.col, e.message);
        if (rl.block_delete) warn(line, 1, "block delete '/' lines run (the block delete switch is off)");
        if (rl.words.empty()) return;
        const std::size_t before = errors_.size();
        block(rl.words, line, read_failed);
        // A line that could not be read whole reports that one error: what its
        // block then lacks (a value, a word after the error) is no news.
        if (read_failed) errors_.resize(before);
    }

    // One block, in RS274NGC's order of execution.
    void block(const std::vector<Word>& words, int line, bool read_failed) {
        auto err = [&](const Word& w, std::string msg) { error(line, w.col, std::move(msg)); };
        const SourceLoc first{line, words.front().col};
        loc_ = first;
        const std::size_t blocks_before = job_.blocks.size();

        std::map<char, const Word*> by;
        std::vector<const Word*> gs, ms;
        for (const auto& w : words) {
            if (w.letter == 'G') {
                gs.push_back(&w);
            } else if (w.letter == 'M') {
                ms.push_back(&w);
            } else if (by.count(w.letter) != 0) {
                err(w, fmt::format("word '{}' appears twice in one block", w.letter));
            } else {
                by[w.letter] = &w;
            }
        }
        auto word = [&](char l) -> const Word* {
            auto it = by.find(l);
            return it == by.end() ? nullptr : it->second;
        };
        for (const auto& [letter, w] : by) {
            if (std::string_view("BCUVW").find(letter) != std::string_view::npos) {
                err(*w, fmt::format("axis {} is not supported: the card drives X, Y, Z and A", letter));
            } else if (std::string_view("DE").find(letter) != std::string_view::npos) {
                err(*w, fmt::format("word '{}' is not supported ({})", w->text,
                                    letter == 'D' ? "cutter compensation G41/G42 is not supported"
                                                  : "E is not an RS274NGC word"));
            }
        }

        // ---- G codes into modal groups ----
        const Word* motion_w = nullptr;   // group 1
        const Word* nonmodal_w = nullptr; // group 0: G4 G10 G28 G28.1 G30 G30.1 G53 G92 G92.1-3
        const Word* g53_w = nullptr;
        const Word* plane_w = nullptr;
        const Word* units_w = nullptr;
        const Word* dist_w = nullptr;
        const Word* arcdist_w = nullptr;
        const Word* tlo_w = nullptr;
        const Word* cs_w = nullptr;
        const Word* retract_w = nullptr;
        const Word* g64_w = nullptr;
        const Word* g4_w = nullptr;
        bool conflict = false;
        auto set_group = [&](const Word*& slot, const Word* w, std::string_view group) {
            if (slot != nullptr) {
                conflict = true;
                err(*w, fmt::format("{} and {} are in the same modal group ({})", slot->text, w->text, group));
                return;
            }
            slot = w;
        };
        auto code_of = [](const Word* w) { return static_cast<int>(std::lround(w->value * 10)); };
        const std::size_t errors_before_g = errors_.size();
        for (const Word* w : gs) {
            if (!w->known) continue;
            const double tenths = w->value * 10;
            const int code = static_cast<int>(std::lround(tenths));
            if (std::abs(tenths - code) > 1e-6 || w->value < 0) {
                err(*w, fmt::format("unsupported G-code {}", w->text));
                continue;
            }
            switch (code) {
                case g(0): case g(1): case g(2): case g(3): case g(80):
                case g(73): case g(81): case g(82): case g(83): case g(85): case g(86): case g(89):
                    set_group(motion_w, w, "motion"); break;
                case g(4):
                    set_group(nonmodal_w, w, "non-modal");
                    g4_w = w;
                    break;
                case g(10): case g(28): case g(28, 1): case g(30): case g(30, 1): case g(92):
                case g(92, 1): case g(92, 2): case g(92, 3):
                    set_group(nonmodal_w, w, "non-modal"); break;
                case g(53): g53_w = w; break;
                case g(17): case g(18): case g(19): set_group(plane_w, w, "plane"); break;
                case g(20): case g(21): set_group(units_w, w, "units"); break;
                case g(90): case g(91): set_group(dist_w, w, "distance"); break;
                case g(90, 1): case g(91, 1): set_group(arcdist_w, w, "arc distance"); break;
                case g(43): case g(43, 1): case g(49): set_group(tlo_w, w, "tool length"); break;
                case g(54): case g(55): case g(56): case g(57): case g(58): case g(59):
                case g(59, 1): case g(59, 2): case g(59, 3): set_group(cs_w, w, "coordinate system"); break;
                case g(98): case g(99): set_group(retract_w, w, "canned cycle return"); break;
                case g(64): g64_w = w; break;
                case g(40): case g(61): case g(61, 1): case g(94): case g(97): break;  // ignore list
                case g(93): err(*w, "inverse-time feed (G93) is not supported; use G94"); break;
                case g(95): err(*w, "feed per revolution (G95) is not supported; use G94"); break;
                case g(96): err(*w, "constant surface speed (G96) is not supported; use G97"); break;
                case g(41): case g(42): case g(41, 1): case g(42, 1):
                    err(*w, fmt::format("{}: cutter radius compensation is not supported; let the CAM "
                                        "offset the path",
                                        w->text));
                    break;
                case g(33): case g(33, 1): case g(76): case g(84): case g(74):
                    err(*w, fmt::format("{}: spindle-synchronized motion (threading, tapping) is not "
                                        "supported",
                                        w->text));
                    break;
                case g(87): case g(88):
                    err(*w, fmt::format("{}: back boring and manual boring cycles are not supported", w->text));
                    break;
                case g(38, 2): case g(38, 3): case g(38, 4): case g(38, 5):
                    if (opt_.probe) set_group(motion_w, w, "motion");
                    else err(*w, fmt::format("{}: probing needs a card with a probe input, on `cpstep run` "
                                             "(docs/HOST.md \"Probing\")",
                                             w->text));
                    break;
                case g(5): case g(5, 1): case g(5, 2): case g(5, 3):
                    set_group(motion_w, w, "motion"); break;
                case g(7): case g(8):
                    err(*w, fmt::format("{}: lathe diameter/radius mode is not supported", w->text));
                    break;
                default: err(*w, fmt::format("unsupported G-code {}", w->text)); break;
            }
        }

        // A refused G code leaves its axis words without a home: no follow-on error for them.
        if (errors_.size() != errors_before_g) conflict = true;

        // ---- M codes ----
        const Word* stop_w = nullptr;
        const Word* spindle_w = nullptr;
        const Word* toolchange_w = nullptr;
        const Word* output_w = nullptr;
        for (const Word* w : ms) {
            if (!w->known) continue;
            const int code = static_cast<int>(std::lround(w->value));
            if (std::abs(w->value - code) > 1e-9) {
                err(*w, fmt::format("unsupported M-code {}", w->text));
                continue;
            }
            switch (code) {
                case 0: case 1: case 2: case 30: set_group(stop_w, w, "stopping"); break;
                case 3: case 4: case 5: set_group(spindle_w, w, "spindle"); break;
                case 6: toolchange_w = w; break;
                case 62: case 63: case 64: case 65: set_group(output_w, w, "digital output"); break;
                case 7: case 8: case 9: case 48: case 49: break;  // ignore list
                case 60: err(*w, "M60 (pallet change) is not supported"); break;
                case 98: case 99:
                    err(*w, fmt::format("M{}: subprograms are not supported; expand them before planning", code));
                    break;
                default: err(*w, fmt::format("unsupported M-code {}", w->text)); break;
            }
        }

        const int nonmodal = nonmodal_w ? code_of(nonmodal_w) : -1;
        const bool cycle_mode_after = motion_w ? is_cycle(code_of(motion_w)) : (st_.motion && is_cycle(*st_.motion));

        // ---- words that need a code to use them ----
        const int motion_now = motion_w ? code_of(motion_w) : (st_.motion ? *st_.motion : -1);
        const bool arc_now = motion_now == g(2) || motion_now == g(3);
        if (const Word* p = word('P')) {
            const bool used = g4_w || g64_w || nonmodal == g(10) || motion_now == g(5) || motion_now == g(5, 2) ||
                              (cycle_mode_after && (motion_now == g(82) || motion_now == g(86) || motion_now == g(89))) ||
                              arc_now;
            if (output_w && used) {
                err(*p, fmt::format("P is wanted by {} and by another code of the block: write them on separate lines",
                                    output_w->text));
            } else if (!used && !output_w) {
                err(*p, "P is only used by G4 (dwell seconds), G10, G64, G2/G3 turns, G82/G86/G89 and M62-M65");
            }
        }
        if (output_w) {
            const Word* p = word('P');
            const int c = static_cast<int>(std::lround(output_w->value));
            if (p == nullptr) {
                err(*output_w, fmt::format("{} needs P<output>: P0, the card's torch output", output_w->text));
            } else if (p->known && p->value != 0) {
                err(*p, fmt::format("{}: the card has one digital output, P0 (the torch); P{} is not one",
                                    output_w->text, p->text.substr(1)));
            } else if (p->known && (c == 62 || c == 63)) {
                st_.output0_sync = c == 62;
            } else if (p->known) {
                st_.output0 = c == 64;
                st_.output0_sync.reset();
            }
        }
        if (const Word* q = word('Q')) {
            if (!g64_w && motion_now != g(5) && !(cycle_mode_after && (motion_now == g(73) || motion_now == g(83))))
                err(*q, "Q is only used by G64 and the peck cycles G73/G83");
        }
        if (const Word* l = word('L')) {
            if (nonmodal != g(10) && !cycle_mode_after && motion_now != g(5, 2))
                err(*l, "L is only used by G10, canned cycles and G5.2 (NURBS order)");
        }
        if (const Word* h = word('H')) {
            if (!tlo_w || code_of(tlo_w) != g(43)) err(*h, "H is only used by G43 (tool length offset)");
        }
        // ---- 1..13: F, S, T, M6, spindle ----
        // A line whose reading stopped may have lost its F: no "feed not set" for it.
        if (read_failed && !word('F') && !st_.feed) st_.feed_known = false;
        if (const Word* f = word('F')) {
            if (!f->known) {
                st_.feed_known = false;
            } else if (!(f->value > 0)) {
                err(*f, "feed rate F must be > 0");
                st_.feed_known = false;
            } else {
                st_.feed = f->value;
                st_.feed_known = true;
            }
        }
        if (const Word* sw = word('S')) {
            if (sw->known && sw->value < 0) err(*sw, "spindle speed S must be >= 0");
            if (sw->known) st_.spindle_speed = std::max(0.0, sw->value);
        }
        if (const Word* t = word('T')) {
            if (t->known) {
                if (t->value < 0 || t->value > kMaxTool || t->value != std::floor(t->value)) {
                    err(*t, fmt::format("tool number T must be a whole number in 0..{:g}", kMaxTool));
                } else {
                    st_.selected_tool = static_cast<int>(t->value);
                }
            }
        }
        if (toolchange_w) st_.tool = st_.selected_tool;
        if (spindle_w) {
            const int c = static_cast<int>(std::lround(spindle_w->value));
            st_.spindle_on = c != 5;
            if (c != 5) st_.spindle_ccw = c == 4;
        }

        // ---- 14: dwell ----
        if (g4_w) {
            const Word* p = word('P');
            if (p == nullptr) {
                err(*g4_w, "G4 needs P<seconds>");
            } else if (p->known && p->value < 0) {
                err(*p, "dwell P must be >= 0 seconds");
            } else if (p->known && p->value > 0) {
                MotionBlock b = base_block(MotionKind::dwell);
                b.dwell_s = p->value;
                job_.blocks.push_back(b);
            }
        }

        // ---- 15..22: plane, units, cutter comp, tool length, CS, path, distance, retract ----
        if (plane_w) {
            const int c = code_of(plane_w);
            st_.plane = c == g(17) ? Plane::xy : c == g(18) ? Plane::zx : Plane::yz;
        }
        if (units_w) {
            st_.unit = code_of(units_w) == g(20) ? 25.4 : 1.0;
            st_.units_set = true;
        }
        if (tlo_w) tool_length(*tlo_w, word('H'), word('Z'), code_of(tlo_w));
        if (cs_w) {
            const int c = code_of(cs_w);
            st_.cs = c <= g(59) ? (c - g(54)) / 10 + 1 : 6 + (c - g(59));
        }
        if (dist_w) st_.absolute = code_of(dist_w) == g(90);
        if (arcdist_w) st_.arc_absolute = code_of(arcdist_w) == g(90, 1);
        if (retract_w) st_.retract_old_z = code_of(retract_w) == g(98);

        const Word* axis_w[kAxes] = {word('X'), word('Y'), word('Z'), word('A')};
        const bool any_axis = std::any_of(std::begin(axis_w), std::end(axis_w), [](const Word* w) { return w != nullptr; });
        check_axes(axis_w);

        // ---- 23: G10, G28, G30, G92 ----
        bool axes_used = false;
        if (nonmodal_w && nonmodal != g(4)) {
            axes_used = true;
            if (motion_w && any_axis && code_of(motion_w) != g(80)) {
                err(*motion_w, fmt::format("{} and {} cannot share the axis words of one block", nonmodal_w->text,
                                           motion_w->text));
            }
            non_modal(*nonmodal_w, nonmodal, axis_w, word('L'), word('P'), word('R'));
        }

        // ---- 24: motion ----
        if (nurbs_ && !conflict) {
            const Word* intruder = motion_w && code_of(motion_w) != g(5, 3) ? motion_w
                                   : (nonmodal_w && nonmodal != g(4)) ? nonmodal_w
                                   : g4_w                               ? g4_w
                                   : stop_w;
            if (intruder) {
                err(*intruder, fmt::format("{} inside a G5.2 NURBS (line {}): end it with G5.3 first", intruder->text,
                                           nurbs_->open.line));
                nurbs_.reset();
                st_.motion.reset();
            }
        }
        if (motion_w) {
            const int c = code_of(motion_w);
            if (c == g(80)) {
                st_.motion.reset();
                clear_cycle();
            } else {
                if (!is_cycle(c)) clear_cycle();
                st_.motion = c;
            }
        }
        if (g53_w && (!st_.motion || (*st_.motion != g(0) && *st_.motion != g(1)) || axes_used)) {
            err(*g53_w, "G53 needs G0 or G1 in the same block (a move in machine coordinates)");
        } else if (g53_w && !st_.absolute) {
            err(*g53_w, "G53 cannot be used with G91 (incremental)");
        }
        if (!axes_used && st_.motion && is_spline(*st_.motion)) {
            // A line of the spline's words (a G5/G5.1 move, a G5.2 point or knot, G5.3).
            const bool spline_words = motion_w || any_axis || word('I') || word('J') || word('K') ||
                                      ((word('P') || word('Q') || word('L')) && !g4_w && !g64_w);
            if (spline_words) spline(*st_.motion, motion_w, words.front(), axis_w, by);
        } else if (!axes_used) {
            const bool has_center = word('I') || word('J') || word('K') || word('R');
            if (any_axis || (has_center && !(st_.motion && is_cycle(*st_.motion)))) {
                if (!st_.motion) {
                    if (conflict) {
                        // already reported: the block's codes are in conflict
                    } else if (motion_w == nullptr || code_of(motion_w) != g(80)) {
                        err(words.front(), "axis words without a motion mode (G0, G1, G2, G3 or a canned cycle)");
                    } else {
                        err(words.front(), "axis words after G80 in the same block: no motion mode is active");
                    }
                    mark_unknown(axis_w);
                } else if (is_cycle(*st_.motion)) {
                    cycle(*st_.motion, motion_w ? *motion_w : words.front(), axis_w, by);
                } else {
                    motion(*st_.motion, motion_w ? *motion_w : words.front(), axis_w, by, g53_w != nullptr,
                           read_failed);
                }
            } else if (st_.motion && is_cycle(*st_.motion) && word('R') && !any_axis) {
                // R alone in a cycle mode updates the sticky retract plane.
                if (word('R')->known) st_.cycle_r = word('R')->value;
            } else if (motion_w && !is_cycle(code_of(motion_w)) && (code_of(motion_w) == g(2) || code_of(motion_w) == g(3))) {
                err(*motion_w, "an arc needs an end point or a centre (axis words, I/J/K or R)");
            }
        } else {
            for (char l : {'I', 'J', 'K', 'R'}) {
                if (const Word* w = word(l); w && !(l == 'R' && nonmodal == g(10)))
                    err(*w, fmt::format("{} is only used by arcs and canned cycles", l));
            }
        }
        if (read_failed) {
            // The rest of the line was not read: its axis words may be missing.
            if (st_.motion || any_axis) mark_all_unknown();
        }

        // ---- 25: stops ----
        if (stop_w) {
            const int c = static_cast<int>(std::lround(stop_w->value));
            if (c == 0 || c == 1) {
                MotionBlock b = base_block(MotionKind::dwell);
                b.pause = c == 0 ? PauseKind::program_stop : PauseKind::optional_stop;
                job_.blocks.push_back(b);
            } else {
                ended_ = true;
            }
        }
        // M62/M63 took effect with the first motion of this block, if it had one.
        if (st_.output0_sync) {
            for (std::size_t i = blocks_before; i < job_.blocks.size(); ++i) {
                if (job_.blocks[i].kind == MotionKind::dwell) continue;
                st_.output0 = *st_.output0_sync;
                st_.output0_sync.reset();
                break;
            }
        }
    }

    void clear_cycle() {
        st_.cycle_r.reset();
        st_.cycle_z.reset();
        st_.cycle_p.reset();
        st_.cycle_q.reset();
    }

    void mark_unknown(const Word* const axis_w[kAxes]) {
        for (std::size_t a = 0; a < kAxes; ++a)
            if (axis_w[a]) st_.known[a] = false;
    }
    void mark_all_unknown() { st_.known = {false, false, false, false}; }

    // Words for axes the machine lacks: refused, or Z dropped by the machine file's policy.
    void check_axes(const Word* axis_w[kAxes]) {
        if (!opt_.axes_present) return;
        for (std::size_t a = 0; a < kAxes; ++a) {
            if (!axis_w[a] || (*opt_.axes_present)[a]) continue;
            const char L = static_cast<char>(std::toupper(kAxisLetters[a]));
            if (a == Z && opt_.z_words == MissingZ::ignore) {
                warn(line_, axis_w[a]->col, "Z word ignored: the machine has no Z axis (gcode.z_words = \"ignore\")");
            } else if (a == Z) {
                error(line_, axis_w[a]->col,
                      "Z word on a machine without a Z axis; set [gcode] z_words = \"ignore\" in the machine "
                      "file to drop Z words");
            } else {
                error(line_, axis_w[a]->col, fmt::format("{} word on a machine without an {} axis", L, L));
            }
            axis_w[a] = nullptr;
        }
    }

    void tool_length(const Word& w, const Word* h, const Word* zw, int code) {
        if (code == g(49)) {
            st_.tlo = 0;
            return;
        }
        if (code == g(43, 1)) {
            // G43.1 Z<length>: the Z word is the offset, not a move (LinuxCNC).
            if (!zw) {
                error(line_, w.col, "G43.1 needs Z<tool length>");
            } else if (zw->known) {
                st_.tlo = zw->value * st_.unit;
            }
            z_consumed_ = true;
            return;
        }
        int n = st_.tool;
        if (h) {
            if (!h->known) return;
            if (h->value < 0 || h->value > kMaxTool || h->value != std::floor(h->value)) {
                error(line_, h->col, fmt::format("H must be a whole tool number in 0..{:g}", kMaxTool));
                return;
            }
            n = static_cast<int>(h->value);
        }
        if (n == 0) {
            st_.tlo = 0;
            return;
        }
        auto it = opt_.tool_lengths.find(n);
        if (it == opt_.tool_lengths.end()) {
            error(line_, h ? h->col : w.col,
                  fmt::format("G43: tool {} has no length; give it in the machine file's [gcode.tool_lengths] "
                              "({} = <mm>)",
                              n, n));
            return;
        }
        st_.tlo = it->second;
    }

    void non_modal(const Word& w, int code, const Word* const axis_w[kAxes], const Word* l, const Word* p,
                   const Word* r) {
        const bool any_axis = std::any_of(axis_w, axis_w + kAxes, [](const Word* x) { return x != nullptr; });
        switch (code) {
            case g(92):
                if (!any_axis) {
                    error(line_, w.col, "G92 needs at least one axis word");
                    return;
                }
                st_.g92_on = true;
                for (std::size_t a = 0; a < kAxes; ++a) {
                    if (!axis_w[a] || !axis_w[a]->known) continue;
                    // machine = value*unit + cs + g92 + tlo
                    st_.g92[a] = st_.pos[a] - axis_w[a]->value * unit_for(a) - st_.cs_offset[static_cast<std::size_t>(st_.cs - 1)][a] -
                                 (a == Z ? st_.tlo : 0.0);
                }
                return;
            case g(92, 1): st_.g92 = {}; st_.g92_on = false; return;
            case g(92, 2): st_.g92_on = false; return;
            case g(92, 3): st_.g92_on = true; return;
            case g(28, 1): st_.g28 = st_.pos; return;
            case g(30, 1): st_.g30 = st_.pos; return;
            case g(28): case g(30): {
                const PerAxis<double>& home = code == g(28) ? st_.g28 : st_.g30;
                if (!(code == g(28) ? opt_.g28_position : opt_.g30_position) && !warned_home_) {
                    warned_home_ = true;
                    warn(line_, w.col, fmt::format("{} goes to the machine origin: the machine file gives no "
                                                   "gcode.{}_position",
                                                   w.text, code == g(28) ? "g28" : "g30"));
                }
                // Through the point the axis words name, then home on those axes (all without words).
                PerAxis<double> mid = st_.pos;
                for (std::size_t a = 0; a < kAxes; ++a) {
                    if (!axis_w[a]) continue;
                    if (!axis_w[a]->known) {
                        st_.known[a] = false;
                        continue;
                    }
                    mid[a] = st_.absolute ? machine(a, axis_w[a]->value) : st_.pos[a] + axis_w[a]->value * unit_for(a);
                }
                emit_line(MotionKind::rapid, mid, 0);
                PerAxis<double> end = st_.pos;
                for (std::size_t a = 0; a < kAxes; ++a) {
                    if ((any_axis && !axis_w[a]) || !present(a)) continue;
                    end[a] = home[a];
                    st_.known[a] = true;
                }
                emit_line(MotionKind::rapid, end, 0);
                return;
            }
            case g(10): {
                const int lv = l && l->known ? static_cast<int>(std::lround(l->value)) : -1;
                if (!l) {
                    error(line_, w.col, "G10 needs L2 or L20 (work offsets)");
                    return;
                }
                if (lv != 2 && lv != 20) {
                    if (l->known)
                        error(line_, l->col, fmt::format("G10 L{}: only L2 and L20 (work offsets) are supported; "
                                                         "tool lengths come from the machine file",
                                                         lv));
                    return;
                }
                if (r && !(r->known && r->value == 0)) {
                    error(line_, r->col, "G10 L2/L20 R (rotation of a coordinate system) is not supported");
                    return;
                }
                int cs = st_.cs;
                if (p) {
                    if (!p->known) return;
                    const double pv = p->value;
                    if (pv < 0 || pv > 9 || pv != std::floor(pv)) {
                        error(line_, p->col, "G10 P must be 0 (the active system) or 1..9 (G54..G59.3)");
                        return;
                    }
                    if (pv != 0) cs = static_cast<int>(pv);
                } else {
                    error(line_, w.col, "G10 L2/L20 needs P<coordinate system 0..9>");
                    return;
                }
                auto& off = st_.cs_offset[static_cast<std::size_t>(cs - 1)];
                for (std::size_t a = 0; a < kAxes; ++a) {
                    if (!axis_w[a] || !axis_w[a]->known) continue;
                    const double v = axis_w[a]->value * unit_for(a);
                    if (lv == 2) {
                        off[a] = v;  // absolute, G91 has no effect (LinuxCNC)
                    } else {
                        // L20: the current position becomes v in that system.
                        off[a] = st_.pos[a] - v - (st_.g92_on ? st_.g92[a] : 0.0) - (a == Z ? st_.tlo : 0.0);
                    }
                }
                return;
            }
            default: return;
        }
    }

    bool present(std::size_t a) const { return !opt_.axes_present || (*opt_.axes_present)[a]; }

    MotionBlock base_block(MotionKind kind) const {
        MotionBlock b;
        b.kind = kind;
        b.loc = loc_;
        b.start = st_.pos;
        b.end = st_.pos;
        b.spindle_on = st_.spindle_on;
        b.output0 = kind != MotionKind::dwell && st_.output0_sync ? *st_.output0_sync : st_.output0;
        b.spindle_ccw = st_.spindle_ccw;
        b.spindle_speed = st_.spindle_speed;
        b.plane = st_.plane;
        b.tool = st_.tool;
        return b;
    }

    // Feed in mm/s for a move to `target`; A-only moves take F as degrees/min.
    double feed_mm_s(const PerAxis<double>& target) const {
        const bool linear_axes = target[X] != st_.pos[X] || target[Y] != st_.pos[Y] || target[Z] != st_.pos[Z];
        return *st_.feed * (linear_axes ? st_.unit : 1.0) / 60.0;
    }

    // A straight move (rapid or feed) from the current position; updates it.
    void emit_line(MotionKind kind, PerAxis<double> target, double feed) {
        if (!present(Z) && opt_.z_words == MissingZ::ignore) target[Z] = st_.pos[Z];
        if (target == st_.pos) return;
        MotionBlock b = base_block(kind);
        b.end = target;
        b.feed = kind == MotionKind::rapid ? 0 : feed;
        job_.blocks.push_back(b);
        st_.pos = target;
    }
    void emit_dwell(double s) {
        if (s <= 0) return;
        MotionBlock b = base_block(MotionKind::dwell);
        b.dwell_s = s;
        job_.blocks.push_back(b);
    }

    // G38.2..G38.5 (opt_.probe set): the handler runs the blocks so far and the move;
    // the program goes on from where it stopped.
    void probe(int mode, const Word& at, const PerAxis<double>& target) {
        if (!need_feed(at)) return;
        const std::string code = fmt::format("G38.{}", mode % 10);
        if (target == st_.pos) {
            error(line_, at.col, fmt::format("{}: the probe move has no length (the target is where the tool is)", code));
            return;
        }
        for (std::size_t a = 0; a < kAxes; ++a)
            if (!st_.known[a]) {
                error(line_, at.col, fmt::format("{}: the position is not known after a refused block", code));
                return;
            }
        if (!errors_.empty()) return;  // a refused program runs nothing, probes included
        ProbeRequest r;
        r.loc = {line_, at.col};
        r.code = code;
        r.contact = mode == g(38, 2) || mode == g(38, 3);
        r.must_trip = mode == g(38, 2) || mode == g(38, 4);
        r.from = st_.pos;
        r.to = target;
        r.feed = feed_mm_s(target);
        r.before = std::span<const MotionBlock>(job_.blocks).subspan(job_.probed_blocks);
        const ProbeResult res = opt_.probe(r);
        job_.probed_blocks = job_.blocks.size();
        ++job_.probes;
        if (!res.error.empty()) {
            error(line_, at.col, fmt::format("{}: {}", code, res.error));
            ended_ = probe_failed_ = true;  // nothing after it runs
            return;
        }
        st_.pos = res.at;
        st_.probe_at = res.at;
        st_.probe_tripped = res.tripped;
        if (r.must_trip && !res.tripped) {
            error(line_, at.col, fmt::format("{}: the probe {} by the end of the move", code,
                                             r.contact ? "made no contact" : "did not lose contact"));
            ended_ = probe_failed_ = true;
        }
    }

    bool need_feed(const Word& at) {
        if (st_.feed) return true;
        if (st_.feed_known) error(line_, at.col, "feed rate is not set (F) for a G1/G2/G3 move or canned cycle");
        return false;
    }

    void motion(int mode, const Word& at, const Word* const axis_w[kAxes], const std::map<char, const Word*>& by,
                bool g53, bool read_failed) {
        auto word = [&](char l) -> const Word* {
            auto it = by.find(l);
            return it == by.end() ? nullptr : it->second;
        };
        PerAxis<double> target = st_.pos;
        bool moved_word = false;
        for (std::size_t a = 0; a < kAxes; ++a) {
            const Word* w = axis_w[a];
            if (!w) continue;
            if (a == Z && z_consumed_) continue;
            moved_word = true;
            if (!w->known) {
                st_.known[a] = false;
                continue;
            }
            if (g53) {
                target[a] = w->value * unit_for(a);
            } else if (st_.absolute) {
                target[a] = machine(a, w->value);
            } else {
                target[a] = st_.pos[a] + w->value * unit_for(a);
            }
            if (st_.absolute || g53) st_.known[a] = true;
        }
        const bool arc = mode == g(2) || mode == g(3);
        if (!arc) {
            for (char l : {'I', 'J', 'K', 'R'}) {
                if (const Word* w = word(l)) {
                    error(line_, w->col, fmt::format("{} is only used by G2/G3 arcs and canned cycles", l));
                    st_.pos = target;
                    return;
                }
            }
            if (!moved_word) return;
            if (!st_.units_set && !warned_units_) {
                warned_units_ = true;
                warn(line_, at.col, "the program sets no units (G20/G21): millimetres assumed");
            }
            if (is_probe(mode)) {
                probe(mode, at, target);
                return;
            }
            if (mode == g(1) && !need_feed(at)) return;
            if (target == st_.pos) return;  // a move to where the tool is: no block
            if (mode == g(0)) {
                MotionBlock b = base_block(MotionKind::rapid);
                b.end = target;
                job_.blocks.push_back(b);
                st_.pos = target;
                return;
            }
            MotionBlock b = base_block(MotionKind::linear);
            b.end = target;
            b.feed = feed_mm_s(target);
            job_.blocks.push_back(b);
            st_.pos = target;
            return;
        }
        (void)read_failed;
        if (!st_.units_set && !warned_units_) {
            warned_units_ = true;
            warn(line_, at.col, "the program sets no units (G20/G21): millimetres assumed");
        }
        arc_move(mode, at, target, word);
    }

    template <class WordFn>
    void arc_move(int mode, const Word& at, const PerAxis<double>& target, WordFn word) {
        // The plane's axes (first, second) and the centre-offset letters for them.
        std::size_t u = X, v = Y;
        char lu = 'I', lv = 'J', lw = 'K';
        if (st_.plane == Plane::zx) {
            u = Z; v = X; lu = 'K'; lv = 'I'; lw = 'J';
        } else if (st_.plane == Plane::yz) {
            u = Y; v = Z; lu = 'J'; lv = 'K'; lw = 'I';
        }
        const Word* wu = word(lu);
        const Word* wv = word(lv);
        const Word* wn = word(lw);
        const Word* wr = word('R');
        const Word* wp = word('P');
        auto done = [&] { st_.pos = target; };
        const bool fed = need_feed(at);
        if (wn && wn->known && wn->value != 0) {
            error(line_, wn->col, fmt::format("{} is not an offset in the {} plane ({}{} arcs use {} and {})",
                                              lw, st_.plane == Plane::xy ? "XY" : st_.plane == Plane::zx ? "ZX" : "YZ",
                                              "G", st_.plane == Plane::xy ? 17 : st_.plane == Plane::zx ? 18 : 19, lu, lv));
            return done();
        }
        if (wp && wp->known && wp->value != 1) {
            error(line_, wp->col, "G2/G3 P (extra full turns) is not supported");
            return done();
        }
        if (wr && (wu || wv)) {
            error(line_, wr->col, "give either the centre (I/J/K) or R for an arc, not both");
            return done();
        }
        if (!wr && !wu && !wv) {
            error(line_, at.col, fmt::format("an arc needs its centre ({}/{}) or R (radius)", lu, lv));
            return done();
        }
        // Unknown inputs: the geometry cannot be checked; move on silently.
        if (!st_.known[u] || !st_.known[v] || (wr && !wr->known) || (wu && !wu->known) || (wv && !wv->known) || !fed) {
            return done();
        }
        MotionBlock b = base_block(mode == g(2) ? MotionKind::arc_cw : MotionKind::arc_ccw);
        b.end = target;
        b.feed = feed_mm_s(target);
        const double u0 = st_.pos[u], v0 = st_.pos[v], u1 = target[u], v1 = target[v];
        double cu = 0, cv = 0;
        if (wr) {
            const double r = wr->value * st_.unit;
            const double du = u1 - u0, dv = v1 - v0;
            const double d = std::hypot(du, dv);
            if (d < 1e-9) {
                error(line_, wr->col, "an R-form arc cannot end where it starts; use I/J/K for a full circle");
                return done();
            }
            const double half = d / 2;
            if (half - std::abs(r) > kRadiusTolerance) {
                error(line_, wr->col, fmt::format("arc radius {:g} is shorter than half the chord ({:g} mm)",
                                                  std::abs(r), half));
                return done();
            }
            const double h2 = std::max(0.0, r * r - half * half);
            double h = std::sqrt(h2);
            // G2 with R > 0 (the short way): the centre is right of travel.
            if ((mode == g(2)) == (r > 0)) h = -h;
            cu = (u0 + u1) / 2 - h * dv / d;
            cv = (v0 + v1) / 2 + h * du / d;
        } else {
            const double ou = wu ? wu->value * st_.unit : 0.0;
            const double ov = wv ? wv->value * st_.unit : 0.0;
            if (st_.arc_absolute) {
                cu = wu ? ou + offset(u) : u0;
                cv = wv ? ov + offset(v) : v0;
            } else {
                cu = u0 + ou;
                cv = v0 + ov;
            }
            const double r0 = std::hypot(u0 - cu, v0 - cv);
            const double r1 = std::hypot(u1 - cu, v1 - cv);
            if (r0 < kRadiusTolerance || r1 < kRadiusTolerance) {
                error(line_, (wu ? wu : wv)->col, "arc radius is zero (the centre is on the start or end point)");
                return done();
            }
            const double abs_err = std::abs(r0 - r1);
            if (abs_err > kSpiralAbs && abs_err > kSpiralRel * std::max(r0, r1)) {
                error(line_, at.col, fmt::format("arc end is not on the circle: radius {:.4f} mm at the start, "
                                                 "{:.4f} mm at the end",
                                                 r0, r1));
                return done();
            }
        }
        switch (st_.plane) {
            case Plane::xy: b.center_x = cu; b.center_y = cv; break;
            case Plane::zx: b.center_z = cu; b.center_x = cv; break;
            case Plane::yz: b.center_y = cu; b.center_z = cv; break;
        }
        job_.blocks.push_back(b);
        done();
    }

    // Canned cycles G73 G81 G82 G83 G85 G86 G89 in the XY plane, expanded into moves.
    void cycle(int mode, const Word& at, const Word* const axis_w[kAxes], const std::map<char, const Word*>& by) {
        auto word = [&](char l) -> const Word* {
            auto it = by.find(l);
            return it == by.end() ? nullptr : it->second;
        };
        const std::string name = gname(mode);
        if (st_.plane != Plane::xy) {
            error(line_, at.col, fmt::format("{}: canned cycles are supported in the XY plane (G17) only", name));
            return mark_all_unknown();
        }
        if (axis_w[A]) {
            error(line_, axis_w[A]->col, fmt::format("{}: A cannot move in a canned cycle", name));
            return;
        }
        bool unknown = false;
        auto sticky = [&](char l, std::optional<double>& slot) {
            if (const Word* w = word(l)) {
                if (w->known) {
                    slot = w->value;
                } else {
                    unknown = true;
                }
            }
        };
        sticky('R', st_.cycle_r);
        if (axis_w[Z]) {
            if (axis_w[Z]->known) {
                st_.cycle_z = axis_w[Z]->value;
            } else {
                unknown = true;
            }
        }
        if (mode == g(82) || mode == g(86) || mode == g(89)) sticky('P', st_.cycle_p);
        if (mode == g(73) || mode == g(83)) sticky('Q', st_.cycle_q);
        for (std::size_t a : {X, Y})
            if (axis_w[a] && !axis_w[a]->known) unknown = true;
        if (unknown) return mark_all_unknown();
        if (!st_.cycle_r) {
            error(line_, at.col, fmt::format("{} needs R (the retract plane)", name));
            return mark_all_unknown();
        }
        if (!st_.cycle_z) {
            error(line_, at.col, fmt::format("{} needs Z (the hole bottom)", name));
            return mark_all_unknown();
        }
        if ((mode == g(73) || mode == g(83)) && !(st_.cycle_q && *st_.cycle_q > 0)) {
            error(line_, word('Q') ? word('Q')->col : at.col, fmt::format("{} needs Q > 0 (the peck depth)", name));
            return mark_all_unknown();
        }
        double repeats_l = 1;
        if (const Word* l = word('L')) {
            if (!l->known) return mark_all_unknown();
            if (l->value < 1 || l->value != std::floor(l->value)) {
                error(line_, l->col, "L (canned cycle repeats) must be a whole number >= 1");
                return;
            }
            repeats_l = l->value;
        }
        if (!need_feed(at)) return mark_all_unknown();
        if (!st_.units_set && !warned_units_) {
            warned_units_ = true;
            warn(line_, at.col, "the program sets no units (G20/G21): millimetres assumed");
        }
        const double feed = *st_.feed * st_.unit / 60.0;
        const double z0 = st_.pos[Z];
        // G90: R and Z are program coordinates; G91: R from the current Z, Z from R.
        const double r = st_.absolute ? machine(Z, *st_.cycle_r) : z0 + *st_.cycle_r * st_.unit;
        const double bottom = st_.absolute ? machine(Z, *st_.cycle_z) : r + *st_.cycle_z * st_.unit;
        if (bottom > r + 1e-9) {
            error(line_, at.col, fmt::format("{}: the hole bottom Z is above the retract plane R", name));
            return mark_all_unknown();
        }
        const double clear = st_.retract_old_z ? std::max(z0, r) : r;
        const double dwell = st_.cycle_p.value_or(0.0);
        const double q = st_.cycle_q.value_or(0.0) * st_.unit;
        const bool pecking = mode == g(73) || mode == g(83);
        const double pecks = pecking ? std::ceil((r - bottom) / q) : 1;  // per hole
        // A line like G83 ... Q0.00001 L100000000 is refused, not expanded until the
        // memory is full; and so is the block that takes the program's cycles together
        // past max_cycle_job (a few kilobytes of G81 ... L99999 lines), once.
        const double holes_pecks = repeats_l * std::max(pecks, 1.0);
        if (!(holes_pecks <= opt_.max_cycle_block)) {
            error(line_, at.col, fmt::format("{}: {:g} hole(s) of {:g} peck(s) each; a block expands into at most "
                                             "{:g} holes x pecks",
                                             name, repeats_l, pecks, opt_.max_cycle_block));
            return mark_all_unknown();
        }
        if (!(cycle_total_ + holes_pecks <= opt_.max_cycle_job)) {
            if (!cycle_job_refused_) {
                cycle_job_refused_ = true;
                error(line_, at.col, fmt::format("{}: the program's canned cycles expand into more than {:g} holes x "
                                                 "pecks ({:g} before this block, {:g} in it)",
                                                 name, opt_.max_cycle_job, cycle_total_, holes_pecks));
            }
            return mark_all_unknown();
        }
        cycle_total_ += holes_pecks;
        const int repeats = static_cast<int>(repeats_l);
        // Pecks counted too: d -= q may stop moving d when q is below its rounding step.
        const int max_pecks = static_cast<int>(std::min(opt_.max_cycle_block, 1e9));
        for (int rep = 0; rep < repeats; ++rep) {
            PerAxis<double> p = st_.pos;
            for (std::size_t a : {X, Y}) {
                if (!axis_w[a]) continue;
                p[a] = st_.absolute ? machine(a, axis_w[a]->value) : st_.pos[a] + axis_w[a]->value * st_.unit;
                st_.known[a] = true;
            }
            auto at_z = [&](double z) {
                PerAxis<double> t = st_.pos;
                t[Z] = z;
                return t;
            };
            if (st_.pos[Z] < r) emit_line(MotionKind::rapid, at_z(r), 0);
            PerAxis<double> above = st_.pos;
            above[X] = p[X];
            above[Y] = p[Y];
            emit_line(MotionKind::rapid, above, 0);
            emit_line(MotionKind::rapid, at_z(r), 0);
            int n_pecks = 0;
            switch (mode) {
                case g(73):
                    for (double d = r - q; d > bottom && n_pecks < max_pecks; d -= q, ++n_pecks) {
                        emit_line(MotionKind::linear, at_z(d), feed);
                        emit_line(MotionKind::rapid, at_z(d + kPeckRetract), 0);
                    }
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    break;
                case g(83):
                    for (double d = r - q; d > bottom && n_pecks < max_pecks; d -= q, ++n_pecks) {
                        emit_line(MotionKind::linear, at_z(d), feed);
                        emit_line(MotionKind::rapid, at_z(r), 0);
                        emit_line(MotionKind::rapid, at_z(d + kPeckRetract), 0);
                    }
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    break;
                case g(81):
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    break;
                case g(82):
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    emit_dwell(dwell);
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    break;
                case g(85):
                case g(89):
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    if (mode == g(89)) emit_dwell(dwell);
                    emit_line(MotionKind::linear, at_z(r), feed);
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    break;
                case g(86): {
                    emit_line(MotionKind::linear, at_z(bottom), feed);
                    emit_dwell(dwell);
                    const bool on = st_.spindle_on;
                    st_.spindle_on = false;  // spindle stops, rapid out, starts again
                    emit_line(MotionKind::rapid, at_z(clear), 0);
                    st_.spindle_on = on;
                    break;
                }
                default: break;
            }
        }
        st_.known[Z] = true;
    }

    Result<Job> finish() {
        end_of_program();
        Result<Job> r;
        std::stable_sort(errors_.begin(), errors_.end(), [](const Diagnostic& a, const Diagnostic& b) {
            return a.loc.line != b.loc.line ? a.loc.line < b.loc.line : a.loc.col < b.loc.col;
        });
        if (errors_.size() > opt_.max_errors) {
            const std::size_t total = errors_.size();
            errors_.resize(opt_.max_errors);
            errors_.push_back({file_, {}, fmt::format("{} more errors not shown ({} in total)", total - opt_.max_errors, total)});
        }
        r.errors = std::move(errors_);
        r.warnings = summarize_repeats(std::move(warnings_));
        if (r.errors.empty()) r.value = std::move(job_);
        return r;
    }

    // ---- splines: G5 (cubic), G5.1 (quadratic), G5.2 ... G5.3 (NURBS) ----
    struct OpenNurbs {
        SourceLoc open;                    // the G5.2 word
        MotionBlock block;                 // start, spindle state at G5.2
        int order = 3;
        std::vector<Eigen::Vector3d> pts;  // machine mm; the first is the start
        std::vector<double> weights;
        std::vector<double> knots;         // K words (empty: LinuxCNC's uniform knots)
        std::vector<SourceLoc> knot_loc;
        bool bad = false;                  // an error was reported: no block at G5.3
    };

    // The XY point an X/Y pair names (absolute or incremental), machine mm.
    Eigen::Vector3d xy_target(const Word* wx, const Word* wy) const {
        Eigen::Vector3d p(st_.pos[X], st_.pos[Y], st_.pos[Z]);
        for (std::size_t a : {X, Y}) {
            const Word* w = a == X ? wx : wy;
            if (!w) continue;
            p[static_cast<Eigen::Index>(a)] = st_.absolute ? machine(a, w->value) : st_.pos[a] + w->value * st_.unit;
        }
        return p;
    }

    void emit_curve(MotionBlock b, std::shared_ptr<const Nurbs> curve) {
        const Eigen::Vector3d& e = curve->points().back();
        b.end[X] = e[0];
        b.end[Y] = e[1];
        b.feed = st_.feed ? *st_.feed * st_.unit / 60.0 : 0.0;  // X/Y only: units per minute
        b.curve = std::move(curve);
        st_.pos = b.end;
        // A curve whose control points all coincide does not move: no block.
        const auto& pts = b.curve->points();
        const bool moves = std::any_of(pts.begin(), pts.end(), [&](const Eigen::Vector3d& q) { return q != pts.front(); });
        if (moves) job_.blocks.push_back(std::move(b));
    }

    void spline(int mode, const Word* motion_w, const Word& first, const Word* const axis_w[kAxes],
                const std::map<char, const Word*>& by) {
        auto word = [&](char l) -> const Word* {
            auto it = by.find(l);
            return it == by.end() ? nullptr : it->second;
        };
        const Word& at = motion_w ? *motion_w : first;
        const std::string name = gname(mode);
        auto fail = [&](const Word& w, std::string msg) {
            error(line_, w.col, std::move(msg));
            if (nurbs_) nurbs_->bad = true;
        };
        if (st_.plane != Plane::xy) {
            fail(at, fmt::format("{}: splines are supported in the XY plane (G17) only", name));
            return;
        }
        for (std::size_t a : {Z, A}) {
            if (axis_w[a] && !(a == Z && z_consumed_)) {
                fail(*axis_w[a], fmt::format("{}: splines move X and Y only", name));
                return;
            }
        }
        for (char l : {'R'}) {
            if (const Word* w = word(l)) {
                fail(*w, fmt::format("{} is not used by {}", l, name));
                return;
            }
        }
        for (const auto& [l, w] : by) {
            if (!w->known) {  // already reported: the spline cannot be built
                if (nurbs_) nurbs_->bad = true;
                if (mode == g(5) || mode == g(5, 1)) mark_all_unknown();
                return;
            }
        }
        if (!st_.units_set && !warned_units_ && (axis_w[X] || axis_w[Y])) {
            warned_units_ = true;
            warn(line_, at.col, "the program sets no units (G20/G21): millimetres assumed");
        }
        if (mode == g(5) || mode == g(5, 1)) return bezier(mode, at, axis_w, word);
        if (mode == g(5, 3)) return close_nurbs(at, axis_w, word);
        // G5.2: opens (with the G5.2 word) or adds a control point / a knot.
        if (const Word* w = word('I') ? word('I') : word('J')) {
            fail(*w, fmt::format("{} is not used by G5.2 (control points take X, Y and P)", w->letter));
            return;
        }
        if (motion_w) {
            OpenNurbs o;
            o.open = {line_, motion_w->col};
            o.block = base_block(MotionKind::nurbs);
            o.pts.emplace_back(st_.pos[X], st_.pos[Y], st_.pos[Z]);
            o.weights.push_back(1.0);
            nurbs_ = std::move(o);
            if (!st_.absolute) fail(*motion_w, "G5.2 control points need absolute distance mode (G90)");
            if (!need_feed(*motion_w)) nurbs_->bad = true;
            if (const Word* l = word('L')) {
                if (l->value < 3 || l->value > kMaxNurbsOrder || l->value != std::floor(l->value)) {
                    fail(*l, fmt::format("G5.2 L (the order) must be a whole number from 3 to {} (LinuxCNC reads "
                                         "L below 3 as 3)",
                                         kMaxNurbsOrder));
                } else {
                    nurbs_->order = static_cast<int>(l->value);
                }
            }
            if (!axis_w[X] && !axis_w[Y]) {
                if (const Word* p = word('P')) {  // the first point's weight
                    if (!(p->value > 0)) {
                        fail(*p, "NURBS weight P must be > 0");
                    } else {
                        nurbs_->weights.front() = p->value;
                    }
                }
            }
        } else if (!nurbs_) {
            return;  // the G5.2 line was refused; already reported
        } else if (const Word* l = word('L')) {
            fail(*l, "G5.2 L (the order) is given on the G5.2 line only");
        }
        if (axis_w[X] || axis_w[Y]) {
            const Word* p = word('P');
            if (!axis_w[X] || !axis_w[Y]) {
                fail(axis_w[X] ? *axis_w[X] : *axis_w[Y], "G5.2 control points need both X and Y");
            } else if (!p) {
                fail(*axis_w[X], "G5.2 control point without a weight: give P > 0");
            } else if (!(p->value > 0)) {
                fail(*p, "NURBS weight P must be > 0");
            } else {
                nurbs_->pts.push_back(xy_target(axis_w[X], axis_w[Y]));
                nurbs_->weights.push_back(p->value);
            }
        } else if (!motion_w && word('P')) {
            fail(*word('P'), "P without X and Y: only the G5.2 line may give the first point's weight alone");
        }
        if (const Word* k = word('K')) {
            if (!nurbs_->knots.empty() && k->value < nurbs_->knots.back()) {
                fail(*k, fmt::format("knots must not decrease: K{:g} after K{:g}", k->value, nurbs_->knots.back()));
            } else if (!std::isfinite(k->value)) {
                fail(*k, "knot K must be a finite number");
            }
            nurbs_->knots.push_back(k->value);
            nurbs_->knot_loc.push_back({line_, k->col});
        }
    }

    template <class WordFn>
    void close_nurbs(const Word& at, const Word* const axis_w[kAxes], WordFn word) {
        st_.motion.reset();  // G5.3 leaves no motion mode (LinuxCNC)
        if (!nurbs_) {
            error(line_, at.col, "G5.3 without an open G5.2 NURBS");
            return;
        }
        OpenNurbs o = std::move(*nurbs_);
        nurbs_.reset();
        for (const Word* w : {axis_w[X], axis_w[Y], word('P'), word('K'), word('L'), word('I'), word('J')}) {
            if (w) {
                error(line_, w->col, fmt::format("G5.3 takes no {} word: it only ends the NURBS", w->letter));
                o.bad = true;
            }
        }
        if (o.bad) {
            if (o.pts.size() > 1) {  // leave the tool where the curve would end
                st_.pos[X] = o.pts.back()[0];
                st_.pos[Y] = o.pts.back()[1];
            }
            return;
        }
        const auto order = static_cast<std::size_t>(o.order);
        if (o.pts.size() < order) {
            error(line_, at.col,
                  fmt::format("a NURBS of order {} needs at least {} control points (the start counts as the "
                              "first); got {} (G5.2 on line {})",
                              o.order, o.order, o.pts.size(), o.open.line));
            return;
        }
        std::vector<double> knots = o.knots;
        if (knots.empty()) {
            knots = Nurbs::uniform_clamped_knots(o.pts.size(), o.order);
        } else if (knots.size() != o.pts.size() + order) {
            error(line_, at.col,
                  fmt::format("a NURBS of order {} with {} control points (the start counts as the first) needs {} "
                              "knots, got {} K words",
                              o.order, o.pts.size(), o.pts.size() + order, knots.size()));
            return;
        }
        if (auto e = Nurbs::validate(o.order, o.pts.size(), o.weights, knots)) {
            const SourceLoc loc = o.knot_loc.empty() ? SourceLoc{line_, at.col} : o.knot_loc.front();
            error(loc.line, loc.col, *e);
            return;
        }
        emit_curve(o.block, std::make_shared<const Nurbs>(o.order, std::move(o.pts), std::move(o.weights),
                                                          std::move(knots)));
    }

    // G5 (cubic Bezier: start, start + IJ, end + PQ, end) and G5.1 (quadratic:
    // start, start + IJ, end), as LinuxCNC builds them (I J P Q incremental).
    template <class WordFn>
    void bezier(int mode, const Word& at, const Word* const axis_w[kAxes], WordFn word) {
        const std::string name = gname(mode);
        if (const Word* k = word('K')) {
            error(line_, k->col, fmt::format("K is not used by {}", name));
            return;
        }
        if (!need_feed(at)) return;
        const Word *wi = word('I'), *wj = word('J'), *wp = word('P'), *wq = word('Q');
        const Eigen::Vector3d p0(st_.pos[X], st_.pos[Y], st_.pos[Z]);
        const Eigen::Vector3d p3 = xy_target(axis_w[X], axis_w[Y]);
        Eigen::Vector3d ij = Eigen::Vector3d::Zero();
        if (mode == g(5, 1)) {
            if (!wi || !wj) {
                error(line_, at.col, "G5.1 needs both I and J (the control point, relative to the start)");
                return;
            }
        } else if (!wp || !wq) {
            error(line_, at.col, "G5 needs both P and Q (the second control point, relative to the end)");
            return;
        } else if ((wi == nullptr) != (wj == nullptr)) {
            error(line_, (wi ? wi : wj)->col, "G5 needs both I and J, or neither (to continue the previous G5)");
            return;
        } else if (!wi) {
            if (!g5_next_ij_ || *g5_next_ij_block_ != block_count()) {
                error(line_, at.col, "G5 without I and J continues a previous G5: give I and J on the first");
                return;
            }
            ij = *g5_next_ij_;
        }
        if (wi) ij = Eigen::Vector3d(wi->value * st_.unit, wj->value * st_.unit, 0);
        std::vector<Eigen::Vector3d> pts{p0, p0 + ij};
        Eigen::Vector3d pq = Eigen::Vector3d::Zero();
        if (mode == g(5)) {
            pq = Eigen::Vector3d(wp->value * st_.unit, wq->value * st_.unit, 0);
            pts.push_back(p3 + pq);
        }
        pts.push_back(p3);
        const int order = static_cast<int>(pts.size());
        const std::size_t n = pts.size();
        MotionBlock b = base_block(MotionKind::nurbs);
        emit_curve(b, std::make_shared<const Nurbs>(order, std::move(pts), std::vector<double>(n, 1.0),
                                                    Nurbs::uniform_clamped_knots(n, order)));
        g5_next_ij_.reset();
        if (mode == g(5)) {
            g5_next_ij_ = -pq;
            g5_next_ij_block_ = block_count();
        }
    }

    // A NURBS still open at the end of the program.
    void end_of_program() {
        if (nurbs_) {
            error(nurbs_->open.line, nurbs_->open.col, "G5.2 NURBS not ended by G5.3");
            nurbs_.reset();
        }
    }

    bool ended() const { return ended_; }
    // The blocks made so far, moved out between lines (stream_gcode), and how
    // many the program has made in all.
    void take_blocks(std::vector<MotionBlock>& out) {
        for (MotionBlock& b : job_.blocks) out.push_back(std::move(b));
        taken_ += job_.blocks.size();
        job_.blocks.clear();
    }
    std::size_t block_count() const { return taken_ + job_.blocks.size(); }
    void note_after_end(int line) {
        if (!probe_failed_) warn(line, 1, "text after the program end (M2/M30) is ignored");
    }
    void reset_line_flags() { z_consumed_ = false; }

private:
    std::string file_;
    GcodeOptions opt_;
    State st_;
    Job job_;
    std::size_t taken_ = 0;  // blocks moved out by take_blocks()
    gcode::Parameters params_;
    bool ended_ = false;
    bool probe_failed_ = false;  // a G38 move failed: the program stops there
    bool warned_units_ = false;
    bool warned_home_ = false;
    bool z_consumed_ = false;
    std::optional<OpenNurbs> nurbs_;
    std::optional<Eigen::Vector3d> g5_next_ij_;        // -P, -Q of the last G5 (mm) ...
    std::optional<std::size_t> g5_next_ij_block_;      // ... valid while no block followed it
    double cycle_total_ = 0;        // holes x pecks of the cycle blocks so far
    bool cycle_job_refused_ = false;
    int line_ = 0;
    SourceLoc loc_;
    std::vector<Diagnostic> errors_;
    std::vector<Diagnostic> warnings_;
};

// The message with every number replaced by '#', for grouping repeats.
std::string shape(const std::string& m) {
    std::string out;
    for (std::size_t i = 0; i < m.size(); ++i) {
        const char c = m[i];
        if (std::isdigit(static_cast<unsigned char>(c))) {
            while (i + 1 < m.size() && (std::isdigit(static_cast<unsigned char>(m[i + 1])) || m[i + 1] == '.')) ++i;
            out.push_back('#');
        } else {
            out.push_back(c);
        }
    }
    return out;
}

}  // namespace

ArcFrame arc_frame(const MotionBlock& b) {
    switch (b.plane) {
        case Plane::zx: return {2, 0, b.center_z, b.center_x};
        case Plane::yz: return {1, 2, b.center_y, b.center_z};
        case Plane::xy: break;
    }
    return {0, 1, b.center_x, b.center_y};
}

GcodeOptions gcode_options(const Machine& machine, const PerAxis<double>& start) {
    GcodeOptions o;
    o.start_position = start;
    PerAxis<bool> present{};
    for (std::size_t a = 0; a < kAxes; ++a) present[a] = machine.axes[a].present;
    o.axes_present = present;
    o.z_words = machine.gcode.z_words;
    o.g28_position = machine.gcode.g28_position;
    o.g30_position = machine.gcode.g30_position;
    o.tool_lengths = machine.gcode.tool_lengths;
    return o;
}

std::vector<Diagnostic> summarize_repeats(std::vector<Diagnostic> diags) {
    std::vector<Diagnostic> out;
    std::map<std::pair<std::string, std::string>, std::size_t> first;  // (file, shape) -> index in out
    std::vector<std::size_t> count;
    std::vector<int> last_line;
    for (auto& d : diags) {
        const auto key = std::pair{d.file, shape(d.message)};
        auto it = first.find(key);
        if (it == first.end()) {
            first.emplace(key, out.size());
            count.push_back(1);
            last_line.push_back(d.loc.line);
            out.push_back(std::move(d));
        } else {
            ++count[it->second];
            last_line[it->second] = d.loc.line;
        }
    }
    for (std::size_t i = 0; i < out.size(); ++i) {
        if (count[i] > 1) {
            out[i].message += fmt::format(" ({} times, lines {}-{})", count[i], out[i].loc.line, last_line[i]);
        }
    }
    return out;
}

std::span<const std::string_view> ignored_codes() { return kIgnored; }

namespace {

// Binary data (a NUL byte, or mostly bytes that are neither printable ASCII,
// whitespace nor UTF-8, in the first 4 KiB) is refused whole with one error,
// instead of one error per line of noise.
constexpr std::size_t kBinaryHead = 4096;
std::optional<Diagnostic> binary_data(std::string_view head, std::string_view file) {
    head = head.substr(0, kBinaryHead);
    std::size_t odd = 0;
    bool nul = false;
    for (const char ch : head) {
        const auto c = static_cast<unsigned char>(ch);
        nul = nul || c == 0;
        odd += c < 0x20 && c != '\n' && c != '\r' && c != '\t' && c != '\f' && c != '\v';
        odd += c == 0x7f;
    }
    if (nul || (head.size() >= 64 && odd * 10 > head.size())) {
        return Diagnostic{std::string(file), {1, 1},
                          nul ? "not a G-code text file: it holds NUL bytes (binary data)"
                              : fmt::format("not a G-code text file: {} of its first {} bytes are "
                                            "control characters (binary data)",
                                            odd, head.size())};
    }
    return std::nullopt;
}

// A UTF-8 byte-order mark (as some Windows editors write) is not part of line 1.
constexpr std::string_view kBom = "\xEF\xBB\xBF";

// Line `line` of the program (without its newline): false once the program
// has ended and text after it was noted.
bool run_program_line(Parser& p, std::string_view s, int line) {
    if (p.ended()) {
        if (!gcode::read_line(s, {}).empty()) {
            p.note_after_end(line);
            return false;
        }
        return true;
    }
    p.reset_line_flags();
    p.run_line(s, line);
    return true;
}

}  // namespace

Result<Job> parse_gcode(std::string_view text, std::string_view file, const GcodeOptions& options) {
    if (auto e = binary_data(text, file)) {
        Result<Job> r;
        r.errors.push_back(std::move(*e));
        return r;
    }
    Parser p(file, options);
    int line = 0;
    std::size_t pos = text.starts_with(kBom) ? kBom.size() : 0;
    while (pos <= text.size()) {
        auto nl = text.find('\n', pos);
        if (nl == std::string_view::npos) nl = text.size();
        if (!run_program_line(p, text.substr(pos, nl - pos), ++line)) break;
        pos = nl + 1;
    }
    return p.finish();
}

Result<Job> stream_gcode(const std::filesystem::path& path, const GcodeOptions& options,
                         const std::function<void(MotionBlock&&, std::size_t)>& sink) {
    if (options.probe) {
        Result<Job> r;
        r.errors.push_back({path.string(), {}, "a program with probe moves is read whole (parse_gcode), not streamed"});
        return r;
    }
    GcodeBlockReader reader(path, options);
    std::size_t handed = 0;
    while (auto b = reader.next()) sink(std::move(*b), handed++);
    return reader.result();
}

// The program's text a piece at a time, each line (without its newline) handed
// to the parser as soon as it is whole: a line that runs past one piece waits
// for the next. The pieces are a text the caller holds (one piece) or a file's
// kGcodePiece bytes each, recorded in a mark or checked against one.
struct GcodeBlockReader::Impl {
    std::string file;
    Parser parser;
    std::shared_ptr<const std::string> text;
    std::shared_ptr<const int> fd;  // the file, read with pread (null: it could not be opened)
    GcodeFileMark* record = nullptr;
    std::shared_ptr<const GcodeFileMark> check;
    std::string buf, carry;
    std::string_view piece;
    std::size_t pos = 0;        // the piece's first byte not yet in a line
    std::size_t pieces = 0;     // pieces read
    std::uint64_t offset = 0;   // the file's bytes before the current piece
    bool last = false;          // the current piece is the last
    bool have_piece = false, lines_done = false;
    int line = 0;
    std::vector<MotionBlock> made;
    std::size_t next_made = 0;
    std::optional<Result<Job>> done;

    Impl(std::string f, const GcodeOptions& o) : file(std::move(f)), parser(file, o) {}

    void refuse(Diagnostic d) {
        done.emplace().errors.push_back(std::move(d));
        lines_done = true;
    }

    // The next piece into `piece`; false when the reading stopped (done holds why).
    bool read_piece() {
        if (text) {
            piece = *text;
            last = true;
        } else {
            if (!fd) {
                refuse({file, {}, "cannot open file"});
                return false;
            }
            buf.resize(kGcodePiece);
            std::size_t got = 0;
            while (got < buf.size()) {
                const ssize_t n = ::pread(*fd, buf.data() + got, buf.size() - got, static_cast<off_t>(offset + got));
                if (n < 0 && errno == EINTR) continue;
                if (n < 0) {
                    refuse({file, {line + 1, 1}, fmt::format("cannot read the file at byte {}: {}", offset + got,
                                                             std::strerror(errno))});
                    return false;
                }
                if (n == 0) break;
                got += static_cast<std::size_t>(n);
            }
            piece = std::string_view(buf.data(), got);
            last = got < buf.size();
            const std::size_t hash = std::hash<std::string_view>{}(piece);
            if (record) {
                record->pieces.push_back(hash);
                record->size = offset + got;
            }
            if (check) {
                const std::uint64_t expect =
                    check->size > offset ? std::min<std::uint64_t>(check->size - offset, kGcodePiece) : 0;
                if (pieces >= check->pieces.size() || got != expect || check->pieces[pieces] != hash) {
                    struct stat st {};
                    const bool known = ::fstat(*fd, &st) == 0;
                    refuse({file, {line + 1, 1},
                            fmt::format("the file changed after the job was planned from it: bytes {} to {} "
                                        "differ ({} bytes then, {} now)",
                                        offset, offset + std::max<std::uint64_t>({got, expect, 1}) - 1, check->size,
                                        known ? std::to_string(st.st_size) : std::string("unknown"))});
                    return false;
                }
            }
            offset += got;
        }
        if (pieces++ == 0) {
            // The first piece holds the first 4 KiB, or the whole text.
            if (auto e = binary_data(piece, file)) {
                refuse(std::move(*e));
                return false;
            }
            if (piece.starts_with(kBom)) piece.remove_prefix(kBom.size());
        }
        pos = 0;
        have_piece = true;
        return true;
    }

    // The next line into the parser; false when there is none (lines_done).
    bool next_line() {
        for (;;) {
            if (!have_piece && !read_piece()) return false;
            const auto nl = piece.find('\n', pos);
            if (nl != std::string_view::npos) {
                std::string_view s = piece.substr(pos, nl - pos);
                if (!carry.empty()) {
                    carry.append(s);
                    s = carry;
                }
                pos = nl + 1;
                if (!run_program_line(parser, s, ++line)) lines_done = true;
                carry.clear();
                return true;
            }
            carry.append(piece.substr(pos));
            have_piece = false;
            if (last) {
                // The text after the last newline (parse_gcode's last line, empty or not).
                run_program_line(parser, carry, ++line);
                carry.clear();
                lines_done = true;
                return true;
            }
        }
    }
};

GcodeBlockReader::GcodeBlockReader(std::shared_ptr<const std::string> text, std::string file,
                                   const GcodeOptions& options)
    : impl_(std::make_unique<Impl>(std::move(file), options)) {
    impl_->text = std::move(text);
}

namespace {

// The file opened for reading, closed with its last owner; null when it cannot be opened.
std::shared_ptr<const int> open_file(const std::filesystem::path& path) {
    int fd = -1;
    do fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0) return nullptr;
    return std::shared_ptr<const int>(new int(fd), [](const int* p) {
        ::close(*p);
        delete p;
    });
}

}  // namespace

GcodeBlockReader::GcodeBlockReader(const std::filesystem::path& path, const GcodeOptions& options,
                                   GcodeFileMark* mark)
    : impl_(std::make_unique<Impl>(path.string(), options)) {
    impl_->fd = open_file(path);
    impl_->record = mark;
    if (mark) *mark = GcodeFileMark{path.string(), 0, {}, impl_->fd};
}

GcodeBlockReader::GcodeBlockReader(std::shared_ptr<const GcodeFileMark> mark, const GcodeOptions& options)
    : impl_(std::make_unique<Impl>(mark->path, options)) {
    impl_->fd = mark->descriptor ? mark->descriptor : open_file(mark->path);
    impl_->check = std::move(mark);
}

GcodeBlockReader::~GcodeBlockReader() = default;

std::optional<MotionBlock> GcodeBlockReader::next() {
    Impl& p = *impl_;
    for (;;) {
        if (p.next_made < p.made.size()) return std::move(p.made[p.next_made++]);
        p.made.clear();
        p.next_made = 0;
        if (p.done) return std::nullopt;
        if (!p.lines_done && p.next_line()) {
            p.parser.take_blocks(p.made);
            continue;
        }
        if (p.done) return std::nullopt;  // the reading stopped
        // The end: what it closes (a curve) comes out only when the program is accepted.
        p.done = p.parser.finish();
        if (p.done->value) {
            p.made = std::move(p.done->value->blocks);
            p.done->value->blocks.clear();
        }
    }
}

const Result<Job>& GcodeBlockReader::result() const {
    if (!impl_->done) throw std::logic_error("GcodeBlockReader::result before the program's end");
    return *impl_->done;
}

bool file_has_probe_words(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    for (std::string line; std::getline(in, line);)
        if (has_probe_words(line)) return true;
    return false;
}

bool has_probe_words(std::string_view text) {
    for (std::size_t pos = 0; pos <= text.size();) {
        std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos) nl = text.size();
        for (const Word& w : gcode::read_line(text.substr(pos, nl - pos), {}).words) {
            const long tenths = std::lround(w.value * 10);
            if (w.letter == 'G' && w.known && is_probe(static_cast<int>(tenths))) return true;
        }
        pos = nl + 1;
    }
    return false;
}

Result<Job> load_gcode(const std::filesystem::path& path, const GcodeOptions& options) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        Result<Job> r;
        r.errors.push_back({path.string(), {}, "cannot open file"});
        return r;
    }
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_gcode(ss.str(), path.string(), options);
}

}  // namespace cpstep::plan

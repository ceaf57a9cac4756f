#include "plan/gcode.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <fmt/format.h>

namespace cpstep::plan {

namespace {

// G codes are compared as integers in tenths (G61.1 -> 611).
constexpr int g(int whole, int tenth = 0) { return whole * 10 + tenth; }

constexpr std::string_view kIgnored[] = {"G40", "G49", "G54", "G61", "G61.1", "G64", "G80",
                                         "G94", "M6",  "M7",  "M8",  "M9",    "T"};

struct Word {
    char letter;     // upper case
    double value;
    int col;         // 1-based
    std::string text;
};

// Modal state carried from line to line.
struct State {
    std::optional<int> motion;     // g(0..3)
    double unit = 1.0;             // mm per program unit (25.4 after G20)
    bool absolute = true;          // G90 / G91
    PerAxis<double> offset{};      // G92: machine = program + offset
    PerAxis<double> pos{};         // current machine position, mm
    std::optional<double> feed;    // mm/s
    bool spindle_on = false;
    double spindle_speed = 0;
};

class Parser {
public:
    Parser(std::string_view file, const GcodeOptions& opt) : file_(file) {
        st_.pos = opt.start_position;
        job_.file = std::string(file);
    }

    void error(int line, int col, std::string msg) {
        errors_.push_back({file_, {line, col}, std::move(msg)});
    }

    // Split one line into words; false when the line had a lexical error.
    bool lex(std::string_view s, int line, std::vector<Word>& words) {
        std::size_t i = 0;
        bool ok = true;
        while (i < s.size()) {
            const char c = s[i];
            const int col = static_cast<int>(i) + 1;
            if (c == ' ' || c == '\t' || c == '\r') {
                ++i;
            } else if (c == ';') {
                break;
            } else if (c == '(') {
                const auto close = s.find(')', i);
                if (close == std::string_view::npos) {
                    error(line, col, "comment '(' is not closed on this line");
                    return false;
                }
                i = close + 1;
            } else if (c == '%' && words.empty() && s.find_first_not_of(" \t\r%") == std::string_view::npos) {
                break;  // program delimiter line
            } else if (c == '/' && words.empty()) {
                error(line, col, "block delete '/' is not supported");
                return false;
            } else if (std::isalpha(static_cast<unsigned char>(c))) {
                const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
                std::size_t j = i + 1;
                if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
                const std::size_t num_begin = j;
                while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.')) ++j;
                std::string num(s.substr(num_begin, j - num_begin));
                const bool neg = num_begin > i + 1 && s[i + 1] == '-';
                double v = 0;
                const auto* b = num.data();
                const auto* e = num.data() + num.size();
                auto [p, ec] = std::from_chars(b, e, v);
                if (num.empty() || ec != std::errc() || p != e) {
                    error(line, col, fmt::format("expected a number after '{}'", letter));
                    ok = false;
                    i = j;
                    continue;
                }
                words.push_back({letter, neg ? -v : v, col, std::string(s.substr(i, j - i))});
                i = j;
            } else {
                error(line, col, fmt::format("unexpected character '{}'", c));
                ok = false;
                ++i;
            }
        }
        return ok;
    }

    void run_line(std::string_view s, int line) {
        std::vector<Word> words;
        if (!lex(s, line, words) || words.empty()) return;
        const std::size_t errors_before = errors_.size();
        auto err = [&](const Word& w, std::string msg) { error(line, w.col, std::move(msg)); };

        std::map<char, const Word*> by_letter;
        std::vector<const Word*> gs, ms;
        for (const auto& w : words) {
            if (w.letter == 'G') {
                gs.push_back(&w);
            } else if (w.letter == 'M') {
                ms.push_back(&w);
            } else if (by_letter.count(w.letter) != 0) {
                err(w, fmt::format("word '{}' appears twice in one block", w.letter));
            } else {
                by_letter[w.letter] = &w;
            }
        }
        for (const auto& [letter, w] : by_letter) {
            if (std::string_view("XYZAIJRFSPQNT").find(letter) == std::string_view::npos) {
                if (letter == 'K') {
                    err(*w, "K is only used by G18/G19 arcs; only the XY plane (G17) is supported");
                } else {
                    err(*w, fmt::format("unsupported word '{}'", w->text));
                }
            }
        }

        // G codes, sorted into their modal groups.
        const Word* motion_word = nullptr;
        const Word* nonmodal_word = nullptr;  // G4 or G92
        const Word* units_word = nullptr;
        const Word* distance_word = nullptr;
        const Word* g64_word = nullptr;
        auto set_group = [&](const Word*& slot, const Word* w, std::string_view group) {
            if (slot != nullptr) {
                err(*w, fmt::format("{} and {} are in the same modal group ({})", slot->text,
                                    w->text, group));
                return;  // keep the first, so later checks do not cascade
            }
            slot = w;
        };
        for (const Word* w : gs) {
            const double tenths = w->value * 10;
            const int code = static_cast<int>(std::lround(tenths));
            if (std::abs(tenths - code) > 1e-6 || w->value < 0) {
                err(*w, fmt::format("unsupported G-code {}", w->text));
                continue;
            }
            switch (code) {
                case g(0): case g(1): case g(2): case g(3):
                    set_group(motion_word, w, "motion"); break;
                case g(4): case g(92):
                    set_group(nonmodal_word, w, "non-modal"); break;
                case g(17): break;
                case g(18): case g(19):
                    err(*w, fmt::format("{}: only the XY plane (G17) is supported", w->text)); break;
                case g(20): case g(21): set_group(units_word, w, "units"); break;
                case g(90): case g(91): set_group(distance_word, w, "distance"); break;
                case g(93): err(*w, "inverse-time feed (G93) is not supported; use G94"); break;
                case g(64): g64_word = w; break;
                case g(40): case g(49): case g(54): case g(61): case g(61, 1): case g(80):
                case g(94): break;  // ignore list
                default: err(*w, fmt::format("unsupported G-code {}", w->text)); break;
            }
        }
        bool end_program = false;
        std::optional<bool> spindle;
        for (const Word* w : ms) {
            const int code = static_cast<int>(std::lround(w->value));
            if (std::abs(w->value - code) > 1e-9) {
                err(*w, fmt::format("unsupported M-code {}", w->text));
                continue;
            }
            switch (code) {
                case 2: case 30: end_program = true; break;
                case 3: case 4: spindle = true; break;
                case 5: spindle = false; break;
                case 6: case 7: case 8: case 9: break;  // ignore list
                default: err(*w, fmt::format("unsupported M-code {}", w->text)); break;
            }
        }
        auto word = [&](char l) -> const Word* {
            auto it = by_letter.find(l);
            return it == by_letter.end() ? nullptr : it->second;
        };
        const bool is_g4 = nonmodal_word != nullptr && std::lround(nonmodal_word->value * 10) == g(4);
        const bool is_g92 = nonmodal_word != nullptr && !is_g4;
        if (const Word* p = word('P'); p != nullptr && !is_g4 && g64_word == nullptr) {
            err(*p, "P is only accepted with G4 (dwell seconds) or G64");
        }
        if (const Word* q = word('Q'); q != nullptr && g64_word == nullptr) {
            err(*q, "Q is only accepted with G64");
        }
        if (errors_.size() != errors_before) return;

        // Execution order of RS274/NGC, restricted to what we support.
        if (units_word != nullptr) st_.unit = std::lround(units_word->value) == 20 ? 25.4 : 1.0;
        if (distance_word != nullptr) st_.absolute = std::lround(distance_word->value) == 90;
        if (const Word* f = word('F')) {
            if (!(f->value > 0)) {
                err(*f, "feed rate F must be > 0");
            } else {
                st_.feed = f->value * st_.unit / 60.0;  // units/min -> mm/s
            }
        }
        if (const Word* sw = word('S')) {
            if (sw->value < 0) err(*sw, "spindle speed S must be >= 0");
            st_.spindle_speed = sw->value;
        }
        if (spindle) st_.spindle_on = *spindle;

        const Word* axis_words[kAxes] = {word('X'), word('Y'), word('Z'), word('A')};
        const bool any_axis = std::any_of(std::begin(axis_words), std::end(axis_words),
                                          [](const Word* w) { return w != nullptr; });
        const SourceLoc first{line, words.front().col};

        if (is_g4) {
            const Word* p = word('P');
            if (any_axis || motion_word != nullptr) {
                err(*nonmodal_word, "G4 takes no axis words and no motion code");
            } else if (p == nullptr) {
                err(*nonmodal_word, "G4 needs P<seconds>");
            } else if (p->value < 0) {
                err(*p, "dwell P must be >= 0 seconds");
            } else if (p->value > 0) {
                MotionBlock b = base_block(MotionKind::dwell, first);
                b.dwell_s = p->value;
                job_.blocks.push_back(b);
            }
        } else if (is_g92) {
            if (!any_axis) {
                err(*nonmodal_word, "G92 needs at least one axis word");
            } else if (motion_word != nullptr) {
                err(*motion_word, "a motion code cannot share a block with G92");
            }
            for (int a = 0; a < kAxes; ++a) {
                if (const Word* w = axis_words[a]) {
                    const auto i = static_cast<std::size_t>(a);
                    st_.offset[i] = st_.pos[i] - w->value * st_.unit;
                }
            }
        } else {
            if (motion_word != nullptr) st_.motion = static_cast<int>(std::lround(motion_word->value * 10));
            const bool has_ij = word('I') != nullptr || word('J') != nullptr;
            const bool has_r = word('R') != nullptr;
            if (any_axis || motion_word != nullptr || has_ij || has_r) {
                if (!st_.motion) {
                    err(words.front(), "axis words without a motion mode (G0, G1, G2 or G3)");
                } else {
                    motion(*st_.motion, line, motion_word ? *motion_word : words.front(), axis_words,
                           word('I'), word('J'), word('R'), first);
                }
            }
        }
        if (end_program) ended_ = true;
    }

    MotionBlock base_block(MotionKind kind, SourceLoc loc) const {
        MotionBlock b;
        b.kind = kind;
        b.loc = loc;
        b.start = st_.pos;
        b.end = st_.pos;
        b.spindle_on = st_.spindle_on;
        b.spindle_speed = st_.spindle_speed;
        return b;
    }

    void motion(int mode, int line, const Word& at, const Word* const axis_words[kAxes],
                const Word* wi, const Word* wj, const Word* wr, SourceLoc loc) {
        auto err = [&](const Word& w, std::string msg) { error(line, w.col, std::move(msg)); };
        PerAxis<double> target = st_.pos;
        bool moved_word = false;
        for (int a = 0; a < kAxes; ++a) {
            const auto i = static_cast<std::size_t>(a);
            if (const Word* w = axis_words[a]) {
                moved_word = true;
                target[i] = st_.absolute ? w->value * st_.unit + st_.offset[i]
                                         : st_.pos[i] + w->value * st_.unit;
            }
        }
        const bool arc = mode == g(2) || mode == g(3);
        if (!arc && (wi || wj || wr)) {
            err(wi ? *wi : wj ? *wj : *wr, "I, J and R are only used by G2/G3 arcs");
            return;
        }
        if (!arc && !moved_word) return;  // e.g. a bare "G0" sets the mode only
        MotionBlock b = base_block(mode == g(0) ? MotionKind::rapid
                                   : mode == g(1) ? MotionKind::linear
                                   : mode == g(2) ? MotionKind::arc_cw
                                                  : MotionKind::arc_ccw,
                                   loc);
        b.end = target;
        if (mode != g(0)) {
            if (!st_.feed) {
                err(at, "feed rate is not set (F) for a G1/G2/G3 move");
                return;
            }
            b.feed = *st_.feed;
        }
        if (arc) {
            const double x0 = st_.pos[0], y0 = st_.pos[1], x1 = target[0], y1 = target[1];
            if (wr && (wi || wj)) {
                err(*wr, "give either I/J or R for an arc, not both");
                return;
            }
            if (wr) {
                const double r = wr->value * st_.unit;
                const double dx = x1 - x0, dy = y1 - y0;
                const double d = std::hypot(dx, dy);
                if (d < 1e-9) {
                    err(*wr, "an R-form arc cannot end where it starts; use I/J for a full circle");
                    return;
                }
                double h2 = r * r - d * d / 4;
                if (h2 < 0) {
                    if (std::abs(r) * 2 < d - 1e-6) {
                        err(*wr, fmt::format("arc radius {:g} is shorter than half the chord "
                                             "({:g} mm)",
                                             std::abs(r), d / 2));
                        return;
                    }
                    h2 = 0;
                }
                // Centre to the right of travel for CW with R > 0 (the shorter arc).
                double h = std::sqrt(h2);
                if ((mode == g(2)) == (r > 0)) h = -h;
                const double nx = -dy / d, ny = dx / d;  // left normal
                b.center_x = (x0 + x1) / 2 + h * nx;
                b.center_y = (y0 + y1) / 2 + h * ny;
            } else if (wi || wj) {
                b.center_x = x0 + (wi ? wi->value * st_.unit : 0.0);
                b.center_y = y0 + (wj ? wj->value * st_.unit : 0.0);
                const double r0 = std::hypot(x0 - b.center_x, y0 - b.center_y);
                const double r1 = std::hypot(x1 - b.center_x, y1 - b.center_y);
                if (r0 < 1e-9) {
                    err(wi ? *wi : *wj, "arc radius is zero");
                    return;
                }
                if (std::abs(r0 - r1) > 0.005 && std::abs(r0 - r1) > 0.001 * r0) {
                    err(at, fmt::format("arc end is not on the circle: radius {:.4f} mm at the "
                                        "start, {:.4f} mm at the end",
                                        r0, r1));
                    return;
                }
            } else {
                err(at, "an arc needs I/J (centre offset) or R (radius)");
                return;
            }
        }
        st_.pos = target;
        job_.blocks.push_back(b);
    }

    Result<Job> finish() {
        Result<Job> r;
        // Report in reading order, whatever order the checks ran in.
        std::stable_sort(errors_.begin(), errors_.end(), [](const Diagnostic& a, const Diagnostic& b) {
            return a.loc.line != b.loc.line ? a.loc.line < b.loc.line : a.loc.col < b.loc.col;
        });
        r.errors = std::move(errors_);
        r.warnings = std::move(warnings_);
        if (r.errors.empty()) r.value = std::move(job_);
        return r;
    }

    bool ended() const { return ended_; }
    void warn(int line, std::string msg) { warnings_.push_back({file_, {line, 1}, std::move(msg)}); }

private:
    std::string file_;
    State st_;
    Job job_;
    bool ended_ = false;
    std::vector<Diagnostic> errors_;
    std::vector<Diagnostic> warnings_;
};

}  // namespace

std::span<const std::string_view> ignored_codes() { return kIgnored; }

Result<Job> parse_gcode(std::string_view text, std::string_view file, const GcodeOptions& options) {
    Parser p(file, options);
    int line = 0;
    std::size_t pos = 0;
    while (pos <= text.size()) {
        auto nl = text.find('\n', pos);
        if (nl == std::string_view::npos) nl = text.size();
        const std::string_view s = text.substr(pos, nl - pos);
        ++line;
        if (p.ended()) {
            if (s.find_first_not_of(" \t\r%") != std::string_view::npos) {
                p.warn(line, "text after the program end (M2/M30) is ignored");
                break;
            }
        } else {
            p.run_line(s, line);
        }
        pos = nl + 1;
    }
    return p.finish();
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

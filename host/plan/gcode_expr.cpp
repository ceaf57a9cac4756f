// SPDX-License-Identifier: MIT
#include "plan/gcode_expr.h"

#include <cctype>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

namespace cpstep::plan::gcode {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kEqualTolerance = 1e-6;  // EQ/NE compare within this (LinuxCNC's TOLERANCE_EQUAL)

// A character for a message: 'c', or \xNN when it does not print.
std::string show(char c) {
    if (std::isprint(static_cast<unsigned char>(c)) != 0) return fmt::format("'{}'", c);
    return fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
}

// The line with comments and whitespace removed, lower case, each character
// with its 1-based column in the original line.
struct Compact {
    std::string s;
    std::vector<int> col;
};

struct Fail {
    int col;
    std::string message;
};

class Reader {
public:
    Reader(const Compact& c, const Parameters& p) : c_(c), prm_(p) {}

    [[nodiscard]] bool at_end() const { return p_ >= c_.s.size(); }
    [[nodiscard]] char peek(std::size_t k = 0) const {
        return p_ + k < c_.s.size() ? c_.s[p_ + k] : '\0';
    }
    [[nodiscard]] int col() const {
        if (c_.col.empty()) return 1;
        return p_ < c_.col.size() ? c_.col[p_] : c_.col.back() + 1;
    }
    [[nodiscard]] std::size_t pos() const { return p_; }
    void advance(std::size_t n = 1) { p_ += n; }
    [[nodiscard]] bool starts(std::string_view w) const { return c_.s.compare(p_, w.size(), w) == 0; }
    [[nodiscard]] std::string text(std::size_t from) const { return c_.s.substr(from, p_ - from); }

    // Errors are thrown as Fail: reading a line stops at its first error.
    [[noreturn]] void fail(std::string message) const { throw Fail{col(), std::move(message)}; }
    [[noreturn]] void fail_at(int col, std::string message) const { throw Fail{col, std::move(message)}; }

    // sign? ( number | [expression] | #parameter | function[...] ). Each nesting
    // level ([, a sign, #, a function) recurses here once: deeper than kMaxDepth is
    // refused, so that a line of thousands of '[' cannot overflow the stack.
    static constexpr int kMaxDepth = 64;
    double real_value() {
        if (depth_ >= kMaxDepth) fail(fmt::format("expression nested more than {} deep", kMaxDepth));
        struct Level {
            int& depth;
            explicit Level(int& d) : depth(d) { ++depth; }
            ~Level() { --depth; }
            Level(const Level&) = delete;
            Level& operator=(const Level&) = delete;
        } level(depth_);
        if (peek() == '-' || peek() == '+') {
            const bool neg = peek() == '-';
            advance();
            const double v = real_value();
            return neg ? -v : v;
        }
        const char c = peek();
        if (c == '[') return expression();
        if (c == '#') return parameter();
        if (std::isalpha(static_cast<unsigned char>(c))) return function();
        return number();
    }

    double number() {
        const std::size_t from = p_;
        const int at = col();
        bool digits = false, dot = false;
        while (!at_end()) {
            const char c = peek();
            if (std::isdigit(static_cast<unsigned char>(c))) {
                digits = true;
            } else if (c == '.' && !dot) {
                dot = true;
            } else {
                break;
            }
            advance();
        }
        if (!digits) {
            p_ = from;
            if (at_end()) fail("expected a number, found the end of the line");
            fail(fmt::format("expected a number, found {}", show(peek())));
        }
        (void)at;
        return std::strtod(c_.s.substr(from, p_ - from).c_str(), nullptr);
    }

    // '[' binary expression ']'
    double expression() {
        const int open = col();
        advance();  // '['
        const double v = binary(1);
        if (peek() != ']') {
            if (at_end()) fail_at(open, "'[' is not closed on this line");
            fail(fmt::format("expected an operator or ']', found {}", show(peek())));
        }
        advance();
        return v;
    }

    struct Op {
        std::string_view name;
        int prec;
    };
    std::optional<Op> peek_op() const {
        // Longest names first where one is a prefix of another (** before *).
        static constexpr Op ops[] = {{"**", 6}, {"*", 5},  {"/", 5},  {"mod", 5}, {"+", 4},
                                     {"-", 4},  {"eq", 3}, {"ne", 3}, {"gt", 3},  {"ge", 3},
                                     {"lt", 3}, {"le", 3}, {"and", 2}, {"or", 2}, {"xor", 2}};
        for (const Op& o : ops) {
            if (starts(o.name)) return o;
        }
        return std::nullopt;
    }

    // Precedence climbing; every operator is left-associative, as LinuxCNC
    // evaluates equal precedence from left to right.
    double binary(int min_prec) {
        double lhs = real_value();
        while (true) {
            const auto op = peek_op();
            if (!op || op->prec < min_prec) return lhs;
            const int at = col();
            advance(op->name.size());
            const double rhs = binary(op->prec + 1);
            lhs = apply(op->name, lhs, rhs, at);
        }
    }

    double apply(std::string_view op, double a, double b, int at) const {
        if (op == "**") {
            if (a < 0 && b != std::floor(b))
                fail_at(at, fmt::format("{:g} ** {:g}: a negative number to a non-integer power", a, b));
            if (a == 0 && b < 0) fail_at(at, "0 ** a negative power: division by zero");
            return std::pow(a, b);
        }
        if (op == "*") return a * b;
        if (op == "/") {
            if (b == 0) fail_at(at, "division by zero");
            return a / b;
        }
        if (op == "mod") {
            if (b == 0) fail_at(at, "mod by zero");
            double r = std::fmod(a, b);
            if (r < 0) r += std::abs(b);  // LinuxCNC: the result has the sign of |b|
            return r;
        }
        if (op == "+") return a + b;
        if (op == "-") return a - b;
        if (op == "eq") return std::abs(a - b) < kEqualTolerance ? 1 : 0;
        if (op == "ne") return std::abs(a - b) < kEqualTolerance ? 0 : 1;
        if (op == "gt") return a > b ? 1 : 0;
        if (op == "ge") return a >= b ? 1 : 0;
        if (op == "lt") return a < b ? 1 : 0;
        if (op == "le") return a <= b ? 1 : 0;
        if (op == "and") return (a != 0 && b != 0) ? 1 : 0;
        if (op == "or") return (a != 0 || b != 0) ? 1 : 0;
        if (op == "xor") return ((a != 0) != (b != 0)) ? 1 : 0;
        fail_at(at, fmt::format("unknown operator '{}'", op));
    }

    double function() {
        static constexpr std::string_view names[] = {"abs", "acos", "asin", "atan", "cos",  "exists",
                                                     "exp", "fix",  "fup",  "ln",   "round", "sin",
                                                     "sqrt", "tan"};
        const int at = col();
        std::string_view name;
        for (auto n : names) {
            if (starts(n) && c_.s.size() > p_ + n.size() && c_.s[p_ + n.size()] == '[') {
                if (n.size() > name.size()) name = n;
            }
        }
        if (name.empty()) {
            std::size_t e = p_;
            while (e < c_.s.size() && std::isalpha(static_cast<unsigned char>(c_.s[e]))) ++e;
            fail(fmt::format("unknown function or misplaced word '{}'", c_.s.substr(p_, e - p_)));
        }
        advance(name.size());
        if (name == "exists") {
            advance();  // '['
            if (!(peek() == '#' && peek(1) == '<')) fail("exists[] takes a named parameter #<name>");
            advance();
            const std::string n = param_name();
            if (peek() != ']') fail("expected ']' after the parameter name");
            advance();
            return prm_.named.count(n) != 0 ? 1 : 0;
        }
        const double x = expression();
        if (name == "atan") {
            if (peek() != '/' || peek(1) != '[') fail("atan needs two arguments: atan[y]/[x]");
            advance();
            const double xx = expression();
            return std::atan2(x, xx) / kDeg;
        }
        if (name == "abs") return std::abs(x);
        if (name == "acos" || name == "asin") {
            if (x < -1 || x > 1) fail_at(at, fmt::format("{}[{:g}]: the argument must be in -1..1", name, x));
            return (name == "acos" ? std::acos(x) : std::asin(x)) / kDeg;
        }
        if (name == "cos") return std::cos(x * kDeg);
        if (name == "sin") return std::sin(x * kDeg);
        if (name == "tan") return std::tan(x * kDeg);
        if (name == "exp") return std::exp(x);
        if (name == "fix") return std::floor(x);
        if (name == "fup") return std::ceil(x);
        if (name == "ln") {
            if (x <= 0) fail_at(at, fmt::format("ln[{:g}]: the argument must be > 0", x));
            return std::log(x);
        }
        if (name == "round") return std::round(x);  // halves away from zero, as LinuxCNC
        if (name == "sqrt") {
            if (x < 0) fail_at(at, fmt::format("sqrt[{:g}]: the argument must be >= 0", x));
            return std::sqrt(x);
        }
        fail_at(at, fmt::format("unknown function '{}'", name));
    }

    // After '#<': the name up to '>', lower case, whitespace already removed.
    std::string param_name() {
        const int open = col();
        advance();  // '<'
        const std::size_t from = p_;
        while (!at_end() && peek() != '>') advance();
        if (at_end()) fail_at(open, "'#<' is not closed with '>'");
        std::string n = c_.s.substr(from, p_ - from);
        advance();  // '>'
        if (n.empty()) fail_at(open, "empty parameter name #<>");
        return n;
    }

    // After '#': an integer 1..5602 (itself a real value: #[1+2], ##1).
    int param_number() {
        const int at = col();
        const double v = real_value();
        const double r = std::round(v);
        if (std::abs(v - r) > 1e-4) fail_at(at, fmt::format("parameter number {:g} is not an integer", v));
        if (r < 1 || r > kMaxParameter)
            fail_at(at, fmt::format("parameter number {:g} is outside 1..{}", r, kMaxParameter));
        return static_cast<int>(r);
    }

    double parameter() {
        const int at = col();
        advance();  // '#'
        if (peek() == '<') {
            const std::string n = param_name();
            if (prm_.named_poisoned.count(n) != 0) {
                poisoned_ = true;
                return 0;
            }
            auto it = prm_.named.find(n);
            if (it == prm_.named.end()) fail_at(at, fmt::format("named parameter #<{}> is not defined", n));
            return it->second;
        }
        const int n = param_number();
        if (prm_.numbered_poisoned.count(n) != 0) {
            poisoned_ = true;
            return 0;
        }
        if (prm_.system) {
            if (auto v = prm_.system(n)) return *v;
        }
        auto it = prm_.numbered.find(n);
        return it == prm_.numbered.end() ? 0.0 : it->second;
    }

    bool poisoned_ = false;

private:
    const Compact& c_;
    const Parameters& prm_;
    std::size_t p_ = 0;
    int depth_ = 0;  // real_value() levels now open
};

// Comments out, whitespace out, lower case. Sets `error` on an unclosed '('.
Compact compact(std::string_view line, std::optional<LineError>& error) {
    Compact c;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char ch = line[i];
        if (ch == ' ' || ch == '\t' || ch == '\r' || ch == '\f' || ch == '\v') continue;
        if (ch == ';') break;
        if (ch == '(') {
            const auto close = line.find(')', i);
            if (close == std::string_view::npos) {
                error = LineError{static_cast<int>(i) + 1, "comment '(' is not closed on this line"};
                break;
            }
            i = close;
            continue;
        }
        c.s.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(ch))));
        c.col.push_back(static_cast<int>(i) + 1);
    }
    return c;
}

}  // namespace

ReadLine read_line(std::string_view line, const Parameters& params) {
    ReadLine out;
    std::optional<LineError> comment_error;
    Compact c = compact(line, comment_error);
    if (!c.s.empty() && c.s.find_first_not_of('%') == std::string::npos) {
        out.tape = true;
        out.error = comment_error;
        return out;
    }
    Reader r(c, params);
    try {
        if (r.peek() == '/') {
            out.block_delete = true;
            r.advance();
        }
        while (!r.at_end()) {
            const char ch = r.peek();
            const int col = r.col();
            if (ch == '#') {
                // #n = value or #<name> = value
                Assignment a;
                a.col = col;
                r.advance();
                if (r.peek() == '<') {
                    a.named = true;
                    a.name = r.param_name();
                } else {
                    a.number = r.param_number();
                }
                if (r.peek() != '=') r.fail("expected '=' after the parameter (an assignment #n = value)");
                r.advance();
                r.poisoned_ = false;
                try {
                    a.value = r.real_value();
                } catch (const Fail&) {
                    a.known = false;  // the parameter reads as unknown later, without new errors
                    out.assignments.push_back(a);
                    throw;
                }
                a.known = !r.poisoned_;
                out.assignments.push_back(std::move(a));
                continue;
            }
            if (!std::isalpha(static_cast<unsigned char>(ch))) {
                if (ch == '$' && out.words.empty())
                    r.fail("a Grbl '$' system command is not G-code");
                if (ch == '=')
                    r.fail("'=' without a parameter before it");
                if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '+')
                    r.fail(fmt::format("a number without a letter: {}", show(ch)));
                r.fail(fmt::format("unexpected character {}", show(ch)));
            }
            if (ch == 'o') {
                out.o_word = true;
                std::size_t n = 0;
                std::string what;
                while (!r.at_end() && n++ < 24) {
                    what.push_back(r.peek());
                    r.advance();
                }
                throw Fail{col, fmt::format("O-word '{}': subroutines, loops and conditionals "
                                            "(o-codes) are not supported; expand them before planning",
                                            what)};
            }
            Word w;
            w.letter = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
            w.col = col;
            const std::size_t from = r.pos();
            r.advance();
            if (r.at_end()) r.fail_at(col, fmt::format("expected a value after '{}'", w.letter));
            r.poisoned_ = false;
            try {
                w.value = r.real_value();
            } catch (const Fail&) {
                // Record the word as given but unknown, then stop the line.
                w.known = false;
                w.text = std::string(1, w.letter);
                out.words.push_back(w);
                throw;
            }
            w.known = !r.poisoned_;
            w.text = r.text(from);
            w.text[0] = w.letter;
            out.words.push_back(std::move(w));
        }
    } catch (const Fail& f) {
        out.error = LineError{f.col, f.message};
    }
    if (comment_error && !out.error) out.error = comment_error;
    return out;
}

std::vector<LineError> apply_assignments(const ReadLine& line, Parameters& params) {
    std::vector<LineError> errors;
    for (const Assignment& a : line.assignments) {
        if (a.named) {
            if (a.known) {
                params.named[a.name] = a.value;
                params.named_poisoned.erase(a.name);
            } else {
                params.named_poisoned[a.name] = true;
            }
            continue;
        }
        if (params.writable && !params.writable(a.number)) {
            errors.push_back({a.col, fmt::format("parameter #{} is set by the interpreter and cannot be "
                                                 "written here (use G10 L2 / G92 / G28.1)",
                                                 a.number)});
            continue;
        }
        if (a.known) {
            params.numbered[a.number] = a.value;
            params.numbered_poisoned.erase(a.number);
        } else {
            params.numbered_poisoned[a.number] = true;
        }
    }
    // A line whose reading failed leaves the parameters it would have set
    // unknown, so their later uses report nothing new.
    return errors;
}

std::optional<double> evaluate(std::string_view text, const Parameters& params, std::string* error) {
    std::optional<LineError> ce;
    Compact c = compact(text, ce);
    Reader r(c, params);
    try {
        const double v = r.real_value();
        if (!r.at_end()) r.fail(fmt::format("unexpected {} after the value", show(r.peek())));
        return v;
    } catch (const Fail& f) {
        if (error) *error = f.message;
        return std::nullopt;
    }
}

}  // namespace cpstep::plan::gcode

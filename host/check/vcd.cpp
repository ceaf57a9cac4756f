// SPDX-License-Identifier: MIT
#include "check/vcd.h"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace cpstep::check {

namespace {

struct Token {
  std::string_view text;
  plan::SourceLoc loc;
};

// Whitespace-separated tokens with their line and column (1-based).
class Tokens {
 public:
  explicit Tokens(std::string_view text) : text_(text) {}

  std::optional<Token> next() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) advance();
    if (pos_ >= text_.size()) return std::nullopt;
    const plan::SourceLoc loc{line_, col_};
    const size_t begin = pos_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) advance();
    return Token{text_.substr(begin, pos_ - begin), loc};
  }
  plan::SourceLoc here() const { return {line_, col_}; }

 private:
  void advance() {
    if (text_[pos_++] == '\n') {
      ++line_;
      col_ = 1;
    } else {
      ++col_;
    }
  }
  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1, col_ = 1;
};

// The keywords that open a section or block. Other words may start with '$':
// an identifier code is any printable text ("$", "#a").
bool keyword(std::string_view s) {
  static constexpr std::string_view kKeywords[] = {
      "$comment", "$date",     "$version", "$timescale", "$scope",   "$upscope", "$var",     "$enddefinitions",
      "$dumpvars", "$dumpall", "$dumpon",  "$dumpoff",   "$attrbegin", "$attrend", "$end"};
  for (const std::string_view k : kKeywords)
    if (s == k) return true;
  return false;
}

struct ParseError {
  plan::SourceLoc loc;
  std::string message;
};

std::optional<uint64_t> whole_number(std::string_view s) {
  uint64_t v = 0;
  if (s.empty()) return std::nullopt;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

class Parser {
 public:
  Parser(std::string_view text, std::string_view file) : tokens_(text) { trace_.file = file; }

  VcdTrace run() {
    header();
    body();
    return std::move(trace_);
  }

 private:
  [[noreturn]] static void fail(plan::SourceLoc loc, std::string message) {
    throw ParseError{loc, std::move(message)};
  }

  // The tokens of a section up to its $end (not included).
  std::vector<Token> section(const Token& opener) {
    std::vector<Token> words;
    while (auto t = tokens_.next()) {
      if (t->text == "$end") return words;
      if (keyword(t->text))
        fail(t->loc, fmt::format("{} inside {} (opened at line {}) before its $end", t->text, opener.text,
                                 opener.loc.line));
      words.push_back(*t);
    }
    fail(tokens_.here(), fmt::format("end of file inside {} (opened at line {}): missing $end", opener.text,
                                     opener.loc.line));
  }

  void skip_to_end(const Token& opener) {
    // Free text ($comment, $date, $version) may hold anything but "$end".
    while (auto t = tokens_.next())
      if (t->text == "$end") return;
    fail(tokens_.here(), fmt::format("end of file inside {} (opened at line {}): missing $end", opener.text,
                                     opener.loc.line));
  }

  void header() {
    while (true) {
      const auto t = tokens_.next();
      if (!t) fail(tokens_.here(), "end of file before $enddefinitions");
      const std::string_view k = t->text;
      if (k == "$comment" || k == "$date" || k == "$version" || k == "$attrbegin" || k == "$attrend") {
        skip_to_end(*t);
      } else if (k == "$timescale") {
        timescale(*t);
      } else if (k == "$scope") {
        const auto w = section(*t);
        if (w.size() != 2) fail(t->loc, "$scope needs a type and a name: $scope module NAME $end");
        scopes_.emplace_back(w[1].text);
      } else if (k == "$upscope") {
        if (!section(*t).empty()) fail(t->loc, "$upscope takes no arguments");
        if (scopes_.empty()) fail(t->loc, "$upscope without an open $scope");
        scopes_.pop_back();
      } else if (k == "$var") {
        var(*t);
      } else if (k == "$enddefinitions") {
        if (!section(*t).empty()) fail(t->loc, "$enddefinitions takes no arguments");
        if (!scopes_.empty()) fail(t->loc, fmt::format("$enddefinitions with $scope {} still open", scopes_.back()));
        return;
      } else if (k.starts_with('$')) {
        fail(t->loc, fmt::format("unknown declaration {}", k));
      } else {
        fail(t->loc, fmt::format("'{}' before $enddefinitions: expected a $keyword", k));
      }
    }
  }

  void timescale(const Token& opener) {
    const auto w = section(opener);
    std::string text;
    for (const Token& x : w) text += x.text;
    const auto digits = text.find_first_not_of("0123456789");
    const auto value = parse_duration(text);
    if (!value || digits == 0 || digits == std::string::npos || text[digits] == '.')
      fail(opener.loc, fmt::format("bad $timescale '{}': expected a whole number and s, ms, us, ns, ps or fs",
                                   text));
    trace_.unit_s = *value;
  }

  void var(const Token& opener) {
    const auto w = section(opener);
    if (w.size() != 4 && w.size() != 5)
      fail(opener.loc, "$var needs a type, a width, an identifier code and a name: $var wire 1 ! step_x $end");
    const auto width = whole_number(w[1].text);
    if (!width || *width == 0 || *width > 64)
      fail(w[1].loc, fmt::format("$var width '{}' is not a whole number in 1..64", w[1].text));
    VcdVar v;
    v.width = unsigned(*width);
    v.name = std::string(w[3].text);
    if (w.size() == 5) v.name += w[4].text;
    for (const std::string& s : scopes_) v.path += s + '.';
    v.path += v.name;
    v.loc = opener.loc;
    const auto [it, added] = codes_.try_emplace(std::string(w[2].text), trace_.changes.size(), v.width);
    if (added) {
      trace_.changes.emplace_back();
    } else if (it->second.second != v.width) {
      fail(w[2].loc, fmt::format("identifier code '{}' declared again with width {} (was {})", w[2].text, v.width,
                                 it->second.second));
    }
    v.code = it->second.first;
    trace_.vars.push_back(std::move(v));
  }

  size_t code_of(const Token& t, std::string_view code) {
    const auto it = codes_.find(std::string(code));
    if (code.empty() || it == codes_.end())
      fail(t.loc, fmt::format("unknown identifier code '{}' (not declared by a $var)", code));
    return it->second.first;
  }

  void record(const Token& t, std::string_view code, uint64_t bits, bool known) {
    trace_.changes[code_of(t, code)].push_back({time_, bits, known});
  }

  void vector(const Token& t) {
    const auto code_token = tokens_.next();
    if (!code_token || keyword(code_token->text))
      fail(t.loc, fmt::format("vector value '{}' without an identifier code", t.text));
    const size_t code = code_of(*code_token, code_token->text);
    if (t.text[0] == 'r' || t.text[0] == 'R') {
      double ignored = 0;
      std::istringstream in{std::string(t.text.substr(1))};
      if (!(in >> ignored) || !in.eof()) fail(t.loc, fmt::format("bad real value '{}'", t.text));
      return;  // real variables are not pins
    }
    const std::string_view digits = t.text.substr(1);
    if (digits.empty() || digits.size() > 64)
      fail(t.loc, fmt::format("vector value '{}' must have 1 to 64 bits", t.text));
    // Wider than its variable (leading zeros aside): refused, not read as a value it cannot hold.
    const unsigned width = codes_.find(std::string(code_token->text))->second.second;
    if (digits.size() > width && digits.substr(0, digits.size() - width).find_first_not_of('0') != std::string_view::npos)
      fail(t.loc, fmt::format("vector value '{}' has more bits than its variable's width {}", t.text, width));
    uint64_t bits = 0;
    bool known = true;
    for (const char c : digits) {
      bits <<= 1;
      if (c == '1') {
        bits |= 1;
      } else if (c == 'x' || c == 'X' || c == 'z' || c == 'Z') {
        known = false;
      } else if (c != '0') {
        fail(t.loc, fmt::format("bad bit '{}' in vector value '{}'", c, t.text));
      }
    }
    trace_.changes[code].push_back({time_, bits, known});
  }

  void body() {
    Token block;  // an open $dumpvars/$dumpall/$dumpon/$dumpoff (empty text: none)
    while (const auto t = tokens_.next()) {
      const std::string_view k = t->text;
      const char c = k[0];
      if (c == '#') {
        const auto v = whole_number(k.substr(1));
        if (!v) fail(t->loc, fmt::format("bad time '{}'", k));
        if (*v < time_) fail(t->loc, fmt::format("time #{} goes back (the time before was #{})", *v, time_));
        time_ = *v;
        trace_.end_time = time_;
      } else if (k == "$dumpvars" || k == "$dumpall" || k == "$dumpon" || k == "$dumpoff") {
        if (!block.text.empty())
          fail(t->loc, fmt::format("{} inside {} (opened at line {})", k, block.text, block.loc.line));
        block = *t;
      } else if (k == "$end") {
        if (block.text.empty()) fail(t->loc, "$end without an open $dumpvars, $dumpall, $dumpon or $dumpoff");
        block = {};
      } else if (k == "$comment") {
        skip_to_end(*t);
      } else if (c == '$') {
        fail(t->loc, fmt::format("unexpected {} after $enddefinitions", k));
      } else if (c == '0' || c == '1') {
        record(*t, k.substr(1), uint64_t(c - '0'), true);
      } else if (c == 'x' || c == 'X' || c == 'z' || c == 'Z') {
        record(*t, k.substr(1), 0, false);
      } else if (c == 'b' || c == 'B' || c == 'r' || c == 'R') {
        vector(*t);
      } else {
        fail(t->loc, fmt::format("unexpected '{}': expected #time or a value change", k));
      }
    }
    if (!block.text.empty())
      fail(tokens_.here(), fmt::format("end of file inside {} (opened at line {}): missing $end", block.text,
                                       block.loc.line));
  }

  Tokens tokens_;
  VcdTrace trace_;
  std::vector<std::string> scopes_;
  std::map<std::string, std::pair<size_t, unsigned>> codes_;  // code -> (index, width)
  uint64_t time_ = 0;
};

}  // namespace

std::vector<const VcdVar*> VcdTrace::find(std::string_view name) const {
  std::vector<const VcdVar*> out;
  for (const VcdVar& v : vars)
    if (v.path == name || v.name == name) out.push_back(&v);
  return out;
}

plan::Result<VcdTrace> parse_vcd(std::string_view text, std::string_view file) {
  plan::Result<VcdTrace> r;
  try {
    r.value = Parser(text, file).run();
  } catch (const ParseError& e) {
    r.errors.push_back({std::string(file), e.loc, e.message});
  }
  return r;
}

plan::Result<VcdTrace> read_vcd(const std::filesystem::path& path) {
  return parse_file<VcdTrace>(path, parse_vcd);
}

std::optional<std::string> read_text(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) return std::nullopt;
  return text;
}

std::optional<double> parse_duration(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  const size_t unit_at = text.find_first_not_of("0123456789.");
  if (unit_at == 0 || unit_at == std::string_view::npos) return std::nullopt;
  std::string_view number = text.substr(0, unit_at), unit = text.substr(unit_at);
  while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.front()))) unit.remove_prefix(1);
  static const std::pair<std::string_view, double> kUnits[] = {{"s", 1},      {"ms", 1e-3},  {"us", 1e-6},
                                                               {"ns", 1e-9},  {"ps", 1e-12}, {"fs", 1e-15}};
  double value = 0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (ec != std::errc() || end != number.data() + number.size() || !(value > 0) || !std::isfinite(value))
    return std::nullopt;
  for (const auto& [name, scale] : kUnits)
    if (unit == name) return value * scale;
  return std::nullopt;
}

}  // namespace cpstep::check

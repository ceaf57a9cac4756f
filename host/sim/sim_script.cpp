// SPDX-License-Identifier: MIT
#include "sim/sim_script.h"

#include <array>
#include <optional>
#include <set>

#include "card/frame.h"
#include "card/protocol.h"

namespace cpstep::sim {

ScriptError::ScriptError(const std::string& file, unsigned line_, unsigned column_,
                         const std::string& message)
    : std::runtime_error(file + ":" + std::to_string(line_) + ":" + std::to_string(column_) +
                         ": error: " + message),
      line(line_),
      column(column_) {}

namespace {

struct Token {
  std::string text;
  unsigned col;  // 1-based
};

std::vector<Token> tokenize(const std::string& line) {
  std::vector<Token> out;
  size_t i = 0;
  while (i < line.size()) {
    if (line[i] == '#') break;
    if (line[i] == ' ' || line[i] == '\t' || line[i] == '\r') {
      ++i;
      continue;
    }
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r' && line[i] != '#')
      ++i;
    out.push_back({line.substr(start, i - start), unsigned(start + 1)});
  }
  return out;
}

class Parser {
 public:
  Parser(const std::string& file) : file_(file) {}

  [[noreturn]] void fail(unsigned col, const std::string& msg) const {
    throw ScriptError(file_, line_, col, msg);
  }

  // An unsigned decimal number (or 0x hex) no larger than `max`.
  uint64_t parse_unsigned(const std::string& s, unsigned col, uint64_t max, const std::string& what) const {
    if (s.empty()) fail(col, what + " needs a value");
    size_t i = 0;
    unsigned base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      base = 16;
      i = 2;
    }
    uint64_t v = 0;
    for (; i < s.size(); ++i) {
      const char c = s[i];
      unsigned d;
      if (c >= '0' && c <= '9') d = unsigned(c - '0');
      else if (base == 16 && c >= 'a' && c <= 'f') d = unsigned(c - 'a' + 10);
      else if (base == 16 && c >= 'A' && c <= 'F') d = unsigned(c - 'A' + 10);
      else fail(col + unsigned(i), "'" + s + "' is not a number (" + what + ")");
      if (d > max || v > (max - d) / base) fail(col, what + " " + s + " is out of range (0.." + std::to_string(max) + ")");
      v = v * base + d;
    }
    return v;
  }

  int64_t parse_signed(const std::string& s, unsigned col, int64_t lo, int64_t hi, const std::string& what) const {
    const bool neg = !s.empty() && s[0] == '-';
    const bool plus = !s.empty() && s[0] == '+';
    const std::string digits = (neg || plus) ? s.substr(1) : s;
    const uint64_t mag = parse_unsigned(digits, col + unsigned(neg || plus), uint64_t(hi) + 1, what);
    const int64_t v = neg ? -int64_t(mag) : int64_t(mag);
    if (v < lo || v > hi)
      fail(col, what + " " + s + " is out of range (" + std::to_string(lo) + ".." + std::to_string(hi) + ")");
    return v;
  }

  struct Field {
    std::string key, value;
    unsigned key_col, value_col;
  };
  // key=value tokens; bare words (no '=') get an empty value and value_col 0.
  std::vector<Field> fields(const std::vector<Token>& toks, size_t from) const {
    std::vector<Field> out;
    std::set<std::string> seen;
    for (size_t i = from; i < toks.size(); ++i) {
      const Token& t = toks[i];
      const size_t eq = t.text.find('=');
      Field f;
      if (eq == std::string::npos) {
        f = {t.text, "", t.col, 0};
      } else {
        f = {t.text.substr(0, eq), t.text.substr(eq + 1), t.col, t.col + unsigned(eq) + 1};
        if (f.key.empty()) fail(t.col, "missing field name before '='");
        if (f.value.empty()) fail(f.value_col, "field '" + f.key + "' needs a value after '='");
      }
      if (!seen.insert(f.key).second) fail(t.col, "field '" + f.key + "' given twice");
      out.push_back(f);
    }
    return out;
  }

  void need_value(const Field& f) const {
    if (f.value_col == 0) fail(f.key_col, "field '" + f.key + "' needs '=value'");
  }

  // Comma-separated list of exactly kSimAxes items; returns each item and its column.
  std::vector<std::pair<std::string, unsigned>> axis_list(const Field& f) const {
    need_value(f);
    std::vector<std::pair<std::string, unsigned>> out;
    size_t start = 0;
    for (;;) {
      const size_t comma = f.value.find(',', start);
      const std::string item = f.value.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      const unsigned col = f.value_col + unsigned(start);
      if (item.empty()) fail(col, "empty item in " + f.key + "=");
      out.emplace_back(item, col);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    if (out.size() != kSimAxes)
      fail(f.value_col, f.key + " needs " + std::to_string(kSimAxes) + " comma-separated values (x,y,z,a), got " +
                            std::to_string(out.size()));
    return out;
  }

  void flush_segment() {
    if (!segment_) return;
    ScriptStep st{segment_line_, SendWords{}};
    card::encode_segment(*segment_, std::get<SendWords>(st.action).words);
    steps_.push_back(std::move(st));
    segment_.reset();
  }

  void send(std::vector<uint32_t> words) { steps_.push_back({line_, SendWords{std::move(words)}}); }

  void no_arguments(const std::vector<Token>& toks) const {
    if (toks.size() > 1) fail(toks[1].col, "'" + toks[0].text + "' takes no arguments");
  }

  void parse_config(const std::vector<Token>& toks) {
    if (toks.size() < 2) fail(toks[0].col + 6, "config needs an axis (x, y, z, a or all)");
    std::vector<unsigned> axes;
    if (toks[1].text == "all") {
      for (unsigned a = 0; a < kSimAxes; ++a) axes.push_back(a);
    } else {
      for (unsigned a = 0; a < kSimAxes; ++a)
        if (toks[1].text == kSimAxisNames[a]) axes.push_back(a);
      if (axes.empty()) fail(toks[1].col, "unknown axis '" + toks[1].text + "' (x, y, z, a or all)");
    }
    const auto fs = fields(toks, 2);
    if (fs.empty()) fail(toks[1].col + unsigned(toks[1].text.size()) + 1,
                         "config needs at least one field (high, low, setup, hold, step_pol, dir_pol, limits, "
                         "filter, probe_pol, watchdog)");
    std::vector<uint32_t> words;
    std::optional<bool> step_pol, dir_pol;
    for (const Field& f : fs) {
      need_value(f);
      card::ConfigField cf;
      if (f.key == "high") cf = card::ConfigField::step_high;
      else if (f.key == "low") cf = card::ConfigField::step_low;
      else if (f.key == "setup") cf = card::ConfigField::dir_setup;
      else if (f.key == "hold") cf = card::ConfigField::dir_hold;
      else if (f.key == "limits") cf = card::ConfigField::limits;  // docs/CORE.md "Inputs"
      else if (f.key == "filter") cf = card::ConfigField::input_filter;
      else if (f.key == "probe_pol") cf = card::ConfigField::probe;
      else if (f.key == "watchdog") cf = card::ConfigField::watchdog;  // docs/CORE.md "Watchdog"
      else if (f.key == "step_pol" || f.key == "dir_pol") {
        const bool b = parse_unsigned(f.value, f.value_col, 1, f.key) != 0;
        (f.key == "step_pol" ? step_pol : dir_pol) = b;
        continue;
      } else {
        fail(f.key_col, "unknown config field '" + f.key +
                            "' (high, low, setup, hold, step_pol, dir_pol, limits, filter, probe_pol, watchdog)");
      }
      const uint32_t v = uint32_t(parse_unsigned(f.value, f.value_col, 0xFFFF, f.key));
      for (unsigned a : axes) card::encode_config(a, cf, v, words);
    }
    if (step_pol || dir_pol) {
      // Both polarities share one CONFIG word: keep the one not given.
      for (unsigned a : axes) {
        if (step_pol) polarity_[a][0] = *step_pol;
        if (dir_pol) polarity_[a][1] = *dir_pol;
        card::encode_config(a, card::ConfigField::polarity,
                            uint32_t(polarity_[a][0]) | uint32_t(polarity_[a][1]) << 1, words);
      }
    }
    send(std::move(words));
  }

  void parse_segment(const std::vector<Token>& toks) {
    card::WireSegment s;
    s.dir_positive.assign(kSimAxes, true);
    bool have_u = false, have_v = false;
    for (const Field& f : fields(toks, 1)) {
      if (f.key == "end") {
        if (f.value_col != 0) fail(f.key_col, "'end' takes no value");
        s.end = true;
      } else if (f.key == "U" || f.key == "u") {
        need_value(f);
        s.u = uint32_t(parse_unsigned(f.value, f.value_col, 0xFFFFFF, "U"));
        have_u = true;
      } else if (f.key == "k") {
        need_value(f);
        s.k = unsigned(parse_unsigned(f.value, f.value_col, 15, "k"));
      } else if (f.key == "v") {
        for (const auto& [item, col] : axis_list(f))
          s.v.push_back(uint32_t(parse_unsigned(item, col, 0xFFFFFF, "v")));
        have_v = true;
      } else if (f.key == "dir") {
        unsigned a = 0;
        for (const auto& [item, col] : axis_list(f)) {
          if (item != "+" && item != "-") fail(col, "dir items are + or -, not '" + item + "'");
          s.dir_positive[a++] = item == "+";
        }
      } else {
        fail(f.key_col, "unknown segment field '" + f.key + "' (U, k, v, dir, end)");
      }
    }
    const unsigned after = toks.back().col + unsigned(toks.back().text.size());
    if (!have_u) fail(after, "segment needs U=");
    if (!have_v) fail(after, "segment needs v=");
    segment_ = std::move(s);
    segment_line_ = line_;
  }

  void parse_chunk(const std::vector<Token>& toks) {
    if (!segment_) fail(toks[0].col, "chunk without a segment (chunks follow their segment line)");
    if (segment_->chunks.size() == 0xFFFF) fail(toks[0].col, "a segment holds at most 65535 chunks");
    card::WireChunk c;
    bool have_interval = false, have_count = false;
    for (const Field& f : fields(toks, 1)) {
      need_value(f);
      if (f.key == "interval") {
        c.interval = uint32_t(parse_unsigned(f.value, f.value_col, 0xFFFFFFFF, "interval"));
        have_interval = true;
      } else if (f.key == "count") {
        c.count = uint16_t(parse_unsigned(f.value, f.value_col, 0xFFFF, "count"));
        have_count = true;
      } else if (f.key == "add") {
        c.add = int16_t(parse_signed(f.value, f.value_col, -32768, 32767, "add"));
      } else if (f.key == "add2") {
        c.add2 = int16_t(parse_signed(f.value, f.value_col, -32768, 32767, "add2"));
      } else {
        fail(f.key_col, "unknown chunk field '" + f.key + "' (interval, count, add, add2)");
      }
    }
    const unsigned after = toks.back().col + unsigned(toks.back().text.size());
    if (!have_interval) fail(after, "chunk needs interval=");
    if (!have_count) fail(after, "chunk needs count=");
    segment_->chunks.push_back(c);
  }

  void parse_line(const std::string& text) {
    const auto toks = tokenize(text);
    if (toks.empty()) return;
    const std::string& cmd = toks[0].text;
    if (cmd == "chunk") return parse_chunk(toks);
    flush_segment();
    if (cmd == "segment") return parse_segment(toks);
    if (cmd == "config") return parse_config(toks);
    if (cmd == "start" || cmd == "abort" || cmd == "clear") {
      no_arguments(toks);
      std::vector<uint32_t> w;
      card::encode_control(cmd == "start", cmd == "abort", cmd == "clear", w);
      return send(std::move(w));
    }
    if (cmd == "run") {
      no_arguments(toks);
      steps_.push_back({line_, RunToStop{}});
      return;
    }
    if (cmd == "wait") {
      if (toks.size() != 2) fail(toks.size() < 2 ? toks[0].col + 4 : toks[2].col, "wait takes one number of cycles");
      steps_.push_back({line_, Wait{parse_unsigned(toks[1].text, toks[1].col, UINT64_MAX, "cycles")}});
      return;
    }
    if (cmd == "urgent") {
      // urgent start|stop|flush|ack ...: one URGENT frame with those bits.
      if (toks.size() < 2) fail(toks[0].col + 6, "urgent takes start, stop, flush or ack");
      uint32_t word = 0;
      for (size_t t = 1; t < toks.size(); ++t) {
        const std::string& b = toks[t].text;
        if (b == "start") word |= card::urgent::start;
        else if (b == "stop") word |= card::urgent::stop;
        else if (b == "flush") word |= card::urgent::flush;
        else if (b == "ack") word |= card::urgent::ack;
        else fail(toks[t].col, "unknown urgent bit '" + b + "' (start, stop, flush, ack)");
      }
      steps_.push_back({line_, Urgent{word}});
      return;
    }
    if (cmd == "input") {
      // input x min on | input y max off | input probe on: a pin's raw level, kept.
      const auto level = [&](size_t t) {
        if (toks.size() != t + 1 || (toks[t].text != "on" && toks[t].text != "off"))
          fail(toks.size() <= t ? toks.back().col + unsigned(toks.back().text.size()) + 1 : toks[t].col,
               "input takes <axis> min|max on|off, or probe on|off");
        return toks[t].text == "on";
      };
      if (toks.size() >= 2 && toks[1].text == "probe") {
        inputs_.probe = level(2);
      } else {
        if (toks.size() < 3) fail(toks[0].col + 5, "input takes <axis> min|max on|off, or probe on|off");
        unsigned axis = kSimAxes;
        for (unsigned a = 0; a < kSimAxes; ++a)
          if (toks[1].text == kSimAxisNames[a]) axis = a;
        if (axis == kSimAxes) fail(toks[1].col, "unknown axis '" + toks[1].text + "' (x, y, z, a or probe)");
        if (toks[2].text != "min" && toks[2].text != "max") fail(toks[2].col, "input takes min or max");
        uint32_t& mask = toks[2].text == "min" ? inputs_.lim_min : inputs_.lim_max;
        mask = level(3) ? mask | 1u << axis : mask & ~(1u << axis);
      }
      steps_.push_back({line_, inputs_});
      return;
    }
    if (cmd == "estop") {
      if (toks.size() != 2 || (toks[1].text != "on" && toks[1].text != "off"))
        fail(toks.size() < 2 ? toks[0].col + 5 : toks[1].col, "estop takes 'on' or 'off'");
      steps_.push_back({line_, Estop{toks[1].text == "on"}});
      return;
    }
    fail(toks[0].col, "unknown command '" + cmd +
                          "' (config, segment, chunk, start, wait, run, estop, input, abort, clear, urgent)");
  }

  std::vector<ScriptStep> parse(std::istream& in) {
    std::string text;
    while (std::getline(in, text)) {
      ++line_;
      parse_line(text);
    }
    flush_segment();
    return std::move(steps_);
  }

 private:
  std::string file_;
  unsigned line_ = 0;
  std::vector<ScriptStep> steps_;
  std::optional<card::WireSegment> segment_;
  unsigned segment_line_ = 0;
  // Polarity per axis as the script last set it (the card's reset: both 1).
  std::array<std::array<bool, 2>, kSimAxes> polarity_{{{true, true}, {true, true}, {true, true}, {true, true}}};
  Inputs inputs_;  // the pins the script has set (input)
};

}  // namespace

std::vector<ScriptStep> parse_sim_script(std::istream& in, const std::string& file) {
  return Parser(file).parse(in);
}

}  // namespace cpstep::sim

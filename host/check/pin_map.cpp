// SPDX-License-Identifier: MIT
#include "check/pin_map.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "check/vcd.h"

namespace cpstep::check {

namespace {

plan::SourceLoc where(const toml::source_region& s) {
  return {int(s.begin.line), int(s.begin.column)};
}

// Collects every problem of one map file; each names its field.
struct MapErrors {
  std::string file;
  std::vector<plan::Diagnostic> list;
  void add(const toml::node& at, std::string_view field, std::string_view what) {
    list.push_back({file, where(at.source()), fmt::format("{}: {}", field, what)});
  }
};

// Visits the keys of `t`; a key not in `known` is an error (a typo must not
// fall back to a default silently).
void each_key(const toml::table& t, std::string_view prefix, std::initializer_list<std::string_view> known,
              MapErrors& errors, const std::function<void(std::string_view, const toml::node&)>& visit) {
  for (const auto& [key, node] : t) {
    const std::string field = prefix.empty() ? std::string(key.str()) : fmt::format("{}.{}", prefix, key.str());
    bool ok = false;
    for (const std::string_view k : known) ok = ok || k == key.str();
    if (!ok) {
      errors.list.push_back({errors.file, where(key.source()),
                             fmt::format("{}: unknown key (known: {})", field, fmt::join(known, ", "))});
      continue;
    }
    visit(field, node);
  }
}

std::optional<double> positive_number(const toml::node& n, std::string_view field, MapErrors& errors) {
  const auto v = n.value<double>();
  if (!n.is_number() || !v || !std::isfinite(*v) || *v <= 0) {
    errors.add(n, field, "must be a number > 0");
    return std::nullopt;
  }
  return v;
}

void read_axis(const toml::table& t, std::string_view prefix, AxisPins& pins, MapErrors& errors) {
  each_key(t, prefix, {"step", "dir", "step_active_high", "dir_positive_high"}, errors,
           [&](std::string_view field, const toml::node& n) {
             const bool is_step = field.ends_with(".step"), is_dir = field.ends_with(".dir");
             if (is_step || is_dir) {
               const auto s = n.value<std::string>();
               if (!n.is_string() || !s || s->empty()) return errors.add(n, field, "must be a signal name (a string)");
               (is_step ? pins.step : pins.dir) = *s;
               (is_step ? pins.step_loc : pins.dir_loc) = where(n.source());
               return;
             }
             if (!n.is_boolean()) return errors.add(n, field, "must be true or false");
             (field.ends_with(".step_active_high") ? pins.step_active_high : pins.dir_positive_high) =
                 *n.value<bool>();
           });
}

}  // namespace

PinMap default_pin_map() {
  PinMap m;
  for (int a = 0; a < plan::kAxes; ++a) {
    m.axes[a].step = fmt::format("step_{}", plan::kAxisLetters[a]);
    m.axes[a].dir = fmt::format("dir_{}", plan::kAxisLetters[a]);
  }
  return m;
}

plan::Result<PinMap> parse_pin_map(std::string_view text, std::string_view file) {
  plan::Result<PinMap> r;
  MapErrors errors{std::string(file), {}};
  toml::table root;
  try {
    root = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    r.errors.push_back({std::string(file), where(e.source()), std::string(e.description())});
    return r;
  }
  PinMap m = default_pin_map();
  m.file = file;
  const toml::node* clock = nullptr;
  const toml::node* timescale = nullptr;
  each_key(root, "", {"timescale", "clock_hz", "sample_hz", "axes"}, errors,
           [&](std::string_view field, const toml::node& n) {
             if (field == "timescale") {
               timescale = &n;
               const auto s = n.value<std::string>();
               const auto d = s ? parse_duration(*s) : std::nullopt;
               if (!n.is_string() || !d)
                 return errors.add(n, field, "must be a duration such as \"1 ns\" or \"20.833ns\" (s, ms, us, ns, ps, fs)");
               m.unit_s = d;
             } else if (field == "clock_hz") {
               clock = &n;
               if (const auto hz = positive_number(n, field, errors)) m.unit_s = 1 / *hz;
             } else if (field == "sample_hz") {
               if (const auto hz = positive_number(n, field, errors)) m.sample_s = 1 / *hz;
             } else if (const toml::table* axes = n.as_table()) {
               each_key(*axes, field, {"x", "y", "z", "a"}, errors, [&](std::string_view axis, const toml::node& t) {
                 if (!t.is_table()) return errors.add(t, axis, "must be a table ([axes.x])");
                 const char letter = axis.back();
                 for (int a = 0; a < plan::kAxes; ++a)
                   if (plan::kAxisLetters[a] == letter) read_axis(*t.as_table(), axis, m.axes[a], errors);
               });
             } else {
               errors.add(n, field, "must be a table of axes ([axes.x], [axes.y], ...)");
             }
           });
  if (clock && timescale) errors.add(*clock, "clock_hz", "give clock_hz or timescale, not both");
  // In the file's order (a table iterates by key).
  std::stable_sort(errors.list.begin(), errors.list.end(), [](const plan::Diagnostic& x, const plan::Diagnostic& y) {
    return std::pair(x.loc.line, x.loc.col) < std::pair(y.loc.line, y.loc.col);
  });
  r.errors = std::move(errors.list);
  if (r.errors.empty()) r.value = std::move(m);
  return r;
}

plan::Result<PinMap> load_pin_map(const std::filesystem::path& path) {
  return parse_file<PinMap>(path, parse_pin_map);
}

}  // namespace cpstep::check

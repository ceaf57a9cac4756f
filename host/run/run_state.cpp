// SPDX-License-Identifier: MIT
#include "run/run_state.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace cpstep::run {

namespace {

using nlohmann::json;

constexpr const char* kFormat = "cpstep run state";
constexpr RunEnd kEnds[] = {RunEnd::finished, RunEnd::stopped, RunEnd::fault};

nlohmann::ordered_json axis_object(const RunState& s, const auto& values) {
  nlohmann::ordered_json o = nlohmann::ordered_json::object();
  for (int a = 0; a < plan::kAxes; ++a)
    if (s.axes[a]) o[std::string(1, plan::kAxisLetters[a])] = values[a];
  return o;
}

// Reads the fields of one JSON object, collecting an error per bad field.
class Fields {
 public:
  Fields(const json& object, const std::string& file, std::vector<plan::Diagnostic>& errors)
      : object_(object), file_(file), errors_(errors) {}

  const json* find(const std::string& name) {
    const auto it = object_.find(name);
    if (it == object_.end()) {
      error(name, "missing");
      return nullptr;
    }
    return &*it;
  }
  void error(const std::string& field, const std::string& why) {
    errors_.push_back({file_, {}, fmt::format("{}: {}", field, why)});
  }
  std::string text(const std::string& name) {
    const json* v = find(name);
    if (v && v->is_string()) return v->get<std::string>();
    if (v) error(name, "expected a string");
    return {};
  }
  uint64_t count(const std::string& name) {
    const json* v = find(name);
    if (v && v->is_number_unsigned()) return v->get<uint64_t>();
    if (v) error(name, "expected a whole number, 0 or more");
    return 0;
  }
  // An object of axis letters; `take` reads one value (false: wrong type).
  template <class T, class Take>
  plan::PerAxis<T> per_axis(const std::string& name, plan::PerAxis<bool>* keys, const char* expected, Take take) {
    plan::PerAxis<T> out{};
    const json* v = find(name);
    if (!v) return out;
    if (!v->is_object()) {
      error(name, "expected an object of axes (x, y, z, a)");
      return out;
    }
    for (const auto& [key, value] : v->items()) {
      int a = 0;
      while (a < plan::kAxes && key != std::string(1, plan::kAxisLetters[a])) ++a;
      if (a == plan::kAxes) {
        error(name + "." + key, "no such axis (x, y, z, a)");
        continue;
      }
      if (!take(value, out[a])) error(name + "." + key, expected);
      if (keys) (*keys)[a] = true;
    }
    return out;
  }

 private:
  const json& object_;
  const std::string& file_;
  std::vector<plan::Diagnostic>& errors_;
};

}  // namespace

const char* run_end_name(RunEnd e) {
  constexpr const char* kNames[] = {"finished", "stopped", "fault"};  // in RunEnd's order
  return kNames[size_t(e)];
}

plan::PerAxis<double> RunState::position_mm() const {
  plan::PerAxis<double> mm{};
  for (int a = 0; a < plan::kAxes; ++a)
    if (axes[a] && steps_per_mm[a] > 0) mm[a] = double(position[a]) / steps_per_mm[a];
  return mm;
}

std::string fnv1a64_hex(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ULL;  // the offset basis
  for (const char c : bytes) {
    h ^= uint8_t(c);
    h *= 0x100000001b3ULL;  // the FNV prime
  }
  return fmt::format("{:016x}", h);
}

std::optional<std::string> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) return std::nullopt;
  return s.str();
}

std::string state_text(const RunState& s) {
  const nlohmann::ordered_json j = {
      {"format", kFormat},
      {"version", RunState::kVersion},
      {"job", s.job},
      {"job_fnv1a64", s.job_fnv1a64},
      {"machine", s.machine},
      {"steps_per_mm", axis_object(s, s.steps_per_mm)},
      {"contours", s.contours},
      {"contours_completed", s.contours_completed},
      {"last_m5_line", s.last_m5_line},
      {"job_start_steps", axis_object(s, s.job_start)},
      {"position_steps", axis_object(s, s.position)},
      {"position_mm", axis_object(s, s.position_mm())},
      {"ended", run_end_name(s.ended)},
  };
  return j.dump(2) + "\n";
}

plan::Result<RunState> parse_state(std::string_view text, const std::string& file) {
  plan::Result<RunState> r;
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    r.errors.push_back({file, {}, fmt::format("not a JSON state file: {}", e.what())});
    return r;
  }
  if (!j.is_object()) {
    r.errors.push_back({file, {}, "not a state file: expected a JSON object"});
    return r;
  }
  Fields f(j, file, r.errors);
  if (f.text("format") != kFormat && r.errors.empty())
    f.error("format", fmt::format("expected \"{}\" (not a state written by cpstep run --state)", kFormat));
  if (const json* v = f.find("version"); v && (!v->is_number_integer() || v->get<int64_t>() != RunState::kVersion))
    f.error("version", fmt::format("{} is not a version this cpstep reads ({})", v->dump(), RunState::kVersion));
  if (!r.errors.empty()) return r;  // another format: its other fields mean nothing here

  RunState s;
  s.job = f.text("job");
  s.job_fnv1a64 = f.text("job_fnv1a64");
  if (!s.job_fnv1a64.empty() && (s.job_fnv1a64.size() != 16 ||
                                 s.job_fnv1a64.find_first_not_of("0123456789abcdef") != std::string::npos))
    f.error("job_fnv1a64", "expected 16 lowercase hex digits");
  s.machine = f.text("machine");
  const auto number = [](const json& v, double& out) {
    if (!v.is_number()) return false;
    out = v.get<double>();
    return true;
  };
  const auto integer = [](const json& v, int64_t& out) {
    if (!v.is_number_integer()) return false;
    out = v.get<int64_t>();
    return true;
  };
  s.steps_per_mm = f.per_axis<double>("steps_per_mm", &s.axes, "expected a number above 0",
                                      [&](const json& v, double& out) { return number(v, out) && out > 0; });
  s.contours = f.count("contours");
  s.contours_completed = f.count("contours_completed");
  if (s.contours_completed > s.contours)
    f.error("contours_completed", fmt::format("{} is more than the job's {} contours", s.contours_completed,
                                              s.contours));
  const uint64_t m5 = f.count("last_m5_line");
  s.last_m5_line = int(std::min<uint64_t>(m5, INT32_MAX));
  plan::PerAxis<bool> position_axes{};
  s.job_start = f.per_axis<int64_t>("job_start_steps", nullptr, "expected a whole number of steps", integer);
  s.position = f.per_axis<int64_t>("position_steps", &position_axes, "expected a whole number of steps", integer);
  f.per_axis<double>("position_mm", nullptr, "expected a number", number);
  if (r.errors.empty() && position_axes != s.axes)
    f.error("position_steps", "its axes are not those of steps_per_mm");
  const std::string ended = f.text("ended");
  bool known = false;
  for (const RunEnd e : kEnds)
    if (ended == run_end_name(e)) s.ended = e, known = true;
  if (!known && !ended.empty()) f.error("ended", fmt::format("\"{}\": expected finished, stopped or fault", ended));
  if (r.errors.empty()) r.value = std::move(s);
  return r;
}

plan::Result<RunState> read_state(const std::filesystem::path& path) {
  const auto bytes = read_bytes(path);
  if (bytes) return parse_state(*bytes, path.string());
  plan::Result<RunState> r;
  r.errors.push_back({path.string(), {}, fmt::format("cannot read the state file: {}", std::strerror(errno))});
  return r;
}

std::string write_state(const std::filesystem::path& path, const RunState& state) {
  const std::string text = state_text(state);
  std::filesystem::path tmp = path;
  tmp += fmt::format(".tmp{}", ::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno));
  bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0 &&
            ::fsync(::fileno(f)) == 0;
  int err = ok ? 0 : errno;
  if (std::fclose(f) != 0 && ok) ok = false, err = errno;
  std::error_code ec;
  if (ok) std::filesystem::rename(tmp, path, ec);
  if (ok && !ec) return "";
  std::filesystem::remove(tmp);
  return fmt::format("cannot write {}: {}", path.string(), ec ? ec.message() : std::strerror(err));
}

}  // namespace cpstep::run

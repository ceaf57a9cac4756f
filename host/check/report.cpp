// SPDX-License-Identifier: MIT
// The verdict of check_trace as JSON and as the summary `cpstep check` prints.
#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "check/check.h"

namespace cpstep::check {

namespace {

using Json = nlohmann::ordered_json;

Json or_null(double v) { return v < 0 ? Json(nullptr) : Json(v); }

// A duration in the largest unit that keeps it >= 1: "1 ps", "41.6667 ns".
std::string duration_text(double s) {
  static const std::pair<const char*, double> kUnits[] = {{"s", 1},     {"ms", 1e-3},  {"us", 1e-6},
                                                          {"ns", 1e-9}, {"ps", 1e-12}, {"fs", 1e-15}};
  for (const auto& [unit, scale] : kUnits)
    if (s >= scale * (1 - 1e-9)) return fmt::format("{:g} {}", s / scale, unit);
  return fmt::format("{:g} s", s);
}

// The worst occurrence of a finding with its unit, for the summary; "" when
// the kind has no measure (strings, directions, endpoints).
std::string worst_text(const Finding& f) {
  switch (f.kind) {
    case FindingKind::deviation: return fmt::format("{:.3f} steps", f.actual);
    case FindingKind::timing: return fmt::format("{:+.1f} cycles", f.actual);
    case FindingKind::step_high:
    case FindingKind::step_low:
    case FindingKind::dir_setup:
    case FindingKind::dir_hold: return fmt::format("{:.0f} ns", f.actual);
    default: return "";
  }
}

std::map<std::string, uint64_t> counts(const Verdict& v) {
  std::map<std::string, uint64_t> n;
  for (const Finding& f : v.findings) ++n[finding_name(f.kind)];
  return n;
}

std::string ns_text(double measured, double required) {
  return measured < 0 ? fmt::format("none (>= {:.0f})", required) : fmt::format("{:.0f} (>= {:.0f})", measured, required);
}

}  // namespace

nlohmann::ordered_json verdict_json(const Verdict& v) {
  using json = Json;
  json j = {{"conforms", v.conforms()},
            {"trace", v.trace},
            {"job", v.job},
            {"machine", v.machine},
            {"map", v.map.empty() ? json(nullptr) : json(v.map)},
            {"clock_hz", v.clock_hz},
            {"trace_unit_s", v.unit_s},
            {"resolution_cycles", v.resolution_cycles},
            {"skew_window_cycles", v.skew_cycles},
            {"time_tolerance_cycles", v.time_tol_cycles},
            {"segments", v.segments},
            {"planned_moves", v.planned_moves},
            {"move_events", v.move_events},
            {"segments_on_endpoint", v.segments_on_endpoint},
            {"segments_bit_exact", v.segments_bit_exact}};
  if (v.torch_checked)
    j["torch"] = {{"planned_switches", v.torch_planned},
                  {"edges", v.torch_edges},
                  {"max_delay_cycles", v.torch_max_delay_cycles}};
  j["timing"] = {{"start_offset_cycles", v.time_offset_cycles}, {"max_early_cycles", v.max_early_cycles},
                 {"max_early_move", v.max_early_move},          {"max_late_cycles", v.max_late_cycles},
                 {"max_late_move", v.max_late_move},            {"moves_off_time", v.moves_off_time}};
  json axes = json::object();
  for (int a = 0; a < plan::kAxes; ++a) {
    const AxisSummary& s = v.axes[a];
    if (!s.present) continue;
    axes[std::string(1, plan::kAxisLetters[a])] = {
        {"step", s.step_name},
        {"dir", s.dir_name},
        {"step_active_high", s.step_active_high},
        {"dir_positive_high", s.dir_positive_high},
        {"pulses", s.pulses},
        {"final_position", s.final_position},
        {"planned_final", s.planned_final},
        {"max_deviation_steps", s.max_deviation},
        {"deviation_limit_steps", s.deviation_limit},
        {"min_step_high_ns", or_null(s.min_high_ns)},
        {"min_step_low_ns", or_null(s.min_low_ns)},
        {"min_dir_setup_ns", or_null(s.min_setup_ns)},
        {"min_dir_hold_ns", or_null(s.min_hold_ns)},
        {"required_ns", s.driver ? json{{"step_high", s.required.step_high},
                                        {"step_low", s.required.step_low},
                                        {"dir_setup", s.required.dir_setup},
                                        {"dir_hold", s.required.dir_hold}}
                                  : json(nullptr)}};
  }
  j["axes"] = axes;
  j["counts"] = counts(v);
  json findings = json::array();
  for (const Finding& f : v.findings) {
    json x;
    x["kind"] = finding_name(f.kind);
    x["segment"] = f.segment ? json(f.segment) : json(nullptr);
    x["line"] = f.line ? json(f.line) : json(nullptr);
    x["axis"] = f.axis >= 0 ? json(std::string(1, plan::kAxisLetters[size_t(f.axis)])) : json(nullptr);
    x["move"] = f.move ? json(f.move) : json(nullptr);
    x["segment_move"] = f.segment_move ? json(f.segment_move) : json(nullptr);
    x["cycle"] = or_null(f.cycle);
    x["time_s"] = f.cycle < 0 ? json(nullptr) : json(f.cycle / v.clock_hz);
    x["count"] = f.count;
    x["expected"] = f.expected;
    x["actual"] = f.actual;
    x["message"] = f.message;
    findings.push_back(std::move(x));
  }
  j["findings"] = std::move(findings);
  j["warnings"] = v.warnings;
  return j;
}

std::string verdict_summary(const Verdict& v, size_t listed) {
  std::string out;
  auto line = [&out](std::string_view head, const std::string& text) { out += fmt::format("{:<10} {}\n", head, text); };
  line("trace", fmt::format("{} (time unit {}, resolution {})", v.trace, duration_text(v.unit_s),
                            duration_text(v.resolution_cycles / v.clock_hz)));
  line("job", fmt::format("{} on {}: {} card segments, {} moves", v.job, v.machine, v.segments, v.planned_moves));
  std::string pins, dev;
  double limit = 0;
  for (int a = 0; a < plan::kAxes; ++a) {
    const AxisSummary& s = v.axes[a];
    if (!s.present) continue;
    const char l = plan::kAxisLetters[a];
    pins += fmt::format("{}{} {}/{}", pins.empty() ? "" : ", ", l, s.step_name, s.dir_name);
    dev += fmt::format("{}{} {:.3f}", dev.empty() ? "" : ", ", l, s.max_deviation);
    limit = std::max(limit, s.deviation_limit);
  }
  line("pins", pins);
  line("events", fmt::format("{} move events, {} planned (skew window {:g} cycles)", v.move_events, v.planned_moves,
                             v.skew_cycles));
  line("endpoints", fmt::format("{} of {} segments end where the plan does", v.segments_on_endpoint, v.segments));
  line("path", fmt::format("max deviation from the planned lines, steps: {} (limit {:.3f})", dev, limit));
  line("strings", fmt::format("{} of {} segments bit for bit", v.segments_bit_exact, v.segments));
  line("timing", fmt::format("at most {:.1f} cycles early, {:.1f} late against the plan (tolerance {:.4g}); {} moves "
                             "off",
                             v.max_early_cycles, v.max_late_cycles, v.time_tol_cycles + v.resolution_cycles,
                             v.moves_off_time));
  for (int a = 0; a < plan::kAxes; ++a) {
    const AxisSummary& s = v.axes[a];
    if (!s.present || !s.driver) continue;
    line(fmt::format("pulses {}", plan::kAxisLetters[a]),
         fmt::format("{} steps, ns: high {}, low {}, DIR setup {}, hold {}", s.pulses,
                     ns_text(s.min_high_ns, s.required.step_high), ns_text(s.min_low_ns, s.required.step_low),
                     ns_text(s.min_setup_ns, s.required.dir_setup), ns_text(s.min_hold_ns, s.required.dir_hold)));
  }
  if (v.conforms()) {
    line("verdict", "conforms");
    return out;
  }
  std::string by_kind;
  for (const auto& [kind, n] : counts(v)) by_kind += fmt::format("{}{} {}", by_kind.empty() ? "" : ", ", kind, n);
  line("verdict", fmt::format("does not conform: {} findings ({})", v.findings.size(), by_kind));
  for (size_t i = 0; i < v.findings.size() && i < listed; ++i) {
    const Finding& f = v.findings[i];
    std::string more;
    if (f.count > 1) {
      more = fmt::format(" ({} times in this segment", f.count);
      if (const std::string worst = worst_text(f); !worst.empty()) more += ", worst " + worst;
      more += ")";
    }
    out += fmt::format("  {:<11} {}{}\n", finding_name(f.kind), f.message, more);
  }
  if (v.findings.size() > listed) out += fmt::format("  ... {} more in the JSON verdict\n", v.findings.size() - listed);
  return out;
}

}  // namespace cpstep::check

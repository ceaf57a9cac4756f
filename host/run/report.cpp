#include "run/report.h"

#include <string>

namespace cpstep::run {

nlohmann::json make_report(const CardJob& job, const CardRun& run, const RunMeasure& m) {
  using nlohmann::json;
  const plan::PlanStats& st = job.planned.stats;
  json r;
  r["job"] = job.job_file;
  r["machine"] = job.machine.file;
  r["transport"] = "sim";
  r["clock_hz"] = job.clock_hz();
  r["ok"] = run.ok();
  r["step_segments"] = st.step_segments;
  r["planned_card_segments"] = st.card_segments;
  r["segments"] = job.wire.segments.size();
  r["chunks"] = job.wire_chunks();
  r["moves"] = job.moves();
  r["moves_per_chunk"] = job.wire_chunks() ? double(job.moves()) / double(job.wire_chunks()) : 0.0;
  r["command_words"] = job.words.size();
  r["planned_time_s"] = st.duration_s;
  r["job_time_s"] = m.job_time_s;
  r["job_time_cycles"] = m.job_time_cycles;
  r["run_cycles"] = run.cycles;
  r["start_cycle"] = run.start_cycle;
  r["move_events"] = m.moves;
  r["moves_done"] = run.moves_done;
  r["segments_done"] = run.segments_done;
  r["checked_segments"] = run.checked_segments;
  r["position_mismatches"] = run.position_mismatches;
  r["max_timing_error_cycles"] = m.max_timing_error_cycles;
  r["max_timing_error_s"] = m.max_timing_error_cycles / job.clock_hz();
  r["max_timing_error_move"] = m.max_timing_error_move;
  r["chunk_tolerance_cycles"] = job.machine.chunk_tolerance_cycles();
  r["max_chunk_error_cycles"] = m.max_chunk_error_cycles;
  r["moves_off_chunk_time"] = m.moves_off_chunk_time;
  r["stretches"] = run.stretch_count;
  r["stretched"] = run.status.stretched;
  json faults = json::array();
  for (const Fault& f : run.faults) faults.push_back({{"code", f.code}, {"name", f.name}, {"message", f.message}});
  r["faults"] = faults;
  json warnings = json::array();
  for (const plan::Diagnostic& w : job.warnings) warnings.push_back(w.str());
  r["warnings"] = warnings;

  json axes = json::object();
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job.machine.axes[a];
    if (!ax.present) continue;
    const AxisMeasure& am = m.axes[a];
    json j;
    j["steps_per_mm"] = ax.steps_per_mm;
    j["final_steps"] = run.position[a];
    j["final_mm"] = double(run.position[a]) / ax.steps_per_mm;
    j["planned_final_steps"] = job.checkpoints.empty() ? 0 : job.checkpoints.back().position[a];
    j["pulses"] = am.pulses;
    j["step_high_cycles"] = ax.pulse.step_high;
    j["step_low_cycles"] = ax.pulse.step_low;
    j["dir_setup_cycles"] = ax.pulse.dir_setup;
    j["dir_hold_cycles"] = ax.pulse.dir_hold;
    j["step_active_high"] = ax.step_active_high;
    j["dir_positive_high"] = ax.dir_positive_high;
    j["max_velocity"] = ax.max_velocity;
    j["max_accel"] = ax.max_accel;
    j["max_jerk"] = ax.max_jerk;
    j["peak_velocity"] = am.peak.v;
    j["peak_accel"] = am.peak.a;
    j["peak_jerk"] = am.peak.j;
    j["velocity_window_s"] = am.window.v;
    j["accel_window_s"] = am.window.a;
    j["jerk_window_s"] = am.window.j;
    j["velocity_tolerance"] = am.tolerance.v;
    j["accel_tolerance"] = am.tolerance.a;
    j["jerk_tolerance"] = am.tolerance.j;
    j["within_limits"] = am.within_limits;
    axes[std::string(1, plan::kAxisLetters[a])] = j;
  }
  r["axes"] = axes;
  return r;
}

}  // namespace cpstep::run

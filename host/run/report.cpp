// SPDX-License-Identifier: MIT
#include "run/report.h"

#include <fmt/format.h>

#include <string>

#include "card/caps.h"
#include "cpstep/builds.h"

namespace cpstep::run {

nlohmann::json make_report(const CardJob& job, const CardRun& run, const RunMeasure& m) {
  using nlohmann::json;
  const plan::PlanStats& st = job.planned.stats;
  json r;
  r["job"] = job.job_file;
  r["machine"] = job.machine.file;
  r["transport"] = run.link.transport.empty() ? "sim" : run.link.transport;
  r["clock_hz"] = job.clock_hz();
  const card::CardCaps& c = job.caps;
  const builds::Build* b = card::build_of(c);
  r["card"] = {{"name", b ? std::string(b->name) : std::string()},
               {"build_id", fmt::format("{:08x}", c.build_id)},
               {"n", c.n},
               {"w", c.w},
               {"umax", c.umax},
               {"kmax", c.kmax},
               {"chunk_queue", c.chunk_queue()},
               {"segment_queue", c.segment_queue()},
               {"tw", c.tw},
               {"command_buffer_words", c.command_buffer_words()},
               {"protocol", c.protocol}};
  r["ok"] = run.ok();
  r["step_segments"] = st.step_segments;
  r["planned_card_segments"] = st.card_segments;
  r["segments"] = job.wire_segments();
  r["chunks"] = job.wire_chunks();
  r["moves"] = job.moves();
  r["moves_per_chunk"] = job.wire_chunks() ? double(job.moves()) / double(job.wire_chunks()) : 0.0;
  r["phases"] = job.phases;  // PHASE commands (a phase-timer card; 0 otherwise)
  r["command_words"] = job.word_count();
  r["planned_time_s"] = st.duration_s;
  if (run.pins_observed) {
    r["job_time_s"] = m.job_time_s;
    r["job_time_cycles"] = m.job_time_cycles;
    r["run_cycles"] = run.cycles;
    r["sim_cycles"] = run.sim_cycles;
    r["engine"] = engine_name(run.engine);
    r["skipped_cycles"] = run.skipped_cycles;
    r["start_cycle"] = run.start_cycle;
    r["move_events"] = m.moves;
  }
  r["moves_done"] = run.moves_done;
  r["segments_done"] = run.segments_done;
  if (run.pins_observed) {
    r["checked_segments"] = run.checked_segments;
    r["position_mismatches"] = run.position_mismatches;
    r["max_timing_error_cycles"] = m.max_timing_error_cycles;
    r["max_timing_error_s"] = m.max_timing_error_cycles / job.clock_hz();
    r["max_timing_error_move"] = m.max_timing_error_move;
    r["chunk_tolerance_cycles"] = job.machine.chunk_tolerance_cycles();
    r["max_chunk_error_cycles"] = m.max_chunk_error_cycles;
    r["moves_off_chunk_time"] = m.moves_off_chunk_time;
    if (m.curve.positions) {
      // The stepped path against the job's NURBS curves (docs/CURVES.md).
      r["curve_deviation"] = {{"curves", m.curve.curves},
                              {"positions", m.curve.positions},
                              {"max_mm", m.curve.max_mm},
                              {"rms_mm", m.curve.rms_mm},
                              {"worst_line", m.curve.worst_loc.line},
                              {"worst_x_mm", m.curve.worst_x_mm},
                              {"worst_y_mm", m.curve.worst_y_mm}};
    }
  }
  // Feed hold and override (docs/CORE.md "Feed hold and override"): what the host sent,
  // when the card took it; with feed_scaled the timing figures above are not the plan's.
  r["feed_scaled"] = run.feed_scaled;
  nlohmann::json feed = nlohmann::json::array();
  for (const FeedApplied& f : run.feed)
    feed.push_back({{"what", f.what}, {"asked_s", f.event.at_s}, {"taken_s", f.taken_s}});
  r["feed"] = feed;
  if (job.machine.card.feed) {
    const plan::FeedRamp& ramp = job.machine.feed.ramp;
    r["feed_ramp"] = {{"tick_cycles", ramp.tick},         {"tau_s", ramp.tau_s},
                      {"span", ramp.span},                {"rate_per_s", ramp.rate_per_s()},
                      {"accel_per_s2", ramp.accel_per_s2()}, {"hold_s", ramp.hold_s()},
                      {"note", job.feed_ramp_note}};
  }
  r["stretches"] = run.stretch_count;
  r["stretched"] = run.status.stretched;
  if (run.pins_observed) {
    // The torch pin against the plan's switches (docs/CORE.md "Torch").
    const TorchVerdict& t = run.torch_verdict;
    json torch = {{"planned_switches", t.planned},
                  {"edges", t.edges},
                  {"as_planned", t.ok()},
                  {"max_delay_cycles", t.max_delay_cycles},
                  {"on_s", t.on_cycles / job.clock_hz()}};
    if (t.min_pierce_cycles) torch["min_pierce_s"] = *t.min_pierce_cycles / job.clock_hz();
    r["torch"] = torch;
  }
  json faults = json::array();
  for (const Fault& f : run.faults) faults.push_back({{"code", f.code}, {"name", f.name}, {"message", f.message}});
  r["faults"] = faults;
  json warnings = json::array();
  for (const plan::Diagnostic& w : job.warnings) warnings.push_back(w.str());
  r["warnings"] = warnings;

  const LinkReport& l = run.link;
  json link;
  link["device"] = l.transport != "sim"            ? l.link
                   : run.engine == Engine::model    ? std::string("cp_card, the fast engine (golden model)")
                   : run.engine == Engine::rtl      ? std::string("Verilated cp_card")
                                                    : std::string("Verilated cp_card and the fast engine in lockstep");
  link["sck_hz"] = l.sck_hz;
  if (l.sck_div) link["sck_div"] = l.sck_div;
  link["frames"] = l.stats.transfers;
  link["command_frames"] = l.stats.command_frames;
  link["polls"] = l.stats.polls;
  link["longest_gap_s"] = l.stats.longest_gap_s;
  link["bytes"] = l.stats.bytes;
  link["command_words"] = l.stats.words;
  link["marker_words"] = l.stats.markers;
  link["resent"] = l.stats.resent;
  link["damaged"] = l.stats.damaged;
  link["no_room"] = l.stats.no_room;
  link["bad_replies"] = l.stats.bad_replies;
  link["lost_results"] = l.stats.lost_results;
  link["waits"] = l.stats.waits;
  link["seconds"] = l.seconds;
  link["capacity_bytes_per_s"] = l.sck_hz / 8;
  link["bytes_per_s"] = l.seconds > 0 ? double(l.stats.bytes) / l.seconds : 0.0;
  link["command_bytes_per_s"] = l.seconds > 0 ? 4.0 * double(l.stats.words) / l.seconds : 0.0;
  if (l.sck_div) {
    link["busy_cycles"] = l.busy_cycles;
    link["utilisation"] = run.sim_cycles ? double(l.busy_cycles) / double(run.sim_cycles) : 0.0;
  }
  r["link"] = link;
  if (run.pins_observed) {
    // The same pin steps on Klipper's wire (plan/queue_step.h).
    auto qs = [](const plan::QueueStepCost& cost) {
      json o = {{"queue_step", cost.queue_step},       {"set_next_step_dir", cost.set_next_step_dir},
                {"reset_step_clock", cost.reset_step_clock}, {"message_bytes", cost.message_bytes},
                {"blocks", cost.blocks},               {"bytes", cost.bytes}};
      if (!cost.error.empty()) o["error"] = cost.error;
      return o;
    };
    r["wire"] = {{"command_bytes", 4 * job.word_count()}};
    if (m.klipper) {  // cpstep run --klipper
      r["wire"]["klipper_25us"] = qs(m.klipper_25us);
      r["wire"]["klipper_1us"] = qs(m.klipper_1us);
      r["wire"]["klipper_pins_25us"] = qs(m.klipper_pins_25us);
    }
  }

  json axes = json::object();
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job.machine.axes[a];
    if (!ax.present) continue;
    const AxisMeasure& am = m.axes[a];
    json j;
    j["steps_per_mm"] = ax.steps_per_mm;
    if (!run.pins_observed) j["start_steps"] = run.start_position[a];
    j["final_steps"] = run.position[a];
    j["final_mm"] = double(run.position[a]) / ax.steps_per_mm;
    j["planned_final_steps"] = job.checkpoint_count ? job.final_position[a] : 0;
    if (run.pins_observed) j["pulses"] = am.pulses;
    j["step_high_cycles"] = ax.pulse.step_high;
    j["step_low_cycles"] = ax.pulse.step_low;
    j["dir_setup_cycles"] = ax.pulse.dir_setup;
    j["dir_hold_cycles"] = ax.pulse.dir_hold;
    j["step_active_high"] = ax.step_active_high;
    j["dir_positive_high"] = ax.dir_positive_high;
    j["max_velocity"] = ax.max_velocity;
    j["max_accel"] = ax.max_accel;
    j["max_jerk"] = ax.max_jerk;
    if (run.pins_observed) {
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
    }
    axes[std::string(1, plan::kAxisLetters[a])] = j;
  }
  r["axes"] = axes;
  return r;
}

}  // namespace cpstep::run

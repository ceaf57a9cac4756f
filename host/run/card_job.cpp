// SPDX-License-Identifier: MIT
#include "run/card_job.h"

#include <fstream>

#include <fmt/format.h>

namespace cpstep::run {

uint64_t CardJob::wire_chunks() const {
  uint64_t n = 0;
  for (const card::WireSegment& s : wire.segments) n += s.chunks.size();
  return n;
}

plan::CardFacts card_facts(const card::CardCaps& caps) {
  return {card::card_name(caps), double(caps.clock_hz), caps.w, caps.kmax, caps.tw};
}

plan::Result<CardJob> prepare_job(const std::filesystem::path& gcode, const std::filesystem::path& machine_file,
                                  const card::CardCaps& caps, const plan::PerAxis<int64_t>& start) {
  plan::Result<CardJob> r;
  auto machine = plan::load_machine(machine_file);
  r.warnings = machine.warnings;
  if (!machine.ok()) {
    r.errors = machine.errors;
    return r;
  }
  r.errors = plan::bind_card(*machine.value, card_facts(caps));
  if (!r.errors.empty()) return r;
  plan::PerAxis<double> start_mm{};
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = machine.value->axes[a];
    if (start[a] == 0) continue;
    if (!ax.present) {
      r.errors.push_back({machine_file.string(), {},
                          fmt::format("the card's axis {} is at {} steps, but the machine has no such axis",
                                      plan::kAxisLetters[a], start[a])});
      return r;
    }
    start_mm[a] = double(start[a]) / ax.steps_per_mm;
  }
  auto job = plan::load_gcode(gcode, plan::gcode_options(*machine, start_mm));
  r.warnings.insert(r.warnings.end(), job.warnings.begin(), job.warnings.end());
  if (!job.ok()) {
    r.errors = job.errors;
    return r;
  }
  plan::PlanOptions options;
  options.chunk_limits = card::chunk_limits();  // add2 as the machine's planner.chunk_add2 says
  auto planned = plan::plan_job(*job, *machine, options);
  r.warnings.insert(r.warnings.end(), planned.warnings.begin(), planned.warnings.end());
  r.warnings = plan::summarize_repeats(std::move(r.warnings));  // e.g. "feed lowered" once, with a count
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  auto wire = card::to_wire(*planned, job->file, card::limits(caps));
  if (!wire.ok()) {
    r.errors = wire.errors;
    return r;
  }

  CardJob& cj = r.value.emplace();
  cj.job_file = job->file;
  cj.machine = *machine;
  cj.caps = caps;
  cj.planned = std::move(*planned.value);
  cj.wire = std::move(*wire.value);
  cj.words = card::encode_job(cj.machine, cj.wire);
  cj.ideal_cycles = plan::ideal_times(cj.planned, cj.clock_hz());

  plan::PerAxis<int64_t> pos = start;
  if (!cj.planned.step_segments.empty()) pos = cj.planned.step_segments.front().start;
  cj.start = pos;
  uint64_t moves = 0;
  int64_t last_event = 0;
  for (const plan::PlannedCardSegment& c : cj.planned.card) {
    // Every move's time from its chunks; a pause's moves time the next move's
    // first interval, but the pins show neither them nor a checkpoint.
    const std::vector<int64_t> t = plan::expand(c.chunks, last_event);
    if (!t.empty()) last_event = t.back();
    if (c.segment.pause) continue;
    cj.chunk_cycles.insert(cj.chunk_cycles.end(), t.begin(), t.end());
    moves += c.segment.moves;
    for (int a = 0; a < plan::kAxes; ++a) pos[a] += c.segment.delta[a];
    cj.checkpoints.push_back({moves, pos, c.segment.loc});
  }
  cj.warnings = r.warnings;
  return r;
}

bool write_words(const std::filesystem::path& path, const std::vector<uint32_t>& words) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return false;
  for (uint32_t w : words) {
    const char bytes[4] = {char(w & 0xFF), char(w >> 8 & 0xFF), char(w >> 16 & 0xFF),
                           char(w >> 24 & 0xFF)};
    out.write(bytes, 4);
  }
  out.close();
  return bool(out);
}

}  // namespace cpstep::run

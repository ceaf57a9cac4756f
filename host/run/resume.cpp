// SPDX-License-Identifier: MIT
#include "run/resume.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

namespace cpstep::run {

namespace {

// The G-code's lines (1-based: line n is lines[n - 1]).
std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  while (!text.empty()) {
    const size_t end = std::min(text.find('\n'), text.size());
    lines.push_back(text.substr(0, end));
    text.remove_prefix(std::min(end + 1, text.size()));
  }
  return lines;
}

// Whether a line has an M word switching the torch off: M5, M63 / M65 (digital
// output off), M2 / M30 (program end). Comments, (...) and ; to the end, are
// skipped; M may be lower case and spaced from its number, as RS274NGC allows.
bool switches_torch_off(std::string_view line) {
  bool in_comment = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_comment) {
      in_comment = c != ')';
      continue;
    }
    if (c == '(') in_comment = true;
    if (c == ';') return false;
    if (c != 'M' && c != 'm') continue;
    size_t j = i + 1;
    while (j < line.size() && (line[j] == ' ' || line[j] == '\t')) ++j;
    size_t k = j;
    while (k < line.size() && (std::isdigit(uint8_t(line[k])) || line[k] == '.')) ++k;
    if (k == j) continue;
    const double code = std::strtod(std::string(line.substr(j, k - j)).c_str(), nullptr);
    for (const double off : {5.0, 63.0, 65.0, 2.0, 30.0})
      if (code == off) return true;
  }
  return false;
}

}  // namespace

bool torch_on(const plan::MotionBlock& b) { return b.spindle_on || b.output0; }

std::vector<Contour> find_contours(const plan::Job& job, std::string_view text) {
  std::vector<Contour> out;
  const auto& blocks = job.blocks;
  for (size_t i = 0; i < blocks.size(); ++i) {
    if (!torch_on(blocks[i]) || (i > 0 && torch_on(blocks[i - 1]))) continue;
    size_t last = i;
    while (last + 1 < blocks.size() && torch_on(blocks[last + 1])) ++last;
    out.push_back({i, last, blocks[last].loc.line});
  }
  // The torch goes off between a contour's last block and the next block (an
  // M5 in the same block as a motion comes before it, RS274NGC's order).
  const std::vector<std::string_view> lines = split_lines(text);
  for (Contour& c : out) {
    const int after = blocks[c.last_block].loc.line;
    const int until = c.last_block + 1 < blocks.size() ? blocks[c.last_block + 1].loc.line : int(lines.size());
    for (int n = after + 1; n <= until && n <= int(lines.size()); ++n)
      if (switches_torch_off(lines[size_t(n - 1)])) {
        c.m5_line = n;
        break;
      }
  }
  return out;
}

std::vector<uint64_t> contour_end_moves(const CardJob& job) {
  // Each step segment's contour (-1: torch off), counted as find_contours counts blocks.
  const std::vector<plan::StepSegment>& segs = job.planned.step_segments;
  std::vector<int> contour(segs.size(), -1);
  int n = 0;
  for (size_t i = 0; i < segs.size(); ++i) {
    if (segs[i].torch && (i == 0 || !segs[i - 1].torch)) ++n;
    if (segs[i].torch) contour[i] = n - 1;
  }
  std::vector<uint64_t> ends(size_t(n), 0);
  std::vector<bool> moved(size_t(n), false);
  uint64_t moves = 0;
  for (const plan::PlannedCardSegment& c : job.planned.card) {
    moves += c.segment.moves;
    if (const int k = contour.at(c.segment.step_segment); k >= 0) {
      ends[size_t(k)] = moves;
      moved[size_t(k)] = true;
    }
  }
  // A contour without moves of its own (a dwell, timed as the next move's first
  // interval) is done with the one before it.
  for (size_t k = 1; k < ends.size(); ++k)
    if (!moved[k]) ends[k] = ends[k - 1];
  return ends;
}

std::string job_changed(const RunState& state, std::string_view job_bytes, const std::string& state_file) {
  const std::string hash = fnv1a64_hex(job_bytes);
  if (hash == state.job_fnv1a64) return "";
  return fmt::format("the job changed since the state was written ({} says FNV-1a 64 {}, the file's is {}): "
                     "nothing is resumed",
                     state_file, state.job_fnv1a64, hash);
}

size_t contours_done(const std::vector<uint64_t>& ends, uint64_t moves_done) {
  return size_t(std::upper_bound(ends.begin(), ends.end(), moves_done) - ends.begin());
}

plan::Job select_contours(const plan::Job& job, const std::vector<Contour>& contours, const ContourSelection& s) {
  plan::Job out;
  out.file = job.file;
  const size_t end = s.stop_after > 0 && s.stop_after <= contours.size() ? contours[s.stop_after - 1].last_block + 1
                                                                         : job.blocks.size();
  size_t begin = 0;
  if (s.from_mm && s.done < contours.size()) {
    begin = contours[s.done].first_block;
    const plan::MotionBlock& first = job.blocks[begin];
    plan::MotionBlock rapid;  // every other field at its default: torch off, no feed
    rapid.kind = plan::MotionKind::rapid;
    rapid.loc = begin > 0 ? job.blocks[begin - 1].loc : first.loc;
    rapid.start = *s.from_mm;
    rapid.end = first.start;
    rapid.plane = first.plane;
    rapid.tool = first.tool;
    rapid.spindle_speed = first.spindle_speed;
    out.blocks.push_back(rapid);
  }
  if (begin < end)
    out.blocks.insert(out.blocks.end(), job.blocks.begin() + long(begin), job.blocks.begin() + long(end));
  return out;
}

plan::Result<ContourPlan> plan_contours(const ContourOptions& o, const card::CardCaps& caps,
                                        const plan::PerAxis<int64_t>& start, std::string& nothing_left) {
  plan::Result<ContourPlan> r;
  const std::string gcode = o.gcode.string();
  const auto refuse = [&r](std::string file, std::string message) {
    r.errors.push_back({std::move(file), {}, std::move(message)});
    return r;
  };
  const std::optional<std::string> bytes = read_bytes(o.gcode);
  if (!bytes) return refuse(gcode, "cannot read the file");
  ContourPlan p;
  p.job_hash = fnv1a64_hex(*bytes);
  const RunState* st = o.resume;
  if (const std::string why = st ? job_changed(*st, *bytes, o.state_file) : ""; !why.empty())
    return refuse(gcode, why);
  if (st && st->ended == RunEnd::finished) {
    nothing_left = fmt::format("{} says the run finished the job", o.state_file);
    return r;
  }
  auto machine = load_card_machine(o.machine, caps);
  r.warnings = machine.warnings;
  if (!machine.ok()) {
    r.errors = machine.errors;
    return r;
  }
  const plan::Machine& m = *machine;
  for (int a = 0; st && a < plan::kAxes; ++a)
    if (m.axes[a].present != st->axes[a] || (st->axes[a] && m.axes[a].steps_per_mm != st->steps_per_mm[a]))
      return refuse(o.state_file,
                    fmt::format("steps_per_mm.{}: {} in the state, {} in {}: its position would be another place",
                                plan::kAxisLetters[a],
                                st->axes[a] ? fmt::format("{:g}", st->steps_per_mm[a]) : "no such axis",
                                m.axes[a].present ? fmt::format("{:g}", m.axes[a].steps_per_mm) : "no such axis",
                                m.file));
  p.job_start = st ? st->job_start : start;
  p.start = st ? st->position : start;
  auto job = read_card_gcode(o.gcode, m, p.job_start);
  r.warnings.insert(r.warnings.end(), job.warnings.begin(), job.warnings.end());
  if (!job.ok()) {
    r.errors = job.errors;
    return r;
  }
  p.contours = find_contours(*job, *bytes);
  const size_t total = p.contours.size();
  p.first = st ? size_t(st->contours_completed) : 0;
  if (p.first > total)
    return refuse(o.state_file, fmt::format("contours_completed: {}, but {} has {} contours", p.first, gcode, total));
  if (st && p.first == total) {
    nothing_left = fmt::format("{} says every contour of {} is done ({} of {})", o.state_file, gcode, p.first, total);
    return r;
  }
  if (o.stop_after > total)
    return refuse(gcode, fmt::format("--stop-after-contours {}: the job has {} contours", o.stop_after, total));
  if (o.stop_after > 0 && o.stop_after <= p.first)
    return refuse(gcode, fmt::format("--stop-after-contours {}: {} says {} contours are done already",
                                     o.stop_after, o.state_file, p.first));
  p.last = o.stop_after > 0 ? o.stop_after : total;
  ContourSelection sel{p.first, o.stop_after, std::nullopt};
  if (st) {
    p.resumed = true;
    sel.from_mm = st->position_mm();
    const size_t b = p.contours[p.first].first_block;
    p.pierce_mm = job->blocks[b].start;
    p.pierce_loc = job->blocks[b > 0 ? b - 1 : b].loc;  // the G0 to the pierce point, as select_contours names it
  }
  auto planned = plan_card_job(select_contours(*job, p.contours, sel), m, caps, p.start);
  r.warnings.insert(r.warnings.end(), planned.warnings.begin(), planned.warnings.end());
  r.warnings = plan::summarize_repeats(std::move(r.warnings));
  if (!planned.ok()) {
    r.errors = planned.errors;
    return r;
  }
  p.job = std::move(*planned.value);
  p.job.warnings = r.warnings;
  p.ends = contour_end_moves(p.job);
  if (p.ends.size() != p.last - p.first) {
    // A contour that makes no step segment (only moves shorter than a step, no dwell) cannot be counted.
    const Contour& c = p.contours[p.first];
    r.errors.push_back({gcode, job->blocks[c.first_block].loc,
                        fmt::format("the run's {} contours make {} runs of torch-on card moves: a contour of moves "
                                    "shorter than a step cannot be counted",
                                    p.last - p.first, p.ends.size())});
    return r;
  }
  r.value = std::move(p);
  return r;
}

RunState state_after(const ContourPlan& p, const CardRun& run, const std::string& job_file,
                     const std::string& machine_file) {
  RunState s;
  s.job = job_file;
  s.job_fnv1a64 = p.job_hash;
  s.machine = machine_file;
  const plan::Machine& m = p.job.machine;
  for (int a = 0; a < plan::kAxes; ++a) {
    s.axes[a] = m.axes[a].present;
    s.steps_per_mm[a] = m.axes[a].present ? m.axes[a].steps_per_mm : 0;
  }
  s.contours = p.contours.size();
  // A run refused before its first COMMANDS frame moved nothing: the card's
  // counters are not this job's.
  const bool sent = run.link.stats.command_frames > 0;
  s.contours_completed = p.first + (sent ? contours_done(p.ends, run.moves_done) : 0);
  s.last_m5_line = s.contours_completed ? p.contours[s.contours_completed - 1].m5_line : 0;
  s.job_start = p.job_start;
  s.position = run.position;
  s.ended = !run.ok() ? RunEnd::fault : p.last < p.contours.size() ? RunEnd::stopped : RunEnd::finished;
  return s;
}

CardJob counted_from_zero(const CardJob& job) {
  CardJob j = job;
  for (Checkpoint& c : j.checkpoints)
    for (int a = 0; a < plan::kAxes; ++a) c.position[a] -= job.start[a];
  for (int a = 0; a < plan::kAxes; ++a) j.final_position[a] -= job.start[a];
  j.start = {};  // a streamed job's checkpoints are made from it
  return j;
}

void add_origin(CardRun& run, const plan::PerAxis<int64_t>& origin) {
  for (int a = 0; a < plan::kAxes; ++a) {
    run.position[a] += origin[a];
    run.start_position[a] += origin[a];
  }
}

}  // namespace cpstep::run

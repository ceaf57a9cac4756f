// SPDX-License-Identifier: MIT
#include "run/torch.h"

#include <fmt/format.h>

#include <algorithm>

namespace cpstep::run {

std::vector<TorchSwitch> torch_switches(const CardJob& job) {
  std::vector<TorchSwitch> out;
  if (job.streamed) {
    // The changes the planner recorded; each its wire segment's G-code block.
    const uint64_t n = job.wire_segments();
    bool level = false;
    for (const CardJob::TorchChange& t : job.torch_changes) {
      out.push_back({t.segment, t.on, t.end_before + 1, t.end_before + t.first_interval, t.loc});
      level = t.on;
    }
    if (level) out.push_back({size_t(n), false, job.end_cycle + 1, job.end_cycle + 1, job.last_segment_loc});
    return out;
  }
  const std::vector<card::WireSegment>& segs = job.wire.segments;
  bool level = false;
  uint64_t end_before = 0;  // the last move event of the segment before, from START (0: START)
  const auto loc_of = [&](size_t s) {
    return s < job.wire.source.size() && job.wire.source[s] < job.planned.card.size()
               ? job.planned.card[job.wire.source[s]].segment.loc
               : plan::SourceLoc{};
  };
  for (size_t s = 0; s < segs.size(); ++s) {
    if (segs[s].torch != level) {
      // The first move fires `interval` of its first chunk after the move before (on a
      // phase-timer card, at its fire time).
      uint64_t first = segs[s].chunks.empty() ? 1 : segs[s].chunks.front().interval;
      const uint64_t first_move = s == 0 ? 0 : s - 1 < job.segment_end_moves.size() ? job.segment_end_moves[s - 1] : 0;
      if (first_move < job.fire_cycles.size())
        first = std::max<uint64_t>(1, uint64_t(job.fire_cycles[first_move]) - end_before);
      out.push_back({s, segs[s].torch, end_before + 1, end_before + first, loc_of(s)});
      level = segs[s].torch;
    }
    end_before = s < job.segment_end_cycle.size() ? job.segment_end_cycle[s] : end_before;
  }
  if (level) out.push_back({segs.size(), false, end_before + 1, end_before + 1, loc_of(segs.size() - 1)});
  return out;
}

TorchVerdict check_torch(const CardJob& job, const std::vector<TorchEdge>& edges, const std::vector<double>& moves,
                         double tol_cycles, size_t listed) {
  TorchVerdict v;
  const std::vector<TorchSwitch> plan = torch_switches(job);
  v.planned = plan.size();
  v.edges = edges.size();
  size_t errors = 0;
  const auto error = [&](std::string text) {
    if (errors++ < listed) v.errors.push_back(std::move(text));
  };
  const auto where = [&](const TorchSwitch& s) {
    return s.segment < job.wire_segments()
               ? fmt::format("wire segment {} ({}:{})", s.segment + 1, job.job_file, s.loc.line)
               : fmt::format("the run's end ({}:{})", job.job_file, s.loc.line);
  };
  for (size_t k = 0; k < std::min(plan.size(), edges.size()); ++k) {
    const TorchSwitch& s = plan[k];
    const TorchEdge& e = edges[k];
    if (e.on != s.on) {
      error(fmt::format("torch edge {} goes {} at cycle {:.0f}, but the plan switches it {} at {}", k + 1,
                        e.on ? "on" : "off", e.cycle, s.on ? "on" : "off", where(s)));
      continue;
    }
    if (e.cycle < double(s.earliest) - tol_cycles || e.cycle > double(s.latest) + tol_cycles) {
      error(fmt::format("torch {} at cycle {:.0f} from START, but {} switches it in cycles {}..{}", s.on ? "on" : "off",
                        e.cycle, where(s), s.earliest, s.latest));
      continue;
    }
    v.max_delay_cycles = std::max(v.max_delay_cycles, e.cycle - double(s.earliest));
  }
  if (plan.size() != edges.size())
    error(fmt::format("{} torch edges in the trace, {} planned", edges.size(), plan.size()));
  if (errors > listed) v.errors.push_back(fmt::format("... and {} more", errors - listed));
  for (size_t k = 0; k < edges.size(); ++k) {
    if (!edges[k].on) continue;
    const double off = k + 1 < edges.size() ? edges[k + 1].cycle : (moves.empty() ? edges[k].cycle : moves.back());
    v.on_cycles += std::max(0.0, off - edges[k].cycle);
    // The next move after the edge (the segment before may show its last STEP edge in
    // the edge's own cycle).
    const auto next = std::upper_bound(moves.begin(), moves.end(), edges[k].cycle);
    if (next != moves.end() && (k + 1 >= edges.size() || *next <= edges[k + 1].cycle)) {
      const double pierce = *next - edges[k].cycle;
      v.min_pierce_cycles = v.min_pierce_cycles ? std::min(*v.min_pierce_cycles, pierce) : pierce;
    }
  }
  return v;
}

}  // namespace cpstep::run

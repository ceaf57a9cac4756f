// SPDX-License-Identifier: MIT
// A planned job for a phase-timer card (READ 0x23 [26]; docs/CORE.md "Phase-timer
// builds", docs/PROTOCOL.md "Toward a compact wire"): the feed plan's phases of
// constant jerk fitted in the timer's half clocks (plan::PhaseFitter), the card
// segments without chunks, each with its length per move and in the compact axis
// form, and every command in the order the card needs it — a phase by the time it
// begins, a segment by its first move — START after the first segment.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "card/job.h"
#include "plan/common.h"
#include "plan/pipeline.h"

namespace cpstep::card {

// The clocks from the cycle a phase-timer card takes START to the fire of a move
// due at half clock 0 of its first phase (docs/CORE.md "Phase-timer builds"): move n
// fires 2 * fire_half_clocks[n] + kPhaseTimerStartCycles clocks after START, at scale 1.
inline constexpr int64_t kPhaseTimerStartCycles = 1;

// A conic move's length division on a phase-timer card: the 27 + S bits of K 2^S,
// then the done clock (rtl/cp_div.v, rtl/cp_conic_serial.v LEN).
inline constexpr int64_t conic_division_cycles(unsigned s) { return 27 + int64_t(s) + 1; }
// The fewest clocks between two moves of a conic on such a card: the walker's pass
// (IW + 1 clocks) and the division.
inline constexpr int64_t conic_move_gap_cycles(unsigned ciw, unsigned s) {
  return int64_t(ciw) + 1 + conic_division_cycles(s);
}

struct PhaseTimerJob {
  std::vector<uint32_t> preamble;               // encode_preamble: drivers, axes, inputs, feed
  std::vector<std::vector<uint32_t>> commands;  // PHASE and SEGMENT commands, in the order to send
  size_t start_after = 0;                       // commands before START
  // Each move's due in the timer's half clocks from the first phase (the fitter's;
  // at scale 1 the card fires move n 2·(fire_half_clocks[n] - fire_half_clocks[0])
  // clocks after move 0).
  std::vector<int64_t> fire_half_clocks;
  std::array<int64_t, plan::kAxes> end{};       // each axis's steps at the end, from 0
  size_t phases = 0, segments = 0;
  uint64_t bytes = 0;                           // of `commands`
  uint64_t segment_bytes = 0;                   // of which the segments'
  uint64_t every_axis_bytes = 0;                // the segments with every axis's v sent
  uint64_t chunked_bytes = 0;                   // the segments with their chunks, as a chunk card takes them
  // The plan the commands were made from (its chunks unsent: to_wire checks them) and
  // its wire segments, each with its length per move (WireSegment::length).
  plan::PlannedJob planned;
  WireJob wire;
  // The phases' ends in half clocks from the first phase's start, one per PHASE command
  // in `commands`' order (phases are sent in time order).
  std::vector<int64_t> phase_end_half_clocks;
};

// Plans `job` on `machine` (bound to the card: its clock) for a phase-timer card of
// `limits`. Arcs as the machine file plans them (planner.arcs): as conics, each
// move measured by the walker's length rule (plan::conic_rule_lengths, the CONIC's
// L word its arc's {S, K}), its moves at least conic_move_gap_cycles apart. A
// dwell waits in rest phases; a pause (a dwell longer than a move interval holds,
// or one after the last move) is a segment of pause moves (v all 0, L
// 0xFFFFFFFF) each fired by a timed move at its clock. Errors for what the card
// cannot time, as for a line too long for one length word. `file` names the
// G-code in errors.
plan::Result<PhaseTimerJob> plan_phase_timer_job(const plan::Job& job, const plan::Machine& machine,
                                                 const CardLimits& limits, const std::string& file);

}  // namespace cpstep::card

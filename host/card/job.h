// SPDX-License-Identifier: MIT
// From a planned job to the card's command words: choose each segment's
// doubling exponent, split what exceeds the card's move count, and order the
// configuration, the segments and START (docs/CORE.md).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "card/caps.h"
#include "card/protocol.h"
#include "plan/chunks.h"
#include "plan/common.h"
#include "plan/machine.h"
#include "plan/pipeline.h"

namespace cpstep::card {

// What the card accepts (rtl/cp_core.v parameters).
struct CardLimits {
  uint32_t umax = (1u << 20) - 1;  // largest U
  unsigned kmax = 8;               // largest doubling exponent
  uint32_t w = 1024;               // pattern capacity
  unsigned chunk_queue = 64;       // 2^CAW
  unsigned segment_queue = 4;      // 2^SAW
};

// The limits of a card that reported these capabilities.
CardLimits limits(const CardCaps& caps);

// The chunk form the card executes: 16-bit count, add and add2; the increments
// add + j*add2 within 16 bits and of one sign (docs/CORE.md, SEG_ADD2).
plan::ChunkLimits chunk_limits(const CardLimits& card = {});

// A chunk the card takes as it is and that to_wire() can split anywhere.
bool in_card_form(const plan::Chunk& c);

struct WireJob {
  std::vector<WireSegment> segments;
  std::vector<size_t> source;   // per wire segment: index of its planned card segment
  size_t start_after = 0;       // START is sent after this many segments
  // The seek armed before START (CONFIG field 10, seek_mode; cards with inputs):
  // the run ends when the input trips (docs/CORE.md "Seek: homing and probing").
  uint32_t seek = 0;
};

// Converts the planned card segments. A segment whose U exceeds UMAX, or whose
// chunks do not fit the card's chunk queue at once, is split at multiples of
// its patterns' common period, so every piece replays whole patterns and
// nothing moves off the planned lattice; the chunks are cut with it, so the
// move times stay exactly the planned ones. A segment that cannot be cut so
// is an error.
// `file` names the G-code file in errors.
plan::Result<WireJob> to_wire(const plan::PlannedJob& job, const std::string& file,
                              const CardLimits& card = {});

// One planned card segment (job.card[s] with these chunks and walk: its own, or
// made again) as wire segments, appended to `out`
// (none marked `end`); an error when the card cannot take it.
std::optional<plan::Diagnostic> to_wire_segment(const plan::PlannedJob& job, size_t s,
                                                std::span<const plan::Chunk> chunks, const plan::ConicWalk* conic,
                                                const std::string& file, const CardLimits& card,
                                                std::vector<WireSegment>& out);
// The same for a card segment and its torch level (its step segment's), as a
// plan streamed card segment by card segment hands them out.
std::optional<plan::Diagnostic> to_wire_segment(const plan::CardSegment& seg, bool torch,
                                                std::span<const plan::Chunk> chunks, const plan::ConicWalk* conic,
                                                const std::string& file, const CardLimits& card,
                                                std::vector<WireSegment>& out);
// How many segments go before START: the first ones that fit the card's segment
// and chunk queues at once (at least one), from the chunk counts of the first
// segment_queue + 1 wire segments (or all there are).
size_t start_after(std::span<const size_t> chunks, const CardLimits& card);

// One of the fitter's phases (plan/phases.h) as a PHASE command's values (a
// phase-timer card, docs/CORE.md "Phase-timer builds").
WirePhase wire_phase(const plan::TimerPhase& ph);

// Configuration of every present axis, the segments (the last one ends the run)
// and START where the first segments fit the card's queues.
std::vector<uint32_t> encode_job(const plan::Machine& machine, const WireJob& job);
// What encode_job() sends before the segments: drivers on, every axis's
// configuration, the inputs, the seek (seek_mode), the feed ramp.
void encode_preamble(const plan::Machine& machine, uint32_t seek, std::vector<uint32_t>& words);
// The CONFIG words of the machine's inputs on a card that has them (the filter, each
// axis's limit switches, the probe's level); nothing otherwise. encode_job sends them.
void encode_inputs(const plan::Machine& machine, std::vector<uint32_t>& words);

}  // namespace cpstep::card

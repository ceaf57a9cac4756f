// SPDX-License-Identifier: MIT
// Timing chunks in the card's form, compressed greedily from ideal move
// times: each realized time lies in [ideal - tolerance, ideal] (never late,
// at most `tolerance` early, as in Klipper's stepcompress).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cpstep::plan {

// Move j (0..count-1) of a chunk happens interval + j*add + add2*j*(j-1)/2
// cycles after the previous move event. With F fractional bits
// (ChunkLimits::frac_bits > 0) add and add2 count 2^-F cycles, and the delays
// are summed exactly: move j happens floor(X_j / 2^F) cycles after the event
// before the chunk, X_j = (j+1) interval 2^F + add j(j+1)/2 + add2 (j+1)j(j-1)/6.
struct Chunk {
    std::uint32_t interval = 0;
    std::uint32_t count = 0;
    std::int32_t add = 0;
    std::int32_t add2 = 0;
    friend bool operator==(const Chunk&, const Chunk&) = default;
};

// The longest delay between two move events the card can time: its 32-bit interval.
inline constexpr std::int64_t kMaxMoveDelayCycles = (std::int64_t{1} << 32) - 1;

struct ChunkLimits {
    std::uint32_t max_count = 65535;
    std::int64_t add_min = INT32_MIN, add_max = INT32_MAX;
    std::int64_t add2_min = INT16_MIN, add2_max = INT16_MAX;
    bool enable_add2 = true;
    // The card's rule for add2 (docs/CORE.md, SEG_ADD2): within a chunk the
    // increments add + j*add2 (j = 0..count-2) all lie in [add_min, add_max] and
    // none has the opposite sign of another, so the delays are monotone.
    bool monotone = false;
    // Fractional bits of add and add2 (0: whole cycles). add_min..add2_max are
    // then in units of 2^-frac_bits cycles.
    unsigned frac_bits = 0;
};

struct ChunkResult {
    std::vector<Chunk> chunks;
    std::int64_t last_event = 0;   // realized time of the last move, cycles
    std::string error;             // empty on success
    [[nodiscard]] bool ok() const { return error.empty(); }
};

// Compress the moves with ideal absolute times `ideal` (cycles, increasing),
// the previous move event having happened at `prev_event`.
ChunkResult compress(std::span<const double> ideal, std::int64_t prev_event, double tolerance,
                     const ChunkLimits& limits);

// Expand chunks back into absolute event times (the card's arithmetic).
std::vector<std::int64_t> expand(std::span<const Chunk> chunks, std::int64_t prev_event, unsigned frac_bits = 0);

}  // namespace cpstep::plan

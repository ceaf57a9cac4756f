// SPDX-License-Identifier: MIT
// Arcs on the card: a G2/G3 arc as CONIC card segments (docs/CORE.md "CONIC",
// docs/PLANNING.md "Arcs as conics"). The card's walker steps the arc's plane by
// seed 001's rule; the host runs the same walk (model::CpConicSerial::rule, modulo
// the walker's width) to know every node, picks the end node, times every move
// from the feed planned over the arc's chords, and splits what the card cannot
// take in one segment. An arc the walker cannot step within the card's limits is
// left to chords, with the reason.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/planner.h"
#include "plan/reduce.h"
#include "plan/segments.h"

namespace cpstep::plan {

// The walk of one CONIC card segment: the plane, the curve, the start node, every
// move and its ideal time.
struct ConicWalk {
    int axis_u = 0, axis_v = 1;
    bool cw = false;  // the walker's sense: clockwise in (u, v), G > 0 on the left of travel
    // The circle in steps, A x^2 + B xy + C y^2 + D x + E y + F = 0 (A = C = 256).
    std::int64_t a = 0, b = 0, c = 0, d = 0, e = 0, f = 0;
    // The G-code's circle in steps (its exact centre and start radius in u's steps;
    // v's steps stretched by su / sv make it a circle), which the walk's integers
    // round: what `cpstep check` measures the nodes against.
    double centre_u = 0, centre_v = 0, radius = 0, stretch_v = 1;
    // A node's distance in steps from that curve (a circle: exact; an ellipse in
    // steps, unequal steps/mm: to first order, |G| / |grad G|).
    [[nodiscard]] double off_curve(double x, double y) const;
    std::int64_t u0 = 0, v0 = 0;      // the start node
    std::int64_t du = 0, dv = 0;      // the end node minus the start node
    std::vector<std::uint8_t> moves;  // per move: (dx + 1) | (dy + 1) << 2
    std::vector<double> ideal;        // per move: its ideal time, card cycles from the job start
    // The walk goes on from the one before it (a tail(): a later piece of one arc),
    // so its CONIC may continue the previous one's (docs/CORE.md, H0[18]).
    bool cont = false;

    [[nodiscard]] static std::uint8_t pack(int dx, int dy) { return std::uint8_t((dx + 1) | (dy + 1) << 2); }
    [[nodiscard]] static int dx_of(std::uint8_t m) { return int(m & 3) - 1; }
    [[nodiscard]] static int dy_of(std::uint8_t m) { return int(m >> 2 & 3) - 1; }
    // The seven words K0..K6 that load the walker for this walk (docs/CORE.md).
    [[nodiscard]] std::array<std::uint32_t, 7> words() const;
    // The same walk's first `n` moves, and the walk from move n on (with their times;
    // a continuation of the head).
    [[nodiscard]] ConicWalk head(std::size_t n) const;
    [[nodiscard]] ConicWalk tail(std::size_t n) const;
};

// The rule for the length of a conic's move that a phase-timer card's walker
// applies (docs/CONIC.md "The length rule", rtl/cp_conic_serial.v LEN): move n,
// from node n-1 to node n, is K 2^S / m(node n-1) long, m(P) = max(|Gx(P)|,
// |Gy(P)|) (the walker's gradient: Gx = 2Ax + By + D, Gy = Bx + 2Cy + E), K and S
// one constant of the arc. On a circle ds/d(major) = |grad G| / |G of the minor's
// normal|: the move advances the axis its octant steps every move by one, and the
// gradient's larger component is the other one's, so 1 / m is the path per move up
// to a constant. One divisor m per move of `w`.
[[nodiscard]] std::vector<std::uint64_t> conic_rule_divisors(const ConicWalk& w);

// An arc's constant for the rule, as a CONIC segment's length word carries it on a
// phase-timer card: {S [31:27], K [26:0]}, and its moves' lengths floor(K 2^S / m)
// (units of 2^-30 of the phases' path unit), chosen so that they sum to `total`
// (the arc's path, in the same units) as closely as K's 27 bits allow. An error
// when a length would not fit 32 bits or be 0 (or a divisor is 0).
struct ConicRuleLengths {
    std::uint32_t word = 0;
    std::vector<std::uint32_t> lengths;
};
[[nodiscard]] std::variant<ConicRuleLengths, std::string> conic_rule_lengths(std::span<const std::uint64_t> divisors,
                                                                            double total);
// floor(K 2^S / m) for a length word {S, K}, saturated to 2^32 - 1 (m = 0 too), as
// rtl/cp_div.v gives it.
[[nodiscard]] std::uint32_t conic_rule_length(std::uint32_t word, std::uint64_t m);

// One CONIC card segment: what the planner records of it (moves, delta, the other
// axes' patterns over T with k = 0) and its walk.
struct ConicPiece {
    CardSegment segment;
    std::shared_ptr<const ConicWalk> walk;
};

struct ConicArcStats {
    double max_node_deviation = 0;  // steps: the farthest node from the G-code arc
    double max_other_deviation = 0; // steps: the farthest other axis (a helix's) from its line
};

// What plan_conic_arc needs: the arc, its chords as the feed planner planned them,
// the card position it starts from, and the card's limits.
struct ConicArcInput {
    const MotionBlock* block = nullptr;
    std::span<const StepSegment> chords;     // the arc's step segments, in order
    std::span<const PlannedSegment> feeds;   // their planned feeds
    std::size_t first_step_segment = 0;      // index of chords[0] in the job
    PerAxis<std::int64_t> start{};           // where the card is (normally chords[0].start)
    bool last_motion = false;                // no motion follows: the walk must end on the arc's end step
    unsigned ciw = 0;                        // the card's walker width (0: none)
    std::uint32_t umax = 0;                  // largest T
    std::uint32_t w = 0;                     // pattern capacity (the other axes' patterns over T)
    double clock_hz = 0;
    double tolerance_cycles = 0;             // a move may be this much early (chunks)
};

// The arc as CONIC pieces (their moves sum to the walk's), or why it must be chords.
std::variant<std::vector<ConicPiece>, std::string> plan_conic_arc(const ConicArcInput& in, const Machine& m,
                                                                  ConicArcStats* stats = nullptr);

// Cycles the walker needs between the last move of one CONIC segment and the first
// of the next (docs/CORE.md "CONIC": 8 + CIW + 2), and between two moves of one.
inline constexpr std::uint64_t conic_gap_cycles(unsigned ciw) { return 8u + ciw + 2u; }

}  // namespace cpstep::plan

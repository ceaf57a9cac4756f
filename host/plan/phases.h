// SPDX-License-Identifier: MIT
// Move events timed by phases of constant jerk (issue 13, toward a compact
// wire; the card's unit is rtl/cp_ptimer.v, its twin model/cp_ptimer.h, the timer of
// cp_core's PTIMER build: docs/PROTOCOL.md "Toward a compact wire"). The card keeps the path
// position as a sum, exactly, in integers, with the state at tick boundaries
// being the cubic's own derivatives (so that a phase's jerk can change
// without the position, velocity or acceleration jumping):
//
//   every clock of a tick (2^s clocks):  p += S; when p >= the next move's
//       length (times 2^s): the move fires, p -= that length
//   at each tick's end:  S += 2H + 6u, H += 3u
//
// S is the tick's step, V + H + u of the cubic x(m) = V m + H m^2 + u m^3 over
// ticks (V, H, u: its velocity per tick, half its acceleration, a sixth of its
// jerk); the card keeps S, H and u (no V) and carries S and H from a phase into
// the next, so a new u changes the step from the phase's second tick on (its
// first tick's step is the one the phase before left).
//
// S, H and u in units of 2^-F moves (path_unit_mm = 0) or of 2^-F
// path_unit_mm of path (path_unit_mm > 0; each card segment would carry its
// length per move), per tick, per tick^2 (half the acceleration) and per
// tick^3 (a sixth of the jerk). Phases are (ticks, u), maybe from rest (p, S,
// H = 0), maybe reloading p, S and H from the plan, or a timed move (fired a
// given number of clocks after the phase's start; the last move of a stop,
// which the position reaches too flatly for any phase to time within 1 us:
// 3e-14 moves 41 clocks before the end).
//
// Move n (1, 2, ...) of a phase that starts at clock c0 with p0, S, H fires
// at the first clock c0 + k where p0 + P(k) reaches the moves' lengths up to n,
//   P(k) = (S - H) k + H A(k) + u (G(k) - k),  k = M 2^s + r (0 <= r < 2^s),
//   A(k) = 2^s M^2 + r (2M + 1),   G(k) = 2^s M^3 + r (3M^2 + 3M + 1),
// linear in u: each move's window (never late, at most `tolerance` early, as
// the chunks) gives u an interval. PhaseFitter takes the feed plan's own phases
// where they are given (PlanJerk; its jerk up to the tick nearest the next
// change, as it stands or with S and H set back to the plan's) and otherwise a
// greedy phase, which lasts while the intervals of its moves meet.
#pragma once

#include <cstdint>
#include <span>
#include <deque>
#include <string>
#include <utility>
#include <vector>

namespace cpstep::plan {

__extension__ typedef __int128 i128;   // the timer's sums, exactly

// One phase of the feed plan as the fitter may follow it (PhaseFormat::plan_jerk):
// the absolute clock it starts at, its jerk, speed and acceleration there (mm/s^3,
// mm/s, mm/s^2 along the path).
struct PlanJerk {
    double at = 0, jerk = 0, v = 0, a = 0;
};

struct PhaseFormat {
    unsigned tick_log2 = 6;    // a tick is 2^s clocks
    unsigned frac_bits = 60;   // F: S, H and u in 2^-F moves (or path units), p in 2^-F-s
    bool reload = true;        // a phase may set p, S and H (from the plan) where that saves words
    bool lookahead = false;    // a phase may end early where the next then carries on further
    // 0: p counts moves (a move fires at each whole move). > 0: p is the path
    // length in units of path_unit_mm * 2^-F, a move fires when p reaches
    // its own length (each card segment's length per move).
    double path_unit_mm = 0;
    // Path domain, with the plan's jerk changes given to push(): each phase is
    // first tried as the plan's own (its jerk, ending at the tick nearest the
    // plan's next change), the greedy fit only where that misses a window.
    bool plan_jerk = true;
    double clock_hz = 0;       // the card's clock (plan_jerk: the jerk in the timer's units)
    // The card's registers (rtl/cp_ptimer.v): u, S and H signed in these many bits.
    unsigned u_bits = 24, v_bits = 56, h_bits = 40;
    // A move's length as the card holds it: fractional bits of path_unit_mm (a
    // phase-timer card's segment word L is Q2.30: 30).
    unsigned length_bits = 40;
};

struct TimerPhase {
    std::uint64_t ticks = 0;   // ticks (a timed move: clocks)
    std::int64_t jerk = 0;     // u: a sixth of the jerk, per tick^3
    bool rest = false;         // p, S and H set to zero at the phase's start
    bool reload = false;       // p, S and H set at the phase's start (after rest)
    std::int64_t s = 0, a = 0; // S (the step) and H (half the acceleration) for a reload or an adjust
    // A reload's p as the card takes it: r = p minus the pending move's length
    // (times 2^s) = r_top * 2^(F + s + 3 - 64), r's top 64 of F + s + 3 bits.
    std::int64_t r_top = 0;
    bool timed = false;        // no jerk phase: one move `ticks` clocks after the phase's start, then p = 0
    // S and H set at the phase's start, p kept (plan_jerk: the plan's own phase
    // with its state brought back to the plan's; the card's "load S and H").
    bool adjust = false;
    friend bool operator==(const TimerPhase&, const TimerPhase&) = default;
};

// What the phases needed: ranges of the registers, for choosing field widths.
struct PhaseStats {
    std::uint64_t moves = 0;
    std::uint64_t phases = 0;
    std::uint64_t rests = 0;
    std::uint64_t reloads = 0;
    std::uint64_t timed = 0;
    std::uint64_t plan_phases = 0;    // the plan's own (plan_jerk)
    std::uint64_t adjusts = 0;        // of them with S and H corrected
    std::int64_t max_abs_adjust = 0;  // the largest correction of S or H
    std::uint64_t max_ticks = 0;
    std::int64_t max_abs_jerk = 0;
    std::int64_t max_abs_accel = 0;   // at phase ends
    std::int64_t max_velocity = 0;    // the step S at phase ends
    std::uint64_t max_phase_moves = 0;
};

// Fits phases to move times given in order, batch by batch (each card
// segment's moves as it is timed), the state carried from one batch to the
// next. Deterministic.
class PhaseFitter {
public:
    PhaseFitter(PhaseFormat format, double tolerance_cycles);

    // The next moves' ideal times (absolute clocks, increasing, after every
    // earlier move's); rest_at >= 0: the motion starts from rest at that clock
    // (before the first of them), else it continues from the moves before.
    // False with error() when no phase can time a move within its window.
    bool push(std::span<const double> ideal, std::span<const double> lengths_mm, double rest_at = -1,
              std::span<const PlanJerk> plan = {});
    // A pause's moves (they step nothing; absolute clocks, after every earlier
    // move's): the moves before are fitted, then each pause move is a timed move at
    // its clock (never late), after flat rests where it is further than a timed
    // move reaches; the motion after it starts from rest (push()'s rest_at).
    bool push_pause(std::span<const double> ideal);
    // Every move pushed is fitted (the last phase closed).
    bool finish();

    [[nodiscard]] const std::vector<TimerPhase>& phases() const { return phases_; }
    [[nodiscard]] const std::vector<std::int64_t>& fire_clocks() const { return fires_; }
    [[nodiscard]] const PhaseStats& stats() const { return stats_; }
    [[nodiscard]] const std::string& error() const { return error_; }

private:
    // Where a phase starts: clock, p, S, H, the next queued move and the end
    // of the move before it on the path.
    struct State {
        std::int64_t c0 = 0;
        i128 p0 = 0, s0 = 0, a0 = 0;   // p, S, H
        std::size_t head = 0;
        i128 cum_head = 0;
    };
    struct Trial {
        bool wait = false;          // the queue may bring moves the phase would take
        std::size_t covered = 0;
        i128 j = 0;
        std::int64_t E = 0;         // ticks
    };
    static constexpr std::size_t kNoCap = static_cast<std::size_t>(-1);
    bool fit(bool all);
    [[nodiscard]] Trial evaluate(const State& st, bool all, std::size_t cap = kNoCap) const;
    void advance(State& st, const Trial& tr, std::vector<std::int64_t>* fires) const;
    bool plan_state(i128& p, i128& step, i128& h) const;
    // The plan's own phase from the open phase's start: 1 taken, 0 not (the
    // greedy fit then), -1 wait for more moves.
    int plan_phase(bool all);
    int plan_phase_try(bool all, bool adjust);
    void commit(const State& from, const Trial& tr, bool reload, bool adjust = false, i128 ds = 0, i128 dh = 0);

    PhaseFormat fmt_;
    double tol_;
    // The state at the start of the open phase (clock c0_, exact).
    std::int64_t c0_ = 0;
    i128 p0_ = 0, s0_ = 0, a0_ = 0;
    bool pending_rest_ = false;   // the open phase starts from rest
    std::deque<PlanJerk> changes_;   // the plan's phases to come (a change of jerk or of state)
    std::vector<double> queue_;   // ideal times not yet in a closed phase
    std::vector<i128> cum_;       // each queued move's end on the path (units), from the job's start
    i128 cum_head_ = 0;           // the end of the move before queue_[head_]
    std::size_t head_ = 0;
    std::vector<TimerPhase> phases_;
    std::vector<std::int64_t> fires_;
    PhaseStats stats_;
    std::string error_;
};

// A move's length in the timer's units (2^-F of a move, or of path_unit_mm).
i128 move_length(double length_mm, const PhaseFormat& format);

// The card's arithmetic clock by clock (the form's reference): the clocks at
// which the phases fire moves, from rest at clock 0, each move's length given
// (move_length(); none given: a move each).
std::vector<std::int64_t> simulate_phases(std::span<const TimerPhase> phases, PhaseFormat format,
                                          std::span<const i128> lengths = {});

}  // namespace cpstep::plan

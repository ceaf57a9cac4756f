// SPDX-License-Identifier: MIT
// cp_ptimer — cycle-accurate, bit-exact model of rtl/cp_ptimer.v: the phase
// timer, moves timed by phases of constant jerk (issue 13, toward the compact
// wire; cp_run's timer in a PTIMER build of cp_core). The host's side is
// plan/phases.h, whose arithmetic this is, clock by clock:
//
//   every clock of a jerk phase (adv):  p += step; the pending move is due while
//       p >= its length * 2^S. Kept as r = p - that length * 2^S (due: r >= 0);
//       a fire takes off the next move's length (`len` is the length of the move
//       pending after this clock: in a clock that fires, the next one's) when
//       `len_valid`; until then the length is owed (taken off in the first clock
//       that has it) and no move is due
//   at the end of each tick (2^S clocks from the phase's start):
//       step += 2H + 6u, H += 3u
//   (the step S = V + H + u of the cubic V m + H m^2 + u m^3 over ticks; no V is
//   kept). A phase (W0 = {load S and H, rest, timed, load r, 4'b0, ticks[23:0]})
//   holds u for `ticks` ticks (0: 1), then the next phase loads at once (none: the
//   timer stops, `starved`). It carries r, S and H on (a new u changes the step
//   from its second tick on), or starts from rest (p, S, H = 0), and/or loads S
//   and H, and/or r, from the buffer (in that order); a timed phase is one move,
//   due `ticks` clocks after the phase's start, with p, S and H frozen until then
//   and p = 0 after (r = 0 until the timed move fires and takes off the next's);
//   a move that came due in the last clock before it is due in it too.
//
// The next phase is written word by word into a buffer (sel 1: u; 2, 3: r's top
// 64 bits, low word first; 4, 5: S; 6, 7: H) and committed by W0 (sel 0) while
// `ready`; a write while not ready changes nothing. outputs() before the edge,
// tick() the edge.
#pragma once

#include <cstdint>
#include <optional>

#include "model/bits.h"

namespace cpstep::model {


struct CpPtimerIn {
  bool rst = false;
  bool clear = false;      // stop and empty (FLUSH, E-stop)
  bool adv = true;         // this clock counts (the feed's scaled time)
  bool wr = false;
  uint32_t sel = 0;
  uint32_t data = 0;
  bool fire = false;       // the due move fires now
  uint64_t len = 0;        // the pending move's length after this clock, 2^-F units (LW bits)
  bool len_valid = true;   // ... is known (else it is owed)
};

struct CpPtimerOut {
  bool due = false;
  bool active = false;
  bool ready = false;      // the buffer takes the next phase
  bool starved = false;    // a phase ended with none after it (until one loads)
  uint32_t kind = 0;       // the running phase's {load S and H, rest, timed, load r}
  bool operator==(const CpPtimerOut&) const = default;
};

struct CpPtimerParams {
  unsigned s = 6;    // a tick is 2^S clocks
  unsigned f = 60;   // fractional bits of p, V, H, u
  unsigned vw = 56, hw = 40, uw = 24, tw = 24, lw = 62;   // register widths (signed S, H, u)
};

class CpPtimer {
 public:
  using In = CpPtimerIn;
  using Out = CpPtimerOut;
  using Params = CpPtimerParams;

  explicit CpPtimer(Params p = {}) : p_(p) {}
  In in;
  Out outputs() const;
  void tick();

  // Event skipping (CpRun::quiet_for, docs/SIM.md "The fast engine"): with no word
  // written, no fire and no clear, and `len_valid` as it is, how many of the coming
  // clocks that advance (adv) leave everything but r, the tick's count, the step, H
  // and the timed count as they were — no move due after any of them, no phase
  // ending — at most `limit`; kForever while no phase runs (nothing advances);
  // nullopt: something changes in the next clock whether it advances or not (a move
  // due now, an owed length taken off, a phase loading).
  static constexpr uint64_t kForever = ~uint64_t(0);
  std::optional<uint64_t> quiet_advs(bool len_valid, uint64_t limit) const;
  // Applies n such advancing clocks at once (n <= quiet_advs()): exactly the state
  // n tick()s with adv would leave.
  void skip_advs(uint64_t n);

  // For the benches.
  bits::i128 r() const { return r_.r; }
  int64_t step() const { return r_.step; }
  int64_t h() const { return r_.h; }
  unsigned rw() const { return p_.f + p_.s + 3; }
  uint64_t loads() const { return loads_; }   // phases loaded since construction

 private:
  struct Regs {
    bool active = false, timed = false, tdue = false, starved = false;
    bool bdue = false;   // a move came due in the last clock of a jerk phase whose r the next phase replaced
    bool owe = false;     // the pending move's length is still to be taken off r (no move due)
    uint32_t kind = 0;
    uint32_t tleft = 0, tcnt = 0;
    int64_t u = 0, h = 0, step = 0;   // u, H, the step S
    // p minus the pending move's length (times 2^S), signed in rw() bits; -1 after
    // reset and clear: nothing due until a phase starts from rest or loads r.
    bits::i128 r = -1;
    bool nvalid = false;
    uint32_t nkind = 0, nticks = 0;
    int64_t nu = 0;
    uint64_t np = 0, ns = 0, nh = 0;   // r, S, H as written (64 bits each)
  };
  bits::i128 threshold() const;
  Params p_;
  Regs r_;
  uint64_t loads_ = 0;
};

}  // namespace cpstep::model

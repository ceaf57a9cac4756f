// SPDX-License-Identifier: MIT
// Homing (docs/HOST.md "Homing"): each axis with [axes.X.home], in the order of its
// sequence, runs the cycle LinuxCNC and Grbl users know, on the card's seek
// (docs/CORE.md "Seek: homing and probing"): a fast approach toward its limit switch
// that the card ends at the switch's trip (CONFIG field 10, mode 3: no LIMIT fault,
// no move after the trip, the counters hold the pulse count at it), FLUSH, back off,
// a slow approach the same way, the trip's count taken as the switch's position,
// back off. The card's counters are not rewritten: the host keeps each axis's
// offset (machine steps = count - offset), as LinuxCNC's motion module does.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "card/card_client.h"
#include "card/caps.h"
#include "plan/common.h"
#include "plan/gcode.h"
#include "plan/machine.h"

namespace cpstep::run {

// One approach or back-off: the card's counts before and after, whether the seek
// tripped.
struct HomeMove {
  std::string what;      // "search", "backoff", "latch", "clear" (off a switch already closed), "final"
  int64_t from = 0, to = 0;
  bool tripped = false;
};

struct HomedAxis {
  int axis = 0;
  int64_t search_trip = 0;   // the card's count at the fast approach's trip
  int64_t latch_trip = 0;    // and at the slow approach's: the switch at position_mm
  int64_t offset = 0;        // machine steps = count - offset
  int64_t final_count = 0;   // the card's count at the end (backed off)
  double final_mm = 0;       // the same in machine mm
  std::vector<HomeMove> moves;
};

struct HomeResult {
  std::vector<HomedAxis> axes;  // in the order homed
  std::string error;            // "" when every axis homed
  [[nodiscard]] bool ok() const { return error.empty(); }
};

// Plans `job` (its blocks from where the card stands, its counters read as absolute
// steps) on `m` for the card, arms the seek (card::seek_mode; off: none), sends it and
// waits for its end or its trip; after a seek (or a run that did not end) FLUSHes the
// rest, then reads whether it tripped. Shared by homing and probing.
struct BlocksRun {
  bool tripped = false;
  std::vector<int32_t> positions;  // the card's counters at the end (or the trip)
  uint32_t moves = 0;              // move events the card made
  std::string error;               // a planning error, a card fault, a run past its time
};
BlocksRun run_blocks(card::CardClient& c, const plan::Machine& m, const card::CardCaps& caps, const plan::Job& job,
                     uint32_t seek);

// The axes that home, in their order (sequence, then x, y, z, a).
std::vector<int> homing_order(const plan::Machine& m);

// Checks that the machine can home on this card: some axis has [axes.X.home], the
// card has inputs. "" when it can, else why not.
std::string homing_refusal(const plan::Machine& m, const card::CardCaps& caps);

// Runs the homing cycle on the card behind `c` (freshly polled; its counters as they
// stand), `m` bound to the card (run::load_card_machine). Stops at the first error
// (a switch not found within 1.5 travels, still closed after backing off, a card
// fault), leaving the card stopped and flushed; each move is in the result.
HomeResult home_axes(card::CardClient& c, const plan::Machine& m, const card::CardCaps& caps);

// `cpstep home` on the simulated card (docs/SIM.md): a freshly reset card of `board`
// (its engine as for `cpstep run`), switches placed where each axis's
// home.sim_switch_mm says (measured from the start, counters 0), driven from the
// STEP/DIR pins as the simulated machine moves; the machine file loaded for that card.
struct SimHomeSwitchTrip {
  int axis = 0;
  uint64_t cycle = 0;   // the switch's pin went active (the simulated machine reached it)
  int64_t pins = 0;     // the axis's position on the pins then
};
struct SimHomeRun {
  HomeResult result;
  plan::Machine machine;            // as bound to the card
  plan::PerAxis<int64_t> switch_at{};  // each homed axis's simulated switch, steps
  plan::PerAxis<int64_t> pins{};       // positions counted on the STEP/DIR pins at the end
  plan::PerAxis<int64_t> counts{};     // the card's counters at the end
  std::vector<SimHomeSwitchTrip> trips;
  uint64_t cycles = 0;
  std::string error;                // setup errors (machine file, board): nothing ran
};
SimHomeRun home_on_sim(const std::string& machine_file, std::string_view board, std::string_view engine);

// Probing (docs/HOST.md "Probing"): a G-code job with G38.2..G38.5 moves, run on the
// simulated card: the program read whole first (refused whole, nothing sent, on any
// error), then again with each probe move handed to the card: the blocks before it
// run, the probe must not already be in the trip state, the move runs with the seek
// armed (mode 1 for contact, 2 for its loss), the card stops at the trip, and the
// program goes on from the card's counts there with #5061..#5064 and #5070 set. The
// simulated probe is a plane across one axis (inputs.sim_probe_mm), in contact on its
// far side from the start.
struct ProbeEvent {
  plan::SourceLoc loc;
  std::string code;                    // "G38.2", ...
  bool tripped = false;
  plan::PerAxis<int64_t> counts{};     // the card's counters where it stopped
  plan::PerAxis<double> at{};          // the same in machine mm
};
struct SimProbeRun {
  std::vector<ProbeEvent> probes;
  plan::Machine machine;
  plan::PerAxis<int64_t> counts{}, pins{};
  std::vector<SimHomeSwitchTrip> contacts;  // each time the simulated probe made contact
  int64_t probe_at = 0;                // the probe's plane, steps
  uint64_t moves = 0, cycles = 0;
  std::string error;                   // setup (machine file, board, missing sim_probe_mm): nothing ran
  std::vector<plan::Diagnostic> errors, warnings;  // the program's (a probe's failure among them)
  [[nodiscard]] bool ok() const { return error.empty() && errors.empty(); }
};
SimProbeRun probe_job_on_sim(const std::string& gcode_file, const std::string& machine_file, std::string_view board,
                             std::string_view engine);
// True when the job's text has G38 words (plan::has_probe_words): it runs as a probing job.
bool job_probes(const std::string& gcode_file);

}  // namespace cpstep::run

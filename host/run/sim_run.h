// SPDX-License-Identifier: MIT
// Runs a CardJob on the simulated card (cp_card: the SPI front end and the
// motion core; the fast engine, the Verilated RTL or both in lockstep, Engine)
// through its SPI pins, and records what its pins and counters did: the
// transport `sim` of `cpstep run`.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "card/card_client.h"
#include "card/link.h"
#include "card/protocol.h"
#include "plan/common.h"
#include "run/feed.h"
#include "run/card_job.h"
#include "run/torch.h"

namespace cpstep::run {

// Host-side checks that fail a run, beside the card's own error codes
// (1..14, docs/CORE.md). Numbered from 100 so the two never collide.
enum class HostFault : uint32_t {
  position = 101,    // position_o differs from the plan at the end of a card segment
  move_count = 102,  // the card made a different number of move events than planned
  pin_count = 103,   // the STEP/DIR edges counted on the pins differ from position_o
  timeout = 104,     // the card was still running after the cycle budget
  stall = 105,       // the card stopped taking command words while stopped
  link = 106,        // the card refused a frame the host does not repair, or stopped answering
  late = 107,        // the card stretched moves: they fired after their planned cycle
  engine = 108,      // --engine lockstep: the fast engine and the Verilated card differed
  torch = 109,       // the torch pin switched other than the plan says (docs/CORE.md "Torch")
  source = 110,      // the job's G-code file was written over after it was planned: no more was sent
};

// What simulates the card (docs/SIM.md "Engines"): the fast engine (the golden
// model advanced event to event), the Verilated RTL, or both in lockstep.
enum class Engine { model, rtl, lockstep };
const char* engine_name(Engine e);
// "model", "rtl", "lockstep"; nullopt for anything else.
std::optional<Engine> parse_engine(std::string_view name);
const char* host_fault_name(HostFault f);

struct Fault {
  uint32_t code = 0;
  std::string name;
  std::string message;
};

// Leading STEP edges of one axis, as seen on the pins.
struct AxisPulses {
  std::vector<uint64_t> cycles;   // the cycle each leading edge shows on the pin
  std::vector<int8_t> dirs;       // +1 / -1 from the DIR pin at that edge
};

// What went over the SPI link.
struct LinkReport {
  std::string transport;       // "sim", "spidev"
  std::string link;            // what Link::name() says (the device)
  card::LinkStats stats;
  double sck_hz = 0;           // the SCK rate
  unsigned sck_div = 0;        // sim: clock cycles per SCK period (0 on a real link)
  uint64_t busy_cycles = 0;    // sim: clock cycles spent in transfers (CS setup to idle)
  double seconds = 0;          // on the link's clock, from the first POLL to the final reply
};

struct CardRun {
  uint64_t start_cycle = 0;              // the cycle START was taken in
  uint64_t move_events = 0;              // move events seen on the pins
  // Recorded only with SimRunOptions::record_pins (tests): per move event the
  // cycle it fired (pin edge - 1), and each axis's leading STEP edges.
  std::vector<uint64_t> move_cycles;
  plan::PerAxis<AxisPulses> pulses;
  uint64_t checked_segments = 0;         // checkpoints reached and compared
  uint64_t position_mismatches = 0;
  plan::PerAxis<int64_t> position{};     // position_o read back at the end
  card::Status status{};                 // read back at the end
  uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
  uint64_t cycles = 0;                   // clock cycles from reset to the end of motion
  uint64_t sim_cycles = 0;               // clock cycles simulated in all (the final POLL included)
  Engine engine = Engine::model;         // what simulated the card
  uint64_t skipped_cycles = 0;           // model: cycles advanced by event skipping
  bool pins_observed = true;             // false on a real card: pulses, move_cycles, checks empty
  plan::PerAxis<int64_t> start_position{};  // the card's position before the job (0 after a reset)
  LinkReport link;
  std::vector<TorchEdge> torch;          // the torch pin's changes, cycles from START (pin time)
  TorchVerdict torch_verdict;            // the torch pin against the plan
  std::vector<Fault> faults;             // the card's, then the host's
  // Feed hold / override (docs/CORE.md "Feed hold and override"): what the host sent
  // and when the card took it; scaled: the card's time ran at other than 100 % (the
  // planned times then do not apply; positions and move counts still do).
  std::vector<FeedApplied> feed;
  bool feed_scaled = false;

  [[nodiscard]] bool ok() const { return faults.empty(); }
};

class RunMeter;

struct SimRunOptions {
  Engine engine = Engine::model;    // what simulates the card
  // Every move event and STEP edge kept in the CardRun (memory grows with the
  // job: about 30 bytes a move), and/or fed as it happens to a meter that
  // measures the run in bounded memory (run/measure.h; `cpstep run` does that).
  bool record_pins = true;
  RunMeter* meter = nullptr;
  std::string board;                // rtl/builds.json's board to simulate; "": the job's (job.caps)
  std::string fst;                  // rtl: an FST waveform of every RTL signal ("" for none)
  std::string vcd;                  // "" for none: step_<axis>, dir_<axis> per pin
  uint64_t max_cycles = 0;          // 0: twice the planned job time plus 10^7
  unsigned sck_div = 8;             // clock cycles per SCK period (8 or more)
  card::ClientOptions client;       // frames, polling (axes is set to the card's)
  // The card's watchdog for the job (docs/CORE.md "Watchdog"): set before it, kept
  // alive by a frame at least every quarter of it, off again at its end; 0: off.
  double watchdog_s = 0;
  // Feed (cards with FEED): the override from the job's start (100: none sent),
  // events at times from START, and a toggle source (cpstep run: SIGUSR1) asked
  // while the host waits, true once per toggle (HOLD, then RESUME, ...).
  double override_pct = 100;
  std::vector<FeedEvent> feed;
  std::function<bool()> feed_toggle;
  // Called with (moves done, moves planned) about every 65536 cycles.
  std::function<void(uint64_t, uint64_t)> progress;
  // Tests: every cycle's STEP and DIR pins (bit i: axis i).
  std::function<void(uint64_t cycle, uint32_t step, uint32_t dir)> pins;
  // Tests: a link put between the client and the card (e.g. one that damages
  // bytes in flight); it forwards to the link it is given.
  std::function<std::unique_ptr<card::Link>(card::Link&)> wrap_link;
};

// Resets the simulated card, sends the job's words to it in SPI frames
// (card::CardClient over the pin-level master), runs it to its end and takes
// the final state from a POLL reply, while watching its pins every cycle.
// Throws std::runtime_error when the VCD cannot be written.
// First it reads the card's capabilities (READ 0x1F, 0x20..0x25) and refuses,
// with a LINK fault and nothing sent, a card other than the one the job was
// planned for (job.caps). The card simulated is the board options.board names
// (rtl/builds.json), or else the build the job was planned for.
// Throws std::invalid_argument for a board that is not in rtl/builds.json.
// With Engine::lockstep, the first cycle the engines differ in ends the run with
// an ENGINE fault naming it, and the run is made again on the Verilated card
// alone up to that cycle with an FST waveform (options.fst, or
// cpstep-engine-mismatch.fst) for the fault to point at.
CardRun run_on_sim(const CardJob& job, const SimRunOptions& options);

// The card's watchdog around a job (docs/CORE.md "Watchdog"), for both runners: the
// CONFIG that sets it, sent before the job's words (none for 0 s; watchdog_units throws
// std::invalid_argument for a timeout the field cannot hold), the client options
// that keep it alive (a frame at least every quarter of it), and, after the run,
// with the card stopped, the CONFIG that turns it off, so that a host that ends
// cleanly leaves no watchdog to run out. A card still running keeps it.
std::vector<uint32_t> watchdog_words(const CardJob& job, double watchdog_s);
card::ClientOptions keeping_alive(card::ClientOptions client, double watchdog_s);
void watchdog_off(card::CardClient& client, double watchdog_s, const card::CardClient::KeepWaiting& keep);

// The board run_on_sim() simulates for this job and these options.
std::string sim_board_for(const CardJob& job, const SimRunOptions& options);

// Connects to a freshly reset simulated card of this board through its SPI pins
// and reads its capabilities: what `cpstep run` plans with.
card::CardCaps connect_sim(std::string_view board, Engine engine = Engine::model);

// The parts of a run shared by every transport.
Fault host_fault(HostFault f, std::string message);
// SOURCE's message: the change (JobFileChanged::what()) and how far the words went.
std::string changed_file_fault(const JobFileChanged& e, const WordSource& words);
// SOURCE for a run whose job's file was written over while it ran: the words
// stopped where the change begins; the card is stopped (run::stop_short: held
// to a stand and flushed when it has FEED, the HOLD added to run.feed), and the
// fault says what changed, how far the words went and how the card stopped.
Fault stop_for_changed_file(const JobFileChanged& e, const WordSource& words, card::CardClient& client,
                            const card::CardClient::KeepWaiting& keep_waiting,
                            const std::function<std::optional<double>()>& since_start_s, CardRun& run);
// Status, counters and positions from the card's reply (positions absolute).
void take_reply(CardRun& run, const card::Reply& reply);
// The card's own fault first, then MOVE_COUNT (the card's counter, and the pins
// when observed) against the plan.
void add_card_faults(const CardJob& job, CardRun& run);
// "x=1 y=2 z=3" over the machine's axes.
std::string axes_text(const plan::PerAxis<int64_t>& p, const plan::Machine& m);

}  // namespace cpstep::run

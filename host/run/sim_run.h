// Runs a CardJob on the simulated card (the Verilated cp_core) and records
// what its pins and counters did: the transport `sim` of `cpstep run`.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "card/protocol.h"
#include "plan/common.h"
#include "run/card_job.h"

namespace cpstep::run {

// Host-side checks that fail a run, beside the card's own error codes
// (1..14, docs/CORE.md). Numbered from 100 so the two never collide.
enum class HostFault : uint32_t {
  position = 101,    // position_o differs from the plan at the end of a card segment
  move_count = 102,  // the card made a different number of move events than planned
  pin_count = 103,   // the STEP/DIR edges counted on the pins differ from position_o
  timeout = 104,     // the card was still running after the cycle budget
  stall = 105,       // the card stopped taking command words while stopped
};
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

struct CardRun {
  uint64_t start_cycle = 0;              // the cycle START was taken in
  std::vector<uint64_t> move_cycles;     // per move event: the cycle it fired (pin edge - 1)
  plan::PerAxis<AxisPulses> pulses;
  uint64_t checked_segments = 0;         // checkpoints reached and compared
  uint64_t position_mismatches = 0;
  plan::PerAxis<int64_t> position{};     // position_o read back at the end
  card::Status status{};                 // read back at the end
  uint32_t stretch_count = 0, moves_done = 0, segments_done = 0;
  uint64_t cycles = 0;                   // clock cycles from reset to the end of motion
  std::vector<Fault> faults;             // the card's, then the host's

  [[nodiscard]] bool ok() const { return faults.empty(); }
};

struct SimRunOptions {
  std::string vcd;                  // "" for none: step_<axis>, dir_<axis> per pin
  uint64_t max_cycles = 0;          // 0: twice the planned job time plus 10^7
  // Called with (moves done, moves planned) about every 65536 cycles.
  std::function<void(uint64_t, uint64_t)> progress;
};

// Sends the job's words to a freshly reset card, runs it to its end and reads
// its registers back. Throws std::runtime_error when the VCD cannot be written.
CardRun run_on_sim(const CardJob& job, const SimRunOptions& options);

}  // namespace cpstep::run

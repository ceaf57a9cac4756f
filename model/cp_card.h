// SPDX-License-Identifier: MIT
// cp_card — cycle-accurate, bit-exact model of rtl/cp_card.v, the card without
// its board: the SPI front end (CpSpi) feeding the motion core (CpCore), and the
// E-stop input's two-flop synchronizer.
// Same ports as the RTL; the bench sets `in`, reads outputs() (the pins before the
// rising edge), then calls tick() (the edge). No heap allocation per cycle.
//
// A cycle settles in the RTL's order: the registered values first (the E-stop
// synchronizer; cp_spi's command buffer head and its read-port address), then the
// core's outputs for them (cmd_ready, the READ reply's valid and address, rd_data
// for that address, the pins), then cp_spi's next state from those.
#pragma once

#include <array>
#include <cstdint>

#include "cpstep/builds.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "model/cp_inputs.h"
#include "model/cp_spi.h"

namespace cpstep::model {

struct CpCardParams {
  // The core's parameters; core.cbuf_aw is also the command buffer's address
  // width, core.n the axes. The card's position counters are 32 bits (PW = 32).
  CpCoreParams core;
};

// The model's parameters for a build of rtl/builds.json.
constexpr CpCardParams card_params(const builds::Build& b) { return {core_params(b)}; }

struct CpCardIn {
  bool rst = false;
  bool sck = false, cs_n = true, mosi = false;  // SPI pins (asynchronous)
  bool estop = false;                           // raw E-stop input, active high
  // Limit switches (bit a: axis a) and the probe, raw (docs/CORE.md "Inputs").
  uint32_t lim_min = 0, lim_max = 0;
  bool probe = false;
};

// `cycles` clocks with the pins `pins`; `sample`: the master samples MISO in the
// first (the SPI master's schedule of a transfer, host/sim/spi_master.h).
struct CpPinPhase {
  CpCardIn pins;
  uint64_t cycles = 0;
  bool sample = false;
};

struct CpCardOut {
  bool miso = false, miso_oe = false;
  uint32_t step = 0, dir = 0;  // bit i: axis i's pin
  bool torch = false;          // the torch output (docs/CORE.md "Torch")
  bool enable = false, running = false, fault = false, stretched = false;
  uint32_t err_code = 0;
  std::array<int32_t, kCoreMaxAxes> position{};
};

class CpCard {
 public:
  using Params = CpCardParams;
  using In = CpCardIn;
  using Out = CpCardOut;

  explicit CpCard(Params params = {});

  In in;

  Out outputs() const;
  void tick();

  // Event skipping (docs/SIM.md "Engines"): how many clocks from now, with the
  // pins of `in` held, change nothing but the core's counters — every
  // synchronizer settled, the SPI front end between edges with no READ reply to
  // take and no word on its way through the buffer, and the core quiet
  // (CpCore::quiet_for) — at most `limit`; 0: clock this one normally. skip(n)
  // advances n <= quiet_for() clocks at once, to exactly the state n tick()s
  // would leave.
  uint64_t quiet_for(uint64_t limit) const;
  void skip(uint64_t cycles);
  // The fast engine's frames: `cycles` clocks with the pins of `in`, CS low, in
  // which only the SPI front end works — the core quiet through all of them
  // (CpCore in lazy mode has found it so), the E-stop settled, CS low in every
  // synchronizer stage (no frame can end, so nothing commits) and no committed
  // word on its way to the core. Clocks the front end
  // alone, skips the core, and returns true, with *miso the MISO of the first
  // clock; false, having done nothing, when that cannot be promised.
  bool clock_front_end(uint64_t cycles, bool* miso);
  // The same over a transfer's phases from the first on, for as long as their CS
  // stays low and the core's quiet lasts: returns how many phases it clocked (0:
  // none), `in` left as the last one's pins, miso[k] the MISO of phase k's first
  // clock.
  size_t clock_front_end(const CpPinPhase* phases, size_t n, uint8_t* miso);

  const Params& params() const { return p_; }
  const CpCore& core() const { return core_; }
  // Changing the core through this reference between outputs() and tick() is seen by tick().
  CpCore& core() {
    core_valid_ = false;
    return core_;
  }
  const CpSpi& spi() const { return spi_; }
  // The E-stop as the core and the reply see it (the synchronizer's second flop).
  bool estop_synced() const { return (estop_q_ >> 1 & 1) != 0; }
  // Every synchronizer (SPI pins, E-stop) holds what the pins of `in` load into
  // it: another cycle with the same pins changes none of them.
  bool pins_settled() const {
    return spi_.pins_settled(in.rst, in.sck, in.cs_n, in.mosi) && slow_pins_settled(in);
  }
  // The E-stop's and the inputs' synchronizers hold the pins of `i`.
  bool slow_pins_settled(const In& i) const {
    return estop_q_ == (i.estop ? 3u : 0u) && in_q0_ == in_word(i) && in_q1_ == in_word(i);
  }

 private:
  // The core's outputs for this cycle: its inputs are the front end's registered
  // outputs, the synchronized E-stop and rst. Computed once per cycle (outputs()
  // and tick() share it while rst is unchanged).
  const CpCoreOut& core_outputs() const;

  Params p_;
  CpSpi spi_;
  // The core's `in` is a wire of the card, set while settling; hence mutable.
  mutable CpCore core_;
  uint32_t estop_q_ = 0;  // [0] first flop, [1] the synchronized level
  // The inputs' synchronizer, {probe, max[N], min[N]}: first flop, second (the core's).
  uint32_t in_q0_ = 0, in_q1_ = 0;
  uint32_t in_word(const In& i) const { return pack_inputs(p_.core.n, i.lim_min, i.lim_max, i.probe); }
  mutable CpCoreOut core_out_{};
  mutable bool core_valid_ = false;
  mutable bool rd_stale_ = false;  // core_out_ holds but for rd_data (clock_front_end)
};

}  // namespace cpstep::model

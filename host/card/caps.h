// SPDX-License-Identifier: MIT
// What a card says of itself: the capability registers (READ 0x1F, 0x20..0x26,
// docs/CORE.md), read at connect, and what the host plans with from them.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <string>

#include "card/protocol.h"
#include "cpstep/builds.h"

namespace cpstep::card {

// The command set, register map and frame version this host speaks.
constexpr unsigned kProtocolVersion = 2;

// The registers read at connect, in order.
constexpr std::array<Register, 8> kCapsRegisters = {Register::id,        Register::caps,
                                                   Register::pattern_capacity, Register::umax,
                                                   Register::caps2,     Register::clock_hz,
                                                   Register::build_id,  Register::conic_width};

struct CardCaps {
  uint32_t id = 0;                 // 0x1F: "CPS1"
  unsigned n = 0, kmax = 0;        // 0x20: axes, largest doubling exponent
  unsigned caw = 0, saw = 0, tw = 0;  //       chunk and segment queue address widths, timing field width
  uint32_t w = 0, umax = 0;        // 0x21, 0x22
  unsigned pw = 0, cbuf_aw = 0, protocol = 0;  // 0x23: position width, command buffer, version
  uint32_t clock_hz = 0;           // 0x24
  uint32_t build_id = 0;           // 0x25
  unsigned ciw = 0;                // 0x26: the conic walker's width; 0: no CONIC segments
  bool inputs = false;             // 0x23 [24]: limit and probe inputs (docs/CORE.md "Inputs")
  bool feed = false;               // 0x23 [25]: feed hold and override (docs/CORE.md "Feed hold and override")
  bool ptimer = false;             // 0x23 [26]: moves timed by the phase timer, no chunks (docs/CORE.md
                                   //   "Phase-timer builds"); this host does not plan for it yet

  [[nodiscard]] unsigned chunk_queue() const { return 1u << caw; }
  [[nodiscard]] unsigned segment_queue() const { return 1u << saw; }
  [[nodiscard]] unsigned command_buffer_words() const { return cbuf_aw ? 1u << cbuf_aw : 0; }
  // Largest pulse timing value in cycles (a TW-bit field).
  [[nodiscard]] uint32_t max_timing_cycles() const { return tw >= 32 ? UINT32_MAX : (1u << tw) - 1; }
  friend bool operator==(const CardCaps&, const CardCaps&) = default;
};

// From the registers' values, in kCapsRegisters order.
CardCaps decode_caps(const std::array<uint32_t, kCapsRegisters.size()>& values);
// What a card of this build reports (the table rtl/builds.json; for planning
// without a card: `cpstep plan --board`).
CardCaps caps_of(const builds::Build& b);
// The build of rtl/builds.json with this card's build id, or nullptr.
const builds::Build* build_of(const CardCaps& caps);
// "icebreaker (build b5ca169b)" or "an unknown build 12345678".
std::string card_name(const CardCaps& caps);
// The caps of the default board's build (rtl/builds.json's default_board).
CardCaps default_caps();
// The caps of the board named `name`; nullopt when rtl/builds.json has no such board.
std::optional<CardCaps> board_caps(std::string_view name);
// "icebreaker, hx8k"
std::string board_names();
// One line: axes, W, UMAX, KMAX, queues, TW, clock.
std::string describe(const CardCaps& caps);
// Why the host cannot drive this card ("" when it can): not a cpstep card,
// another protocol version, another number of axes than the host's segments carry,
// impossible capabilities.
std::string unusable(const CardCaps& caps, unsigned axes);

}  // namespace cpstep::card

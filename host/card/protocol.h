// SPDX-License-Identifier: MIT
// The card's command words (docs/CORE.md), built from values.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace cpstep::card {

struct WireChunk {
  uint32_t interval = 0;  // cycles before the chunk's first move (>= 1)
  uint16_t count = 0;     // moves in the chunk (>= 1)
  int16_t add = 0;        // interval change per move
  int16_t add2 = 0;       // change of add per move: move j comes interval + j*add +
                          // add2*j*(j-1)/2 cycles after the previous one
  friend bool operator==(const WireChunk&, const WireChunk&) = default;
};

struct WireSegment {
  uint32_t u = 0;                 // U: moves before doubling (1..UMAX)
  unsigned k = 0;                 // doubling exponent: U * 2^k moves
  bool end = false;               // the run ends cleanly after this segment
  bool torch = false;             // H0[16]: the torch output while it runs (docs/CORE.md "Torch")
  std::vector<bool> dir_positive; // per axis
  std::vector<uint32_t> v;        // per axis, v_i <= U (U on the major axis)
  std::vector<WireChunk> chunks;  // counts sum to U * 2^k
  // Set: a CONIC segment (opcode 5) of T = U moves (k = 0) whose axes u, v step by
  // the walk these seven words load (K0..K6 of docs/CORE.md "CONIC"; K1's [31:16]
  // are sent as 0); v is 0 for those two axes.
  // With `cont` (H0[18]) the walk goes on from where the previous segment's, a
  // CONIC on the same axes and way, ended: only K5 and K6 (the end from there) are
  // sent; the card refuses it after anything else (CONIC_CONTINUE, 18).
  struct Conic {
    bool cw = false;
    unsigned axis_u = 0, axis_v = 1;
    std::array<uint32_t, 7> words{};
    bool cont = false;
  };
  std::optional<Conic> conic;
  // Set: a segment for a card that times moves by the phase timer (READ 0x23 [26];
  // docs/PROTOCOL.md "Toward a compact wire"): no chunks (`chunks` is not sent),
  // H0[15:0] its axis form (axis_form: v words only for the axes that move but the
  // first whose v = U), and after its words its length per move, Q2.30 of the
  // phases' path unit, not 0.
  std::optional<uint32_t> length;
};

// A PHASE command (opcode 6, phase-timer cards): one phase of constant jerk of
// rtl/cp_ptimer.v. kind: bit 0 load r, 1 a timed move, 2 from rest, 3 load S and
// H; H0 = {6, kind, ticks}, then u, r's top 64 bits (kind bit 0), S and H (kind
// bit 3), low words first.
struct WirePhase {
  unsigned kind = 0;
  uint32_t ticks = 0;        // 24 bits: ticks of 2^6 timer clocks (a timed move: clocks); 0 = 1
  int32_t u = 0;             // a sixth of the jerk (24 bits)
  uint64_t r_top = 0;
  int64_t s = 0, h = 0;      // the step (56 bits) and H (40 bits)
};
void encode_phase(const WirePhase& p, std::vector<uint32_t>& out);

// A CONIC segment (docs/CORE.md "CONIC"): T moves; axes u and v step by the conic
// walk from the start node (G and its gradient there, in the curve's step units) to
// the end node (du, dv from the start); every other axis by its pattern v_i over T.
struct WireConic {
  uint32_t t = 0;                 // moves (1..UMAX)
  bool end = false;
  bool torch = false;             // H0[16]: the torch output while it runs
  bool cw = false;                // clockwise: G > 0 on the left of travel
  unsigned axis_u = 0, axis_v = 1;
  std::vector<bool> dir_positive; // per axis (those of u and v are not used)
  std::vector<uint32_t> v;        // per axis, v_i <= T; 0 for u and v
  int32_t a = 0, b = 0, c = 0;    // 16 bits each
  int32_t g = 0, gx = 0, gy = 0;  // at the start node
  int32_t du = 0, dv = 0;         // 24 bits each
  bool cont = false;              // continues the last walk (H0[18]): only du, dv sent
  std::vector<WireChunk> chunks;  // counts sum to T
};

// CONFIG's fields: 0..4 an axis's pulse timing and polarity; 5 the card's watchdog
// timeout in units of kWatchdogUnit clocks, 0 = off (docs/CORE.md "Watchdog"); on a
// card with inputs (docs/CORE.md "Inputs"): 6 the input filter's sample period in
// clocks, 7 an axis's limits (bit 0 min active high, 1 max active high, 2 min
// enabled, 3 max enabled), 8 the probe (bit 0 active high).
enum class ConfigField : uint32_t {
  step_high = 0,
  step_low = 1,
  dir_setup = 2,
  dir_hold = 3,
  polarity = 4,
  watchdog = 5,
  input_filter = 6,
  limits = 7,
  probe = 8,
  // Feed hold and override (cards with FEED): the ramp's tick period in clocks
  // (docs/CORE.md "Feed hold and override").
  feed_tick = 9,
  // The seek (cards with inputs, docs/CORE.md "Seek: homing and probing"): the run
  // ends when an input trips; value seek_mode (0 off).
  seek = 10,
};
// CONFIG field 10's modes: trip on the probe active (G38.2/G38.3), on the probe
// inactive (G38.4/G38.5), on a limit hit toward the motion (homing: no LIMIT fault).
namespace seek_mode {
constexpr uint32_t off = 0, probe_contact = 1, probe_loss = 2, limit = 3;
}
// READ 0x27's seek bits.
namespace inputs_bits {
constexpr uint32_t probe = 1u << 16;
constexpr uint32_t seek_mode_shift = 17;  // [18:17]
constexpr uint32_t tripped = 1u << 19;
}
namespace limit_bits {
constexpr uint32_t min_active_high = 1, max_active_high = 2, min_enabled = 4, max_enabled = 8;
}
constexpr uint32_t kWatchdogUnit = 4096;  // clocks

enum class Register : uint32_t {
  status = 0x00,
  stretch_count = 0x01,
  moves_done = 0x02,
  segments_done = 0x03,
  position0 = 0x10,
  id = 0x1F,
  caps = 0x20,          // [7:0] N, [15:8] KMAX, [19:16] CAW, [23:20] SAW, [28:24] TW
  pattern_capacity = 0x21,  // W
  umax = 0x22,          // UMAX
  caps2 = 0x23,         // [7:0] PW, [15:8] CBUF_AW (0: no command buffer), [23:16] protocol version
  clock_hz = 0x24,      // the card clock in Hz
  build_id = 0x25,      // the build id (rtl/builds.json)
  conic_width = 0x26,   // the conic walker's width CIW; 0: no CONIC segments
  inputs = 0x27,        // active now: [7:0] limit min per axis, [15:8] max, [16] probe;
                        // the seek: [18:17] its mode (0 off), [19] tripped
  limits_at = 0x28,     // the limits active when LIMIT (20) latched: [7:0] min, [15:8] max
  feed = 0x29,          // [31] held, [30] settled on its target, [15:0] the timer's scale s (Q2.14)
  feed_override = 0x2A, // [15:0] the override (Q2.14)
};
constexpr uint32_t kCardId = 0x43505331;  // "CPS1"

// A phase-timer segment's compact axis form, H0[15:0] = {1, 000, major valid,
// major[2:0], sent[7:0]}: the first axis whose v = U (not 0) is the major one, its v
// not sent (the card takes it as U); the other axes that move are sent, in axis
// order; an axis in neither has v = 0.
uint32_t axis_form(const WireSegment& s);

// Appends the words of each command to `out`. A segment's chunks are two words
// each, or three (with add2, header bit 22) when some chunk has add2 != 0. A
// phase-timer segment (`length` set) in its compact axis form, or with every
// axis's v (H0[15:0] = 0) if `every_axis`.
void encode_segment(const WireSegment& s, std::vector<uint32_t>& out, bool every_axis = false);
void encode_conic(const WireConic& s, std::vector<uint32_t>& out);
void encode_config(unsigned axis, ConfigField field, uint32_t value, std::vector<uint32_t>& out);
// The watchdog field's value for a timeout of `seconds` on a card clocked at
// `clock_hz`: whole units, rounded up (0 s: 0, off). Throws std::invalid_argument
// for a negative timeout or one past the field's 65,535 units.
uint32_t watchdog_units(double seconds, uint32_t clock_hz);
// CONFIG field 5: the watchdog set to `seconds` (watchdog_units; 0 turns it off).
void encode_watchdog(double seconds, uint32_t clock_hz, std::vector<uint32_t>& out);
void encode_control(bool start, bool abort, bool clear, std::vector<uint32_t>& out);
// CONTROL bit 3 (drivers on) or bit 4 (drivers off): the card's ENABLE pins.
void encode_drivers(bool on, std::vector<uint32_t>& out);
void encode_read(Register r, unsigned axis, std::vector<uint32_t>& out);

// How many words the command whose first word is `first` has, on a card of
// `axes` axes (a SEGMENT: 2 + axes + 2 or 3 words per chunk; a CONIC 7 more; others
// one). On a phase-timer card (`ptimer`): a segment has no chunks but its L, and v
// words as its axis form says; a PHASE 2 to 8 words.
size_t command_words(uint32_t first, unsigned axes, bool ptimer = false);

// Status word fields.
struct Status {
  bool running, fault, stretched, estop;
  uint32_t err_code, segments_queued, chunks_queued;
  bool drivers_enabled;
  // Feed (cards with FEED): HOLD taken and no RESUME since; the timer's scale is
  // still ramping to its target (held and not ramping: the motion stands).
  bool held = false, feed_ramping = false;
};
Status decode_status(uint32_t word);

// The card's error codes (docs/CORE.md, "Validation: whole segments or nothing")
// by name, e.g. "UNDERRUN", with a one-line meaning; "UNKNOWN" past the table.
struct ErrorName {
  const char* name;
  const char* meaning;
};
ErrorName error_name(uint32_t code);

}  // namespace cpstep::card

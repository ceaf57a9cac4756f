// SPDX-License-Identifier: MIT
#include "card/caps.h"

#include <fmt/format.h>

namespace cpstep::card {

CardCaps decode_caps(const std::array<uint32_t, kCapsRegisters.size()>& v) {
  CardCaps c;
  c.id = v[0];
  c.n = v[1] & 0xFF;
  c.kmax = v[1] >> 8 & 0xFF;
  c.caw = v[1] >> 16 & 0xF;
  c.saw = v[1] >> 20 & 0xF;
  c.tw = v[1] >> 24 & 0x1F;
  c.w = v[2];
  c.umax = v[3];
  c.pw = v[4] & 0xFF;
  c.cbuf_aw = v[4] >> 8 & 0xFF;
  c.protocol = v[4] >> 16 & 0xFF;
  c.inputs = (v[4] >> 24 & 1) != 0;
  c.feed = (v[4] >> 25 & 1) != 0;
  c.ptimer = (v[4] >> 26 & 1) != 0;
  c.clock_hz = v[5];
  c.build_id = v[6];
  c.ciw = v[7] & 0xFF;
  return c;
}

CardCaps caps_of(const builds::Build& b) {
  CardCaps c;
  c.id = kCardId;
  c.n = b.n;
  c.kmax = b.kmax;
  c.caw = b.caw;
  c.saw = b.saw;
  c.tw = b.tw;
  c.w = b.w;
  c.umax = b.umax;
  c.pw = 32;
  c.cbuf_aw = b.cbuf_aw;
  c.protocol = kProtocolVersion;
  c.clock_hz = b.clock_hz;
  c.build_id = b.build_id;
  c.ciw = b.conic ? 40 : 0;  // the walker at the RTL's default width (cp_core's CIW)
  c.inputs = b.inputs != 0;
  c.feed = b.feed != 0;
  c.ptimer = b.ptimer != 0;
  return c;
}

CardCaps default_caps() { return *board_caps(builds::kDefaultBoard); }

std::optional<CardCaps> board_caps(std::string_view name) {
  const builds::Build* b = builds::find(name);
  if (!b || !b->board) return std::nullopt;
  return caps_of(*b);
}

std::string board_names() {
  std::string s;
  for (const builds::Build* b : builds::kAll)
    if (b->board) s += (s.empty() ? "" : ", ") + std::string(b->name);
  return s;
}

const builds::Build* build_of(const CardCaps& caps) {
  for (const builds::Build* b : builds::kAll)
    if (b->build_id == caps.build_id) return b;
  return nullptr;
}

std::string card_name(const CardCaps& caps) {
  if (const builds::Build* b = build_of(caps)) return fmt::format("{} (build {:08x})", b->name, caps.build_id);
  return fmt::format("an unknown build {:08x}", caps.build_id);
}

std::string describe(const CardCaps& c) {
  return fmt::format("{}: {} axes, W {}, UMAX {}, KMAX {}, chunk queue {}, segment queue {}, TW {}, "
                     "command buffer {} words, clock {} Hz, protocol {}",
                     card_name(c), c.n, c.w, c.umax, c.kmax, c.chunk_queue(), c.segment_queue(), c.tw,
                     c.command_buffer_words(), c.clock_hz, c.protocol) +
         (c.ciw ? fmt::format(", conic walker {} bits", c.ciw) : std::string()) +
         (c.inputs ? ", limit and probe inputs" : "") +
         (c.feed ? ", feed hold and override" : "") + (c.ptimer ? ", moves timed by the phase timer" : "");
}

std::string unusable(const CardCaps& c, unsigned axes) {
  if (c.id != kCardId) return fmt::format("the card's id register reads {:08x}, not a cpstep card ({:08x})", c.id, kCardId);
  if (c.protocol != kProtocolVersion)
    return fmt::format("the card speaks protocol version {}, this host version {}", c.protocol, kProtocolVersion);
  if (c.n != axes)
    return fmt::format("the card has {} axes; this host's segments carry {} (docs/CORE.md, SEGMENT)", c.n, axes);
  if (c.w < 2 || c.umax < c.w || c.tw < 1 || c.clock_hz == 0)
    return fmt::format("the card reports impossible capabilities ({})", describe(c));
  return "";
}

}  // namespace cpstep::card

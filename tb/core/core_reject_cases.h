// SPDX-License-Identifier: MIT
// The bad commands of docs/CORE.md "Validation" (codes 1–8, 12–15 and 18), one catalogue
// for every bench that sends them (tb/core/test_core_reject.cpp on the RTL cores,
// tb/netlist on the synthesized one), sized from the core's parameters.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "card/protocol.h"
#include "core/core_bench.h"
#include "model/cp_core_ports.h"

namespace cpstep::tb {

inline std::vector<uint32_t> words_of(uint32_t u, unsigned k, std::vector<uint32_t> v,
                                      std::vector<card::WireChunk> chunks, bool end = false) {
  card::WireSegment s;
  s.u = u;
  s.k = k;
  s.v = std::move(v);
  s.dir_positive = {true, false, true, false};
  s.chunks = std::move(chunks);
  s.end = end;
  std::vector<uint32_t> w;
  card::encode_segment(s, w);
  return w;
}
inline std::vector<uint32_t> config_word(unsigned axis, unsigned field, uint32_t value) {
  return {0x2u << 28 | axis << 24 | field << 20 | value};
}

struct BadInput {
  const char* name;
  uint32_t code;
  std::function<std::vector<uint32_t>()> words;
  bool only_while_running = false;
  // CONFIG while running is CONFIG_BUSY whatever its value.
  uint32_t code_while_running() const { return std::string(name).rfind("config", 0) == 0 ? 13 : code; }
};

inline std::vector<BadInput> bad_inputs(const model::CpCoreParams& p) {
  // One chunk more than the chunk queue holds.
  const uint32_t nmany = (1u << p.caw) + 1;
  std::vector<card::WireChunk> many(nmany, card::WireChunk{10, 1, 0});
  std::vector<BadInput> cases = {
      {"U_zero", 1, [] { return words_of(0, 0, {0, 0, 0, 0}, {{10, 1, 0}}); }},
      {"U_above_UMAX", 1, [p] { return words_of(p.umax + 1, 0, {p.umax + 1, 0, 0, 0}, {{10, 1, 0}}); }},
      {"v_above_U", 2, [] { return words_of(10, 0, {10, 0, 11, 0}, {{10, 10, 0}}); }},
      {"k_above_KMAX", 3, [p] { return words_of(2, p.kmax + 1, {2, 1, 0, 0}, {{10, uint16_t(2u << p.kmax), 0}}); }},
      {"no_chunks", 4, [] { return words_of(10, 0, {10, 3, 0, 0}, {}); }},
      {"more_chunks_than_the_queue", 4, [many, nmany] { return words_of(nmany, 0, {nmany, 3, 0, 0}, many); }},
      {"interval_zero", 5, [] { return words_of(10, 0, {10, 3, 0, 0}, {{0, 10, 0}}); }},
      {"count_zero", 5, [] { return words_of(10, 0, {10, 3, 0, 0}, {{10, 10, 0}, {10, 0, 0}}); }},
      {"delay_negative", 6, [] { return words_of(10, 0, {10, 3, 0, 0}, {{5, 10, -1}}); }},
      {"delay_reaches_zero", 6, [] { return words_of(10, 0, {10, 3, 0, 0}, {{9, 10, -1}}); }},
      {"delay_above_2pow32", 6, [] { return words_of(2, 0, {2, 1, 0, 0}, {{0xFFFFFFFFu, 2, 1}}); }},
      // add2 (three-word chunks). Increments -5 + 2i: -5, -3, -1, 1, ... change sign
      // though every delay (50, 45, 42, 41, 42, ...) is positive.
      {"add2_increments_change_sign", 15, [] { return words_of(10, 0, {10, 3, 0, 0}, {{50, 10, -5, 2}}); }},
      // Increments 4, 2, 0, -2 (delays 20, 24, 26, 26, 24).
      {"add2_increments_cross_zero", 15, [] { return words_of(5, 0, {5, 1, 0, 0}, {{20, 5, 4, -2}}); }},
      // Increments -1, -2, -3, -4: delays 10, 9, 7, 4, then 0.
      {"add2_last_delay_zero", 6, [] { return words_of(5, 0, {5, 1, 0, 0}, {{10, 5, -1, -1}}); }},
      // Delays 100 - j(j-1)/2: the 20th is 100 - 171 = -71.
      {"add2_last_delay_negative", 6, [] { return words_of(20, 0, {20, 1, 0, 0}, {{100, 20, 0, -1}}); }},
      // Increments 1, 2: the last delay 2^32 - 3 + 3 = 2^32.
      {"add2_last_delay_2pow32", 6,
       [] { return words_of(3, 0, {3, 1, 0, 0}, {{0xFFFFFFFDu, 3, 1, 1}}); }},
      // 1 + 3·65534·65533/2 = 6,441,959,434 > 2^32 - 1 (a 49-bit product).
      {"add2_last_delay_far_above_2pow32", 6,
       [] { return words_of(65535, 0, {65535, 0, 0, 0}, {{1, 65535, 0, 3}}); }},
      // 2^32 - 1 + 65534·(4·65533)/2 = 12,884,246,539: the product (count-1)·(add + last
      // increment) = 17,178,558,488 is just below 2^34 (a 34-bit signed product wraps to a
      // small negative and would pass).
      {"add2_last_delay_with_a_34_bit_product", 6,
       [] { return words_of(65535, 0, {65535, 0, 0, 0}, {{0xFFFFFFFFu, 65535, 0, 4}}); }},
      {"counts_short", 7, [] { return words_of(10, 0, {10, 3, 0, 0}, {{10, 9, 0}}); }},
      {"counts_long", 7, [] { return words_of(10, 0, {10, 3, 0, 0}, {{10, 6, 0}, {10, 5, 0}}); }},
      {"counts_U_not_U_times_2powk", 7, [] { return words_of(3, 2, {3, 1, 0, 0}, {{10, 3, 0}}); }},
      {"pattern_above_W", 8,
       [p] { return words_of(p.w + 1, 0, {p.w + 1, 1, 0, 0}, {{5, uint16_t(p.w + 1), 0}}); }},
      {"opcode_0", 12, [] { return std::vector<uint32_t>{0x00000000u}; }},
      {"opcode_6", 12, [] { return std::vector<uint32_t>{0x60000001u}; }},
      {"opcode_F", 12, [] { return std::vector<uint32_t>{0xF1234567u}; }},
      {"config_while_running", 13, [] { return config_word(0, 0, 5); }, true},
      {"config_step_high_0", 14, [] { return config_word(1, 0, 0); }},
      {"config_step_low_0", 14, [] { return config_word(2, 1, 0); }},
      {"config_axis_out_of_range", 14, [] { return config_word(4, 0, 3); }},
      {"config_unknown_field", 14, [] { return config_word(0, 11, 3); }},
      {"config_unknown_field_15", 14, [] { return config_word(0, 15, 3); }},
  };
  // Field 10 (the seek) is a CONFIG only in a core built with INPUTS = 1.
  if (!p.inputs) cases.push_back({"config_seek_field_without_inputs", 14, [] { return config_word(0, 10, 1); }});
  // Field 9 (the feed ramp's tick) is a CONFIG only in a core built with FEED = 1.
  if (!p.feed) cases.push_back({"config_feed_field_without_feed", 14, [] { return config_word(0, 9, 3); }});
  // CONIC (opcode 5) is a command only in a core built with CONIC = 1.
  if (!p.conic) cases.push_back({"opcode_5_without_conic", 12, [] { return std::vector<uint32_t>{0x50000001u}; }});
  // A CONIC continuing a walk (H0[18]) with no CONIC before it (docs/CORE.md "CONIC").
  if (p.conic)
    cases.push_back({"conic_continue_first", 18, [] {
                       card::WireConic c;
                       c.t = 10;
                       c.cont = true;
                       c.dir_positive = {true, true, true, true};
                       c.v = {0, 0, 0, 0};
                       c.du = 10;
                       c.chunks = {{100, 10, 0}};
                       std::vector<uint32_t> w;
                       card::encode_conic(c, w);
                       return w;
                     }});
  return cases;
}

template <class Harness>
void expect_stopped_with(Harness& h, uint32_t code, const std::string& where) {
  const card::Status st = h.status();
  EXPECT_TRUE(st.fault) << where;
  EXPECT_EQ(st.err_code, code) << where << ": error code";
  EXPECT_FALSE(st.running) << where;
  EXPECT_EQ(st.segments_queued, 0u) << where << ": queue not flushed";
  EXPECT_EQ(st.chunks_queued, 0u) << where << ": chunks not flushed";
  h.expect_counters(where);
}

}  // namespace cpstep::tb

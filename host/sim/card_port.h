// SPDX-License-Identifier: MIT
// Ports of rtl/cp_card.v (the card: SPI front end + motion core), and the port
// adaptor for its Verilated configurations (see dut.h). The card's golden model,
// model::CpCard, steps behind these pins as sim::CardModel (card_model.h):
// card_configs.h's CardOf<B, V> names it, so RtlDut<P>, ModelDut<P> and
// tb/common/lockstep.h's Lockstep<P> all run a card.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "model/cp_card.h"
#include "sim/dut.h"

namespace cpstep::sim {

constexpr unsigned kCardMaxAxes = 8;

// The card's inputs: rst, SCK (mode 0: idles low), CS (active low), MOSI, and
// the raw E-stop input (active high) — the golden model's own type.
using CardIn = model::CpCardIn;

struct CardOut {
  bool miso = false;
  bool miso_oe = false;  // the card drives MISO
  uint32_t step = 0, dir = 0;  // bit i: axis i's pin
  bool torch = false;          // the torch output
  bool enable = false;         // drivers enabled
  bool running = false, fault = false, stretched = false;
  uint32_t err_code = 0;
  std::array<int32_t, kCardMaxAxes> position{};
};

template <class V, unsigned N>
struct CardPortBase {
  static_assert(N >= 1 && N <= kCardMaxAxes);
  using Rtl = V;
  using In = CardIn;
  using Out = CardOut;
  static constexpr unsigned kAxes = N;

  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.spi_sck_i = i.sck;
    r.spi_cs_n_i = i.cs_n;
    r.spi_mosi_i = i.mosi;
    r.estop_i = i.estop;
    r.lim_min_i = i.lim_min;
    r.lim_max_i = i.lim_max;
    r.probe_i = i.probe;
  }
  static Out sample(const V& r) {
    Out o;
    o.miso = r.spi_miso_o;
    o.miso_oe = r.spi_miso_oe_o;
    o.step = r.step_o;
    o.dir = r.dir_o;
    o.torch = r.torch_o;
    o.enable = r.enable_o;
    o.running = r.running_o;
    o.fault = r.fault_o;
    o.stretched = r.stretched_o;
    o.err_code = r.err_code_o;
    for (unsigned a = 0; a < N; ++a) o.position[a] = int32_t(position_word(r, a));
    return o;
  }
  static const std::vector<Field<Out>>& fields() {
    static const std::vector<Field<Out>> f = [] {
      std::vector<Field<Out>> v = {
          {"spi_miso_o", [](const Out& o) { return uint64_t(o.miso); }},
          {"spi_miso_oe_o", [](const Out& o) { return uint64_t(o.miso_oe); }},
          {"step_o", [](const Out& o) { return uint64_t(o.step); }},
          {"dir_o", [](const Out& o) { return uint64_t(o.dir); }},
          {"torch_o", [](const Out& o) { return uint64_t(o.torch); }},
          {"enable_o", [](const Out& o) { return uint64_t(o.enable); }},
          {"running_o", [](const Out& o) { return uint64_t(o.running); }},
          {"fault_o", [](const Out& o) { return uint64_t(o.fault); }},
          {"stretched_o", [](const Out& o) { return uint64_t(o.stretched); }},
          {"err_code_o", [](const Out& o) { return uint64_t(o.err_code); }},
      };
      add_positions(v, std::make_index_sequence<N>());
      return v;
    }();
    return f;
  }

 private:
  template <size_t... A>
  static void add_positions(std::vector<Field<Out>>& v, std::index_sequence<A...>) {
    static const std::string names[] = {("position_o[" + std::to_string(A) + "]")...};
    (v.push_back({names[A].c_str(), [](const Out& o) { return uint64_t(uint32_t(o.position[A])); }}), ...);
  }
  // position_o is N*32 bits: an integer up to 64 bits, a word array above.
  static uint32_t position_word(const V& r, unsigned a) {
    if constexpr (N * 32 <= 64) return uint32_t(uint64_t(r.position_o) >> (32 * a));
    else return r.position_o[a];
  }
};

}  // namespace cpstep::sim

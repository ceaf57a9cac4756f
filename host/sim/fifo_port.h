// SPDX-License-Identifier: MIT
// Port adaptor between Verilated cp_fifo configurations and model::CpFifo.
#pragma once

#include <verilated.h>

#include <type_traits>
#include <vector>

#include "model/cp_fifo.h"
#include "sim/dut.h"

namespace cpstep::sim {

// Verilator keeps <= 64-bit ports as integers and wider ones as 32-bit word arrays.
template <class Port>
void put_word(Port& port, const model::FifoWord& w) {
  if constexpr (std::is_integral_v<Port>) {
    port = Port(w[0]);
  } else {
    for (size_t i = 0; i < sizeof(port) / 4; ++i) port[i] = uint32_t(w[i / 2] >> (32 * (i % 2)));
  }
}
template <class Port>
model::FifoWord get_word(const Port& port) {
  model::FifoWord w{};
  if constexpr (std::is_integral_v<Port>) {
    w[0] = uint64_t(port);
  } else {
    for (size_t i = 0; i < sizeof(port) / 4; ++i) w[i / 2] |= uint64_t(port[i]) << (32 * (i % 2));
  }
  return w;
}

template <class V, unsigned DW, unsigned AW>
struct FifoPort {
  using Rtl = V;
  using Model = model::CpFifo;
  using In = model::CpFifoIn;
  using Out = model::CpFifoOut;

  static Model::Params model_params() { return {DW, AW}; }
  static void drive(V& r, const In& i) {
    r.rst = i.rst;
    r.clear_i = i.clear;
    r.wr_i = i.wr;
    put_word(r.wr_data_i, i.wr_data);
    r.commit_i = i.commit;
    r.rollback_i = i.rollback;
    r.out_ready_i = i.out_ready;
  }
  static Out sample(const V& r) {
    Out o;
    o.full = r.full_o;
    o.used = r.used_o;
    o.level = r.level_o;
    o.out_valid = r.out_valid_o;
    o.out_data = get_word(r.out_data_o);
    return o;
  }
  static const std::vector<Field<Out>>& fields() {
    static const std::vector<Field<Out>> f = {
        {"full_o", [](const Out& o) { return uint64_t(o.full); }},
        {"used_o", [](const Out& o) { return uint64_t(o.used); }},
        {"level_o", [](const Out& o) { return uint64_t(o.level); }},
        {"out_valid_o", [](const Out& o) { return uint64_t(o.out_valid); }},
        {"out_data_o[63:0]", [](const Out& o) { return o.out_data[0]; }},
        {"out_data_o[127:64]", [](const Out& o) { return o.out_data[1]; }},
    };
    return f;
  }
};

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// Drives a cp_core stepper (RTL, model or lockstep) through its command port:
// words in with valid/ready, register reads, idle cycles; every cycle's outputs
// go to an optional observer (pin monitors, invariant checkers, VCD writers).
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "card/protocol.h"
#include "model/cp_core_ports.h"

namespace cpstep::sim {

template <class Stepper>
class CoreDriver {
 public:
  using Observer = std::function<void(uint64_t, const model::CpCoreIn&, const model::CpCoreOut&)>;

  explicit CoreDriver(Stepper& dut, Observer observe = nullptr)
      : dut_(dut), observe_(std::move(observe)) {}

  // One clock with the given inputs (estop as last set). The read port names a
  // register a cycle, in turn: every READ register, positions past the axes,
  // and addresses that read 0.
  model::CpCoreOut step(model::CpCoreIn in) {
    static constexpr uint8_t kReadSweep[] = {0x00, 0x01, 0x02, 0x03, 0x10, 0x11, 0x12, 0x13, 0x14,
                                             0x17, 0x1F, 0x20, 0x21, 0x22, 0x04, 0x18, 0x23, 0xFF};
    in.estop = estop_;
    const uint64_t c = dut_.cycle();
    in.rd_addr = kReadSweep[c % sizeof kReadSweep];
    last_ = dut_.step(in);
    if (observe_) observe_(c, in, last_);
    return last_;
  }
  void reset(unsigned cycles = 2) {
    model::CpCoreIn in;
    in.rst = true;
    for (unsigned i = 0; i < cycles; ++i) step(in);
  }
  void idle(uint64_t cycles) {
    for (uint64_t i = 0; i < cycles; ++i) step({});
  }
  // Sends words in order, holding each until the core takes it. A full queue
  // waits while motion drains it; `max_idle_wait` bounds the wait while the
  // core is not running (nothing would drain it).
  void send(const std::vector<uint32_t>& words, uint64_t max_idle_wait = 1'000'000) {
    for (uint32_t w : words) {
      model::CpCoreIn in;
      in.cmd_valid = true;
      in.cmd_data = w;
      for (uint64_t idle = 0;;) {
        const model::CpCoreOut o = step(in);
        if (o.cmd_ready) break;
        idle = o.running ? 0 : idle + 1;
        if (idle > max_idle_wait)
          throw std::runtime_error("cp_core did not take a command word and is not running");
      }
    }
  }
  uint32_t read(card::Register r, unsigned axis = 0) {
    std::vector<uint32_t> w;
    card::encode_read(r, axis, w);
    send(w);
    model::CpCoreIn in;
    in.rsp_ready = true;
    for (int n = 0; n < 16; ++n) {
      const auto o = step(in);
      if (o.rsp_valid) return o.rsp_data;
    }
    throw std::runtime_error("cp_core did not reply to READ");
  }
  // Idles until the core stops running (after it has started), or max cycles.
  uint64_t run_until_stopped(uint64_t max_cycles) {
    bool seen = last_.running;
    for (uint64_t n = 0; n < max_cycles; ++n) {
      const auto o = step({});
      seen = seen || o.running;
      if (seen && !o.running) return n + 1;
    }
    throw std::runtime_error("cp_core still running after " + std::to_string(max_cycles) + " cycles");
  }
  void set_estop(bool on) { estop_ = on; }
  const model::CpCoreOut& last() const { return last_; }
  Stepper& dut() { return dut_; }

 private:
  Stepper& dut_;
  Observer observe_;
  model::CpCoreOut last_{};
  bool estop_ = false;
};

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// Runs one request through a cp_engine stepper (RTL, model, or both in lockstep)
// and collects what it emitted: the moves, the timing of the build, and the
// register table decoded from the debug port.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/cp_engine.h"
#include "model/oracle.h"
#include "sim/dut.h"

namespace cpstep::sim {

struct EngineRequest {
  uint32_t u = 0, v = 0, k = 0, rep = 1;
};

struct EngineRun {
  std::string moves;                           // '0' axial, '1' diagonal
  uint32_t err_code = 0;                       // 0: accepted
  uint64_t accept_cycle = 0;                   // the handshake's cycle
  uint64_t first_move_cycle = 0;               // first cycle with move_valid
  uint64_t last_move_cycle = 0;                // cycle the last move was taken
  std::vector<oracle::Iteration> iterations;   // decoded from the debug port
  uint64_t build_cycles() const { return first_move_cycle - accept_cycle; }
};

// M1 and M2 as the debug port shows them: two shadow memories kept from the
// write ports, decoded with the snapshot's window descriptors.
class ShadowRegisters {
 public:
  explicit ShadowRegisters(unsigned aw) : mem_{std::vector<char>(size_t(1) << aw, '?'),
                                               std::vector<char>(size_t(1) << aw, '?')} {}
  void apply(const model::CpEngineOut& o) {
    if (o.dbg_we1) mem_[0].at(o.dbg_waddr1) = o.dbg_wbit1 ? '1' : '0';
    if (o.dbg_we2) mem_[1].at(o.dbg_waddr2) = o.dbg_wbit2 ? '1' : '0';
  }
  std::string decode(int which, uint32_t lo, uint32_t len, bool rev) const {
    const auto& m = mem_[which];
    const size_t n = m.size();
    std::string s;
    for (uint32_t i = 0; i < len; ++i) s.push_back(m[(lo + (rev ? len - 1 - i : i)) % n]);
    return s;
  }

 private:
  std::vector<char> mem_[2];
};

// ready(cycle) says whether the consumer takes a move in that cycle.
using ReadyPattern = std::function<bool(uint64_t)>;
inline bool always_ready(uint64_t) { return true; }
// Sees every cycle's inputs and outputs (for contract checks).
using CycleObserver =
    std::function<void(uint64_t, const model::CpEngineIn&, const model::CpEngineOut&)>;

template <class Stepper>
EngineRun run_request(Stepper& dut, unsigned aw, const EngineRequest& req,
                      const ReadyPattern& ready = always_ready,
                      const CycleObserver& observe = nullptr, uint64_t max_cycles = 0) {
  if (max_cycles == 0)
    max_cycles = 64 + 4 * (uint64_t(req.u) << req.k) * (req.rep ? req.rep : 1) + 16ull * req.u;
  EngineRun run;
  ShadowRegisters shadow(aw);
  model::CpEngineIn in;
  in.in_u = req.u;
  in.in_v = req.v;
  in.in_k = req.k;
  in.in_rep = req.rep;
  bool accepted = false, have_first = false;
  for (uint64_t n = 0; n < max_cycles; ++n) {
    in.in_valid = !accepted;
    in.move_ready = ready(dut.cycle());
    const uint64_t cycle = dut.cycle();
    const model::CpEngineOut o = dut.step(in);
    if (observe) observe(cycle, in, o);
    shadow.apply(o);
    if (!accepted && o.in_ready) {
      accepted = true;
      run.accept_cycle = cycle;
      continue;
    }
    if (!accepted) continue;
    if (o.err) {
      run.err_code = o.err_code;
      return run;
    }
    if (o.dbg_iter)
      run.iterations.push_back({o.dbg_x, o.dbg_y,
                                shadow.decode(0, o.dbg_m1_lo, o.dbg_m1_len, o.dbg_m1_rev),
                                shadow.decode(1, o.dbg_m2_lo, o.dbg_m2_len, o.dbg_m2_rev)});
    if (o.move_valid && !have_first) {
      have_first = true;
      run.first_move_cycle = cycle;
    }
    if (o.move_valid && in.move_ready) {
      run.moves.push_back(o.move ? '1' : '0');
      if (o.move_last) {
        run.last_move_cycle = cycle;
        return run;
      }
    }
    // An accepted request that has gone quiet with neither error nor moves.
    if (cycle == run.accept_cycle + 2 && o.in_ready && !o.move_valid && run.moves.empty())
      return run;
  }
  throw std::runtime_error("engine did not finish the request within " + std::to_string(max_cycles) +
                           " cycles");
}

// One request on a freshly reset engine of configuration P: the Verilated RTL
// (`rtl`) or the golden model.
template <class P>
EngineRun run_fresh(bool rtl, const EngineRequest& req) {
  model::CpEngineIn reset{};
  reset.rst = true;
  const unsigned aw = P::model_params().aw();
  if (rtl) {
    RtlDut<P> dut;
    dut.step(reset);
    return run_request(dut, aw, req);
  }
  ModelDut<P> dut;
  dut.step(reset);
  return run_request(dut, aw, req);
}

}  // namespace cpstep::sim

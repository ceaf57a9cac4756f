// SPDX-License-Identifier: MIT
// cp_fifo — cycle-accurate model of rtl/cp_fifo.v (first-word-fall-through FIFO
// on a block RAM with commit/rollback). Written from the contract in docs/CORE.md.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace cpstep::model {

// Up to 256 data bits, least significant word first (Verilator's order).
using FifoWord = std::array<uint64_t, 4>;

struct CpFifoParams {
  unsigned dw = 64;  // word width
  unsigned aw = 6;   // address width
};

struct CpFifoIn {
  bool rst = false, clear = false;
  bool wr = false;
  FifoWord wr_data{};
  bool commit = false, rollback = false;
  bool out_ready = false;
};

struct CpFifoOut {
  bool full = false;
  uint32_t used = 0, level = 0;
  bool out_valid = false;
  FifoWord out_data{};
};

class CpFifo {
 public:
  using Params = CpFifoParams;
  using In = CpFifoIn;
  using Out = CpFifoOut;

  explicit CpFifo(Params p = {});
  In in;
  Out outputs() const;
  void tick();
  // Single outputs without the whole of outputs() (the fast engine's hot path).
  bool out_valid() const { return out_valid_; }
  uint64_t out_word0() const { return out_valid_ ? rdata_[0] : 0; }
  uint32_t used() const { return ((wptr_ - rptr_) & ptr_mask()) + out_valid_; }
  // True when a clock with inputs `i` changes nothing: no write, pop, commit or
  // rollback that moves a pointer, no clear of a queue not already empty, and no
  // committed word on its way to the head (the event-skipping core's test; see
  // CpCore::quiet_for).
  bool still(const In& i) const;

 private:
  uint32_t ptr_mask() const { return (2u << p_.aw) - 1; }  // pointers carry one extra bit
  FifoWord masked(const FifoWord& w) const;

  Params p_;
  std::vector<FifoWord> mem_;
  FifoWord rdata_{};
  uint32_t wptr_ = 0, cptr_ = 0, rptr_ = 0;
  bool out_valid_ = false;
};

}  // namespace cpstep::model

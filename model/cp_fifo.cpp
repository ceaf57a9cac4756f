// SPDX-License-Identifier: MIT
#include "cp_fifo.h"

#include <stdexcept>

namespace cpstep::model {

CpFifo::CpFifo(Params p) : p_(p), mem_(size_t(1) << p.aw) {
  if (p_.dw < 1 || p_.dw > 256) throw std::invalid_argument("cp_fifo: DW must be 1 to 256");
  if (p_.aw < 1 || p_.aw > 16) throw std::invalid_argument("cp_fifo: AW must be 1 to 16");
}

FifoWord CpFifo::masked(const FifoWord& w) const {
  FifoWord m{};
  for (unsigned i = 0; i < 4; ++i) {
    const unsigned lo = 64 * i;
    if (p_.dw >= lo + 64) m[i] = w[i];
    else if (p_.dw > lo) m[i] = w[i] & ((uint64_t(1) << (p_.dw - lo)) - 1);
  }
  return m;
}

CpFifo::Out CpFifo::outputs() const {
  Out o;
  const uint32_t stored = (wptr_ - rptr_) & ptr_mask();
  o.full = stored >= (1u << p_.aw);
  o.used = stored + out_valid_;
  o.level = ((cptr_ - rptr_) & ptr_mask()) + out_valid_;
  o.out_valid = out_valid_;
  if (out_valid_) o.out_data = rdata_;
  return o;
}

bool CpFifo::still(const In& i) const {
  // A clear (or reset) of an empty queue whose pointers are at 0 changes nothing.
  if (i.rst || i.clear) return wptr_ == 0 && cptr_ == 0 && rptr_ == 0 && !out_valid_;
  const bool fetch_due = cptr_ != rptr_ && !out_valid_;
  return !i.wr && !(out_valid_ && i.out_ready) && !fetch_due && !(i.commit && cptr_ != wptr_) &&
         !(i.rollback && wptr_ != cptr_);
}

void CpFifo::tick() {
  const Out o = outputs();
  const bool write = in.wr && !o.full && !in.clear;
  const bool pop = out_valid_ && in.out_ready;
  // The head is refilled from committed storage when it is empty or leaving.
  const bool fetch = !in.clear && cptr_ != rptr_ && (!out_valid_ || pop);
  const uint32_t slot = (1u << p_.aw) - 1;
  if (fetch) rdata_ = mem_[rptr_ & slot];  // storage as it was before this edge's write
  if (write) mem_[wptr_ & slot] = masked(in.wr_data);

  uint32_t w = wptr_, c = cptr_, r = rptr_;
  bool v = out_valid_ && !pop;
  if (fetch) {
    r = (r + 1) & ptr_mask();
    v = true;
  }
  if (write) w = (w + 1) & ptr_mask();
  if (in.rollback) w = cptr_;
  else if (in.commit) c = w;
  if (in.clear || in.rst) {
    w = c = r = 0;
    v = false;
  }
  wptr_ = w;
  cptr_ = c;
  rptr_ = r;
  out_valid_ = v;
}

}  // namespace cpstep::model

// SPDX-License-Identifier: MIT
// Fuzz target, differential: the Verilated command parser rtl/cp_cmd.v against its
// golden model model::CpCmd, both at the parameters of tb/core/test_core_parts.cpp
// (N = 3, UMAX = 4095, KMAX = 3, CAW = 3, TW = 8, bit-serial multiplier), fed the
// same inputs every cycle; every output is compared every cycle, as the lockstep
// bench does with random traffic.
//
// The input is consumed a cycle at a time: one byte of control (word offered,
// reply taken, fault, running, pulse busy, queues full, rarely reset) and, when
// the word queue is empty, an operation that refills it: a segment built from the
// bytes (valid by construction, then maybe one field broken), a CONFIG, CONTROL or
// READ word, or any 32-bit word. Both start from one clock edge in reset.
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "Vcp_part_cmd.h"
#include "fuzz_util.h"
#include "model/cp_cmd.h"
#include "verilated.h"

using namespace cpstep;

namespace {

constexpr unsigned kN = 3, kUmax = 4095, kKmax = 3, kCaw = 3, kTw = 8;
constexpr unsigned kMaxCycles = 4000;

void segment(fuzz::Bytes& in, std::deque<uint32_t>& q) {
  const uint8_t shape = in.u8();
  const uint32_t k = in.u8() % (kKmax + 1);
  const uint32_t u = (shape & 1) ? 1 + in.u16() % kUmax : 1 + in.u8() % 40;
  const uint32_t nch = 1 + in.u8() % 4;
  const bool add2 = shape & 2;
  std::vector<uint32_t> w;
  w.push_back(1u << 28 | uint32_t(in.flag()) << 27 | k << 23 | uint32_t(add2) << 22 | nch);
  w.push_back(uint32_t(in.u8() & 7) << 24 | u);
  for (unsigned a = 0; a < kN; ++a) {
    const uint8_t m = in.u8();
    w.push_back(m < 64 ? u : m < 128 ? 0 : in.u16() % (u + 1));
  }
  uint32_t left = u << k;
  for (uint32_t c = 0; c < nch; ++c) {
    const uint32_t count = c + 1 == nch ? left : std::max<uint32_t>(1, left / (nch - c));
    left -= std::min(left, count);
    w.push_back((shape & 4) ? in.u32() : 1 + in.u16() % 5000);
    const uint16_t add = (shape & 8) ? in.u16() : uint16_t(int16_t(int8_t(in.u8()) / 32));
    w.push_back(uint32_t(add) << 16 | (count & 0xFFFF));
    if (add2) w.push_back((shape & 16) ? in.u16() : uint16_t(int16_t(int8_t(in.u8()) / 64)));
  }
  // One field broken, sometimes (the word index and its new value from the bytes).
  if (shape & 0x80) {
    const size_t i = in.u8() % w.size();
    w[i] = i == 0 ? (w[0] & 0xF0000000u) | (in.u32() & 0x0FFFFFFFu) : in.u32();
  }
  for (uint32_t x : w) q.push_back(x);
}

void refill(fuzz::Bytes& in, std::deque<uint32_t>& q) {
  switch (in.u8() % 8) {
    case 0:
    case 1:
    case 2: segment(in, q); break;
    case 3: q.push_back(2u << 28 | (in.u8() % 5u) << 24 | (in.u8() % 6u) << 20 | in.u16() % 300); break;
    case 4: q.push_back(3u << 28 | (in.u8() & 0x1F)); break;
    case 5: q.push_back(4u << 28 | in.u8()); break;
    default: q.push_back(in.u32()); break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  auto ctx = std::make_unique<VerilatedContext>();
  auto rtl = std::make_unique<Vcp_part_cmd>(ctx.get(), "top");
  model::CpCmd mod({kN, kUmax, kKmax, kCaw, kTw});
  // One edge in reset for both (outputs before it are not part of the contract).
  rtl->rst = 1;
  rtl->clk = 0;
  rtl->eval();
  rtl->clk = 1;
  rtl->eval();
  mod.in = {};
  mod.in.rst = true;
  mod.tick();

  std::deque<uint32_t> q;
  uint32_t read_data = 0x12345678;
  for (unsigned cycle = 0; cycle < kMaxCycles && !in.empty(); ++cycle) {
    if (q.empty()) refill(in, q);
    const uint8_t c = in.u8();
    model::CpCmdIn i;
    i.rst = c == 0xFF;
    i.cmd_valid = !q.empty() && (c & 0x03) != 0;
    i.cmd_data = q.empty() ? 0 : q.front();
    i.rsp_ready = c & 0x04;
    i.fault = (c & 0x38) == 0x38;
    i.running = (c & 0x70) == 0x70;
    i.pulse_busy = (c & 0x48) == 0x48;
    i.seg_full = (c & 0xC0) == 0xC0;
    i.ch_full = (c & 0x90) == 0x90;
    read_data = read_data * 1664525u + 1013904223u;
    i.read_data = read_data;

    rtl->clk = 0;
    rtl->rst = i.rst;
    rtl->cmd_valid_i = i.cmd_valid;
    rtl->cmd_data_i = i.cmd_data;
    rtl->rsp_ready_i = i.rsp_ready;
    rtl->read_data_i = i.read_data;
    rtl->fault_i = i.fault;
    rtl->running_i = i.running;
    rtl->pulse_busy_i = i.pulse_busy;
    rtl->seg_full_i = i.seg_full;
    rtl->ch_full_i = i.ch_full;
    rtl->eval();
    mod.in = i;
    const model::CpCmdOut o = mod.outputs();

    uint64_t ch[2] = {0, 0};
    for (size_t w = 0; w < 3; ++w) ch[w / 2] |= uint64_t(rtl->ch_wdata_o[w]) << (32 * (w % 2));
#define SAME(name, r, m)                                                                                    \
  FUZZ_CHECK(uint64_t(r) == uint64_t(m), "cycle %u: %s rtl 0x%llx model 0x%llx", cycle, name,              \
             (unsigned long long)uint64_t(r), (unsigned long long)uint64_t(m))
    SAME("cmd_ready_o", rtl->cmd_ready_o, o.cmd_ready);
    SAME("rsp_valid_o", rtl->rsp_valid_o, o.rsp_valid);
    SAME("rsp_data_o", rtl->rsp_data_o, o.rsp_data);
    SAME("rsp_addr_o", rtl->rsp_addr_o, o.rsp_addr);
    SAME("seg_wr_o", rtl->seg_wr_o, o.seg_wr);
    SAME("seg_wdata_o", rtl->seg_wdata_o, o.seg_data);
    SAME("seg_commit_o", rtl->seg_commit_o, o.seg_commit);
    SAME("seg_rollback_o", rtl->seg_rollback_o, o.seg_rollback);
    SAME("ch_wr_o", rtl->ch_wr_o, o.ch_wr);
    SAME("ch_wdata_o[63:0]", ch[0], o.ch_data[0]);
    SAME("ch_wdata_o[80:64]", ch[1], o.ch_data[1]);
    SAME("ch_commit_o", rtl->ch_commit_o, o.ch_commit);
    SAME("ch_rollback_o", rtl->ch_rollback_o, o.ch_rollback);
    SAME("start_o", rtl->start_o, o.start);
    SAME("abort_o", rtl->abort_o, o.abort);
    SAME("clear_o", rtl->clear_o, o.clear);
    SAME("drivers_on_o", rtl->drivers_on_o, o.drivers_on);
    SAME("drivers_off_o", rtl->drivers_off_o, o.drivers_off);
    SAME("cfg_write_o", rtl->cfg_write_o, o.cfg_write);
    SAME("fault_o", rtl->fault_o, o.fault);
    SAME("fault_code_o", rtl->fault_code_o, o.fault_code);
#undef SAME
    if (i.cmd_valid && o.cmd_ready && !i.rst) q.pop_front();
    rtl->clk = 1;
    rtl->eval();
    mod.tick();
  }
  rtl->final();
  return 0;
}

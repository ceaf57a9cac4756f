// SPDX-License-Identifier: MIT
// wave_core — prints ASCII timing diagrams of cp_core's command port, taken
// from the Verilated RTL cycle by cycle (docs/CORE.md "Timing diagrams").
#include <fmt/core.h>

#include <string>
#include <vector>

#include "card/protocol.h"
#include "sim/core_configs.h"
#include "sim/core_driver.h"

using namespace cpstep;

namespace {

struct Trace {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> rows;  // per cycle: one cell per signal
};

std::string bit(bool b) { return b ? "‾" : "_"; }

void print(const Trace& t, const char* title) {
  fmt::print("{}\n\n```\n", title);
  fmt::print("{:<12}", "cycle");
  for (size_t c = 0; c < t.rows.size(); ++c) fmt::print("{:<4}", c);
  fmt::print("\n");
  for (size_t s = 0; s < t.names.size(); ++s) {
    fmt::print("{:<12}", t.names[s]);
    for (const auto& row : t.rows) fmt::print("{:<4}", row[s]);
    fmt::print("\n");
  }
  fmt::print("```\n\n");
}

}  // namespace

int main() {
  using P = sim::CoreDefault;
  sim::RtlDut<P> dut;
  Trace t;
  t.names = {"cmd_valid", "cmd_ready", "cmd_data", "rsp_valid", "rsp_ready", "rsp_data"};
  bool record = false;
  sim::CoreDriver<sim::RtlDut<P>> drv(dut, [&](uint64_t, const model::CpCoreIn& in,
                                                const model::CpCoreOut& o) {
    if (!record) return;
    t.rows.push_back({bit(in.cmd_valid), bit(o.cmd_ready),
                      in.cmd_valid ? fmt::format("{:X}", in.cmd_data >> 28) + "." : "",
                      bit(o.rsp_valid), bit(in.rsp_ready),
                      o.rsp_valid ? fmt::format("{:02X}", o.rsp_data & 0xFF) : ""});
  });
  drv.reset();
  record = true;
  drv.idle(1);
  // READ of the ID register with the reply taken two cycles late, then a CONFIG.
  std::vector<uint32_t> w;
  card::encode_read(card::Register::id, 0, w);
  drv.send(w);
  model::CpCoreIn in;
  drv.step(in);
  drv.step(in);
  in.rsp_ready = true;
  drv.step(in);
  w.clear();
  card::encode_config(0, card::ConfigField::step_high, 5, w);
  drv.send(w);
  drv.idle(1);
  print(t, "READ 0x1F (reply held until rsp_ready), then a CONFIG word. cmd_data shows the "
           "opcode nibble; rsp_data its low byte (0x31 of \"CPS1\").");

  // A one-chunk segment: H0, H1, four v words, C0, C1, then the delay check.
  t.rows.clear();
  t.names = {"cmd_valid", "cmd_ready", "cmd_data"};
  w.clear();
  card::WireSegment s;
  s.u = 4;
  s.end = true;
  s.dir_positive = {true, true, true, true};
  s.v = {4, 1, 0, 0};
  s.chunks = {{10, 4, 3}};
  card::encode_segment(s, w);
  card::encode_read(card::Register::status, 0, w);
  std::vector<const char*> label = {"H0", "H1", "vx", "vy", "vz", "va", "C0", "C1", "RD"};
  size_t next = 0;
  bool record2 = true;
  record = false;
  sim::CoreDriver<sim::RtlDut<P>> drv2(dut, [&](uint64_t, const model::CpCoreIn& i,
                                                 const model::CpCoreOut& o) {
    if (!record2) return;
    t.rows.push_back({bit(i.cmd_valid), bit(o.cmd_ready), i.cmd_valid ? label[next] : ""});
    if (i.cmd_valid && o.cmd_ready) ++next;
  });
  drv2.send(w);
  drv2.idle(1);
  print(t, "A segment with one chunk (interval 10, count 4, add 3) and a READ behind it: cmd_ready drops "
           "for the chunk check's 51 clocks after the chunk's last word (C1, or C2 when its chunks carry "
           "add2: the check takes the same clocks whatever the values).");
  return 0;
}

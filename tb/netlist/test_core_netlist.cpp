// SPDX-License-Identifier: MIT
// cp_core after synthesis: yosys's gate-level netlist of the iCEBreaker build
// (synth_ice40 -abc9: SB_LUT4, SB_CARRY, SB_DFF*, SB_RAM40_4K), simulated with yosys's iCE40 cell models
// (tb/netlist/CMakeLists.txt), in lockstep with the golden model: every output on
// every cycle, the read port sweeping the READ registers every cycle (CoreDriver),
// the pin checker on. Random host-like jobs, the identification registers, bad
// segments the card refuses (many of them decided by the serial chunk check)
// and an E-stop. docs/BUILDS.md, "Post-synthesis simulation".
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "Vcp_core_icebreaker_netlist.h"
#include "core/core_bench.h"
#include "core/core_random.h"
#include "core/core_reject_cases.h"
#include "sim/core_configs.h"

namespace cpstep::tb {
namespace {

// Before its first clock edge in reset the netlist is in the iCE40's power-up state
// (every flip-flop 0, the cell models' `initial Q = 0`), and yosys has recoded the
// command parser's state register one-hot (FSM_RECODE: P_CMD = 9'b000000001), so
// all-zero is no state at all: cmd_ready_o is 0 until the first reset edge, where the
// RTL (x-initial 0: p_state_q = 0 = P_CMD) and the model say 1. Outputs before the
// first reset edge are not part of the contract (CoreNetlist.PowerUp shows which
// differ, and that all agree from that edge on); the netlist the lockstep benches run
// has had that one reset cycle (AfterOneResetEdge; a board holds rst for 256 clocks
// after its PLL locks: rtl/boards/cp_board.v).

using CoreNetlist = sim::CoreOf<builds::icebreaker, AfterOneResetEdge<Vcp_core_icebreaker_netlist>>;
// The netlist straight from power-up.
using CoreNetlistPowerUp = sim::CoreOf<builds::icebreaker, Vcp_core_icebreaker_netlist>;
using Harness = CoreHarness<CoreNetlist>;

// Cycles per second of the lockstep pair (netlist + model + checker), printed.
struct Rate {
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  void print(const char* what, uint64_t cycles) const {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s: %llu cycles in %.1f s, %.0f cycles/s\n", what, (unsigned long long)cycles, s,
                s > 0 ? double(cycles) / s : 0.0);
  }
};


// Random jobs as the RTL benches run them (test_core_random.cpp), fewer and shorter:
// the netlist simulates 15-20 times slower than the RTL (some 60,000 cycles/s).
TEST(CoreNetlist, StreamedJobs) {
  JobShape shape;
  shape.max_chunks = 16;
  shape.max_moves = 600;
  Rate r;
  const uint64_t cycles = random_jobs<CoreNetlist>("core_netlist", core_seed(7000), 2, 2, 8, shape);
  r.print("streamed jobs", cycles);
}

// From power-up, reset held: which outputs differ from the model before the first
// clock edge (printed; the one-hot parser state, above), and none from that edge on.
TEST(CoreNetlist, PowerUp) {
  sim::RtlDut<CoreNetlistPowerUp> rtl;
  sim::ModelDut<CoreNetlistPowerUp> model;
  model::CpCoreIn in;
  in.rst = true;
  for (unsigned c = 0; c < 4; ++c) {
    const auto want = model.step(in), got = rtl.step(in);
    for (const auto& f : CoreNetlistPowerUp::fields()) {
      const uint64_t e = f.get(want), a = f.get(got);
      if (c == 0 && e != a)
        std::printf("before the first reset edge: %s model %llu, netlist %llu\n", f.name,
                    (unsigned long long)e, (unsigned long long)a);
      if (c > 0) {
        EXPECT_EQ(e, a) << f.name << " in reset cycle " << c << " (after the first edge)";
      }
    }
  }
}

// The parameters reached the netlist: the identification and capability registers
// against rtl/builds.json (and the model, every cycle).
TEST(CoreNetlist, IdentificationRegisters) {
  Harness h("netlist_id", 1);
  const builds::Build& b = builds::icebreaker;
  EXPECT_EQ(h.read(card::Register::id), card::kCardId);
  const uint32_t caps = h.read(card::Register::caps);
  EXPECT_EQ(caps & 0xFF, b.n);
  EXPECT_EQ(caps >> 8 & 0xFF, b.kmax);
  EXPECT_EQ(caps >> 16 & 0xF, b.caw);
  EXPECT_EQ(caps >> 20 & 0xF, b.saw);
  EXPECT_EQ(caps >> 24 & 0x1F, b.tw);
  EXPECT_EQ(h.read(card::Register::pattern_capacity), b.w);
  EXPECT_EQ(h.read(card::Register::umax), b.umax);
  EXPECT_EQ(h.read(card::Register::caps2) >> 8 & 0xFF, b.cbuf_aw);
  EXPECT_EQ(h.read(card::Register::clock_hz), b.clock_hz);
  EXPECT_EQ(h.read(card::Register::build_id), b.build_id);
}

// The bad commands of tb/core/core_reject_cases.h (test_core_reject.cpp runs them all
// on the RTL) that reach the synthesized logic's distinct paths: the delay checks
// (codes 6 and 15) are the serial chunk check's verdicts.
std::vector<BadInput> bad_segments() {
  static const char* const kNames[] = {
      "v_above_U", "k_above_KMAX", "more_chunks_than_the_queue", "count_zero", "delay_negative",
      "delay_above_2pow32", "add2_increments_change_sign", "add2_last_delay_negative",
      "add2_last_delay_far_above_2pow32", "add2_last_delay_with_a_34_bit_product", "counts_short",
      "pattern_above_W", "opcode_6"};
  std::vector<BadInput> picked;
  for (const BadInput& b : bad_inputs(CoreNetlist::model_params()))
    for (const char* n : kNames)
      if (std::string(b.name) == n) picked.push_back(b);
  EXPECT_EQ(picked.size(), std::size(kNames)) << "a name is not in the catalogue";
  return picked;
}

// While a segment runs, a bad command: the running segment completes exactly, the bad
// one and a good one after it make no move, the code latches; after CLEAR a job runs.
TEST(CoreNetlist, RefusedWhileRunning) {
  Rate r;
  uint64_t cycles = 0;
  for (const BadInput& bad : bad_segments()) {
    Harness h(std::string("netlist_refused_") + bad.name, 11);
    const std::string where = std::string(bad.name) + " (running)";
    card::WireSegment a;
    ASSERT_TRUE(h.gen.from_deltas({200, -65, 0, 57}, a));
    a.chunks = {{6, 200, 0}};
    h.segment(a);
    h.control(true, false, false);
    ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.position[0] > 8; }, 5000))
        << where << ": the segment did not start";
    h.expecting = false;
    h.send(bad.words());
    ASSERT_TRUE(h.wait_for([](const model::CpCoreOut& o) { return o.fault; }, 5000))
        << where << ": no fault latched";
    JobShape shape;
    shape.max_moves = 100;
    h.segment(h.gen.segment(shape, true), false);
    h.finish();
    h.idle(100);
    EXPECT_EQ(h.chk.segments_done(), 1u) << where << ": the running segment did not complete";
    EXPECT_EQ(h.chk.position(0), 200) << where;
    EXPECT_EQ(h.chk.position(1), -65) << where;
    expect_stopped_with(h, bad.code, where);
    // CLEAR, then a short job runs exactly.
    h.expecting = true;
    h.control(false, false, true);
    ASSERT_FALSE(h.status().fault) << where << ": CLEAR did not clear";
    shape.max_moves = 150;
    h.play(h.gen.job(2, shape));
    h.expect_consistent(where + ", the job after CLEAR");
    cycles += h.cycles;
    if (HasFailure()) return;
  }
  r.print("refused while running", cycles);
}

// Segments at the multiplier's limits are accepted (queued, not run): last delays of
// exactly 2^32 - 1 and 1 over 65535 moves, increments ending at 0, add2 on short chunks.
TEST(CoreNetlist, LimitsAccepted) {
  Harness h("netlist_limits", 12);
  h.expecting = false;
  h.send(words_of(2, 0, {2, 1, 0, 0}, {{0xFFFFFFFEu, 2, 1}}));
  h.send(words_of(3, 0, {3, 1, 0, 0}, {{0xFFFFFFFCu, 3, 1, 1}}));
  h.send(words_of(65535, 0, {65535, 0, 0, 0}, {{1, 65535, 0, 2}}));
  h.send(words_of(65535, 0, {65535, 0, 65535, 0}, {{0xFFFFFFFFu, 65535, 0, -2}}));
  h.idle(100);
  card::Status st = h.status();
  EXPECT_FALSE(st.fault) << "code " << st.err_code;
  EXPECT_EQ(st.segments_queued, 4u);
  h.control(false, true, false);
  h.control(false, false, true);
  h.send(words_of(7, 0, {7, 0, 3, 0}, {{20, 4, 4, -2}, {5, 1, -9, 32767}, {6, 2, 3, -32768}}));
  h.idle(100);
  st = h.status();
  EXPECT_FALSE(st.fault) << "code " << st.err_code;
  EXPECT_EQ(st.segments_queued, 1u);
  h.control(false, true, false);
  h.control(false, false, true);
  EXPECT_EQ(h.status().segments_queued, 0u);
}

// E-stop at a random cycle of a streamed job: no STEP leading edge after the cycle it
// is seen (but a pulse already high completes), code 10, queues flushed, positions
// exact; CLEAR refused while held; after release and CLEAR a job runs exactly.
TEST(CoreNetlist, Estop) {
  const uint64_t seed = core_seed(7100);
  for (unsigned run = 0; run < 2; ++run) {
    Harness h("netlist_estop", seed + run);
    const std::string where = "estop seed " + std::to_string(seed + run);
    h.configure_random(20);
    JobShape shape;
    shape.max_moves = 300;
    const auto job = h.gen.job(4, shape);
    uint64_t total = 0;
    for (const auto& s : job) total += JobGen::programmed_cycles(s);
    const uint64_t at = h.ls.cycle() + 200 + h.gen.uniform(0, uint32_t(std::min<uint64_t>(total, 8000)));
    uint64_t seen = 0;
    h.hook = [&](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut&) {
      if (c + 1 == at) h.drv.set_estop(true);
      if (in.estop && !seen) {
        seen = c;
        h.chk.abandon();
        h.expecting = false;
      }
    };
    h.play(job);
    h.idle(200);
    ASSERT_NE(seen, 0u) << where;
    h.hook = nullptr;
    EXPECT_TRUE(h.chk.errors().empty()) << where << ":\n" << h.chk.report();
    EXPECT_LE(h.chk.last_edge_cycle(), seen) << where << ": a STEP leading edge after the E-stop";
    card::Status st = h.status();
    EXPECT_TRUE(st.fault && st.estop) << where;
    EXPECT_EQ(st.err_code, 10u) << where;
    EXPECT_EQ(st.segments_queued + st.chunks_queued, 0u) << where << ": queues not flushed";
    h.stretch_slack = 1;
    h.expect_counters(where);
    h.control(false, false, true);  // refused while held
    EXPECT_TRUE(h.status().fault) << where << ": CLEAR accepted while E-stop is held";
    h.drv.set_estop(false);
    h.expecting = true;
    h.control(false, false, true);
    EXPECT_TRUE(h.status().fault) << where << ": CLEAR cleared an E-stop (only the out-of-band ACK may)";
    h.ack();
    ASSERT_FALSE(h.status().fault) << where << ": ACK did not clear";
    h.play(h.gen.job(2, shape));
    h.expect_consistent(where + ", the job after CLEAR");
    if (HasFailure()) return;
  }
}

}  // namespace
}  // namespace cpstep::tb

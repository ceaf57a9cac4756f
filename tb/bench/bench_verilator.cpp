// SPDX-License-Identifier: MIT
// bench_verilator — the Verilated card's speed as Verilator built it, for
// scripts/bench-verilator (docs/BENCHMARKS.md "Verilator options"). One program
// per build of the default board's card (rtl/CMakeLists.txt: the shipped library
// and the cpstep_rtl_card_vb_<variant> ones); each runs the same job as
// `cpstep run --engine rtl` does (connect, send every word through the SPI pins,
// POLL every millisecond while waiting, until the card stops) and prints one
// line: variant, card cycles, wall seconds, cycles per second. With MAX_CYCLES
// it stops there (the host gives up waiting), for the builds that are slow.
//
//   bench_verilator_<variant> JOB.ngc MACHINE.toml [MAX_CYCLES]
#include <fmt/core.h>

#include <chrono>
#include <exception>
#include <string>

#include CPSTEP_VB_HEADER
#include "card/caps.h"
#include "card/card_client.h"
#include "card/protocol.h"
#include "run/card_job.h"
#include "sim/card_configs.h"
#include "sim/dut.h"
#include "sim/sim_link.h"
#include "sim/spi_master.h"

using namespace cpstep;

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    fmt::print(stderr, "usage: {} JOB.ngc MACHINE.toml [MAX_CYCLES]\n", argv[0]);
    return 2;
  }
  try {
    using Card = sim::CardOf<builds::CPSTEP_VB_BOARD, CPSTEP_VB_CLASS>;
    auto job = run::prepare_job(argv[1], argv[2], card::caps_of(Card::kBuild));
    if (!job.ok()) {
      fmt::print(stderr, "{}\n", job.errors.front().str());
      return 1;
    }
    sim::RtlDut<Card> dut;
    sim::SpiMaster<sim::RtlDut<Card>> spi(dut, sim::spi_timing_for_divider(8));
    sim::SimLink<sim::RtlDut<Card>> link(spi, double(Card::kBuild.clock_hz));
    card::ClientOptions co;
    co.axes = Card::kAxes;
    card::CardClient client(link, co);
    const uint64_t max_cycles = argc == 4 ? std::stoull(argv[3]) : ~uint64_t(0);
    link.set_deadline(max_cycles);
    const auto keep_waiting = [&](const card::Reply&) { return dut.cycle() < max_cycles; };
    const auto t0 = std::chrono::steady_clock::now();
    spi.reset();
    client.poll();
    if (client.send(job->words, keep_waiting) == job->words.size()) client.wait_until_stopped(keep_waiting);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (card::decode_status(client.last().status).fault) throw std::runtime_error("the card latched a fault");
    fmt::print("{} {} {:.3f} {:.3g}\n", CPSTEP_VB_VARIANT, dut.cycle(), s, double(dut.cycle()) / s);
  } catch (const std::exception& e) {
    fmt::print(stderr, "bench_verilator: {}\n", e.what());
    return 1;
  }
  return 0;
}

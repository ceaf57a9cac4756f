// SPDX-License-Identifier: MIT
#include "cli/sim_command.h"

#include <fmt/core.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <optional>

#include "card/caps.h"
#include "card/card_client.h"
#include "card/protocol.h"
#include "sim/card_configs.h"
#include "sim/fast_card.h"
#include "sim/sim_link.h"
#include "sim/sim_script.h"
#include "sim/spi_master.h"
#include "sim/vcd_writer.h"

namespace cpstep::cli {

namespace {

constexpr int kExitFault = 1;
constexpr int kExitRefused = 2;
// Cycles a stopped card may keep its command buffer full before the run is
// given up: far beyond any build, so only full queues with no motion end up here.
constexpr uint64_t kStoppedStallCycles = 100'000;
// Clock cycles between POLLs while the host waits for room or for the end.
constexpr double kPollCycles = 10'000;

// Why a run stopped before the script's end.
struct Stopped {
  std::string why;
};

template <class Card, class Dut>
class SimRun {
  static_assert(Card::kAxes == sim::kSimAxes);
  static constexpr uint64_t kClockHz = Card::kBuild.clock_hz;

 public:
  SimRun(const SimOptions& o, sim::VcdWriter* vcd)
      : o_(o),
        vcd_(vcd),
        spi_(dut_, sim::spi_timing_for_divider(o.sck_div)),
        link_(spi_, double(kClockHz)),
        client_(link_, client_options()) {
    spi_.set_span_observer([this](uint64_t c, uint64_t n, const sim::CardIn& in, const sim::CardOut& out) {
      observe(c, n, in, out);
    });
    link_.set_deadline(o.max_cycles);
    if (vcd_) {
      for (const char* pin : {"step", "dir"})
        for (unsigned a = 0; a < sim::kSimAxes; ++a)
          pins_.push_back(vcd_->add_signal(fmt::format("{}_{}", pin, sim::kSimAxisNames[a])));
      estop_signal_ = vcd_->add_signal("estop");
    }
  }

  // Runs every step of the script, then lets the card finish its motion.
  // Consecutive command lines go to the card together, in as few frames as fit.
  std::optional<Stopped> run(const std::vector<sim::ScriptStep>& steps) {
    spi_.reset();
    try {
      for (size_t i = 0; i < steps.size(); ++i) {
        const sim::ScriptStep& s = steps[i];
        line_ = s.line;
        if (std::holds_alternative<sim::SendWords>(s.action)) {
          std::vector<uint32_t> words;
          for (; i < steps.size() && std::holds_alternative<sim::SendWords>(steps[i].action); ++i) {
            const auto& w = std::get<sim::SendWords>(steps[i].action).words;
            words.insert(words.end(), w.begin(), w.end());
          }
          --i;
          send(words);
        } else if (const auto* d = std::get_if<sim::Wait>(&s.action)) {
          wait(d->cycles);
        } else if (std::holds_alternative<sim::RunToStop>(s.action)) {
          run_to_stop();
        } else if (const auto* e = std::get_if<sim::Estop>(&s.action)) {
          spi_.set_estop(e->on);
        } else if (const auto* u = std::get_if<sim::Urgent>(&s.action)) {
          client_.urgent(u->word);
        } else if (const auto* in = std::get_if<sim::Inputs>(&s.action)) {
          spi_.set_inputs(in->lim_min, in->lim_max, in->probe);
        }
        check_cycles();
      }
      line_ = 0;
      run_to_stop();
    } catch (const Stopped& s) {
      return s;
    } catch (const card::CardError& e) {
      return Stopped{where() + e.what()};
    }
    return std::nullopt;
  }

  // Polls the card and prints its state from the reply.
  int report(const std::optional<Stopped>& stopped) {
    const uint64_t end = ran_ && !spi_.last().running ? last_fall_ : dut_.cycle();
    card::Reply r;
    try {
      r = client_.poll();
    } catch (const card::CardError& e) {
      fmt::print(stderr, "cpstep sim: {}\n", e.what());
      return kExitFault;
    }
    const card::Status st = card::decode_status(r.status);
    std::string pos = "position";
    for (unsigned a = 0; a < sim::kSimAxes; ++a) pos += fmt::format(" {}={}", sim::kSimAxisNames[a], r.positions[a]);
    const card::ErrorName err = card::error_name(st.err_code);
    fmt::print("{}\n", pos);
    fmt::print("status running={:d} fault={:d} error={} stretched={:d} stretch_count={}\n", st.running,
               st.fault, err.name, st.stretched, r.stretch);
    fmt::print("counters moves_done={} segments_done={} cycles={}\n", r.moves, r.segments, end);
    std::fflush(stdout);
    int rc = 0;
    if (st.fault) {
      fmt::print(stderr, "cpstep sim: fault {} (code {}): {}\n", err.name, st.err_code, err.meaning);
      rc = kExitFault;
    }
    if (stopped) {
      fmt::print(stderr, "cpstep sim: {}\n", stopped->why);
      rc = kExitFault;
    }
    return rc;
  }

 private:
  static card::ClientOptions client_options() {
    card::ClientOptions c;
    c.axes = sim::kSimAxes;
    c.confirm_each_frame = false;  // the next frame's reply carries each result (pipelined)
    c.poll_interval_s = kPollCycles / double(kClockHz);
    return c;
  }

  // `count` cycles from `cycle` with these pins and outputs (the fast engine's
  // spans; 1 on the Verilated card): what changes, changes in the first.
  void observe(uint64_t cycle, uint64_t count, const sim::CardIn& in, const sim::CardOut& out) {
    (void)count;
    if (out.running) ran_ = true;
    else if (was_running_) last_fall_ = cycle + 1;
    was_running_ = out.running;
    if (!vcd_) return;
    for (unsigned a = 0; a < sim::kSimAxes; ++a) {
      vcd_->set(pins_[a], out.step >> a & 1);
      vcd_->set(pins_[sim::kSimAxes + a], out.dir >> a & 1);
    }
    vcd_->set(estop_signal_, in.estop);
    vcd_->sample(sim::cycle_start_ps(cycle, kClockHz));
  }

  std::string where() const {
    return line_ ? fmt::format("{}:{}: ", o_.file, line_) : std::string();
  }

  void check_cycles() {
    if (dut_.cycle() >= o_.max_cycles)
      throw Stopped{fmt::format("{}stopped at --max-cycles {}{}", where(), o_.max_cycles,
                                spi_.last().running ? " with the card still running" : "")};
  }

  // While the host waits: the cycle budget, and a stopped card whose buffer
  // stays full with its free words unchanged.
  bool keep_waiting(const card::Reply& r) {
    check_cycles();
    if (stall_.stalled(r, double(dut_.cycle())))
      throw Stopped{fmt::format(
          "{}the card took no command word for {} cycles while stopped: its queues are full "
          "(send `start` before more segments)",
          where(), kStoppedStallCycles)};
    return true;
  }

  void send(const std::vector<uint32_t>& words) {
    client_.send(words, [this](const card::Reply& r) { return keep_waiting(r); });
  }

  void wait(uint64_t cycles) {
    const uint64_t now = dut_.cycle();
    spi_.idle(std::min(cycles, o_.max_cycles > now ? o_.max_cycles - now : 0));
  }

  // Polls until the card is not running and its buffer is empty.
  void run_to_stop() {
    client_.wait_until_stopped([this](const card::Reply& r) { return keep_waiting(r); });
  }

  const SimOptions& o_;
  sim::VcdWriter* vcd_;
  Dut dut_;
  sim::SpiMaster<Dut> spi_;
  sim::SimLink<Dut> link_;
  card::CardClient client_;
  std::vector<int> pins_;
  int estop_signal_ = -1;
  unsigned line_ = 0;
  bool ran_ = false, was_running_ = false;
  uint64_t last_fall_ = 0;
  card::StallWatch stall_{double(kStoppedStallCycles)};
};

}  // namespace

int run_sim(const SimOptions& o) {
  std::ifstream in(o.file);
  if (!in) {
    fmt::print(stderr, "cpstep sim: cannot read {}\n", o.file);
    return kExitRefused;
  }
  std::vector<sim::ScriptStep> steps;
  try {
    steps = sim::parse_sim_script(in, o.file);
  } catch (const sim::ScriptError& e) {
    fmt::print(stderr, "{}\n", e.what());
    return kExitRefused;
  }
  const std::string board = o.board.empty() ? std::string(builds::kDefaultBoard) : o.board;
  const builds::Build* build = builds::find(board);
  if (!build || !build->board) {
    fmt::print(stderr, "cpstep sim: --board {}: no such board (boards: {})\n", board, card::board_names());
    return kExitRefused;
  }
  if (o.clock_hz != 0 && o.clock_hz != build->clock_hz) {
    fmt::print(stderr, "cpstep sim: --clock-hz {}: the {} card runs at {} Hz\n", o.clock_hz, board,
               build->clock_hz);
    return kExitRefused;
  }
  if (o.sck_div < 8) {
    fmt::print(stderr, "cpstep sim: --sck-div must be 8 or more (the card needs SCK <= clk/8)\n");
    return kExitRefused;
  }
  std::ofstream vcd_file;
  std::unique_ptr<sim::VcdWriter> vcd;
  if (!o.vcd.empty()) {
    vcd_file.open(o.vcd);
    if (!vcd_file) {
      fmt::print(stderr, "cpstep sim: cannot write {}\n", o.vcd);
      return kExitRefused;
    }
    vcd = std::make_unique<sim::VcdWriter>(vcd_file, "1ps", "cpstep");
  }
  int rc = kExitRefused;
#define CPSTEP_SIM_ON(name)                                                      \
  if (board == #name) {                                                          \
    using Card = sim::CardOf<builds::name, Vcp_card_##name>;                     \
    if (o.engine == "model") {                                                   \
      SimRun<Card, sim::FastCardDut<Card>> run(o, vcd.get());                    \
      rc = run.report(run.run(steps));                                           \
    } else {                                                                     \
      SimRun<Card, sim::RtlDut<Card>> run(o, vcd.get());                         \
      rc = run.report(run.run(steps));                                           \
    }                                                                            \
  }
  CPSTEP_FOR_EACH_BOARD(CPSTEP_SIM_ON)
#undef CPSTEP_SIM_ON
  vcd_file.close();
  if (!o.vcd.empty() && !vcd_file) {
    fmt::print(stderr, "cpstep sim: writing {} failed\n", o.vcd);
    return kExitFault;
  }
  return rc;
}

}  // namespace cpstep::cli

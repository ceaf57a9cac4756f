#include "cli/sim_command.h"

#include <fmt/core.h>

#include <fstream>
#include <memory>
#include <optional>

#include "Vcp_core.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"
#include "sim/sim_script.h"
#include "sim/vcd_writer.h"

namespace cpstep::cli {

namespace {

struct CoreRtl : sim::CorePortBase<Vcp_core, sim::kSimAxes> {};
using Dut = sim::RtlDut<CoreRtl>;

constexpr int kExitFault = 1;
constexpr int kExitRefused = 2;
// Cycles a stopped card may go without taking a command word before the run is
// given up: far beyond any build, so only full queues with no motion end up here.
constexpr uint64_t kStoppedStallCycles = 100'000;

// Why a run stopped before the script's end.
struct Stopped {
  std::string why;
};

class SimRun {
 public:
  SimRun(const SimOptions& o, sim::VcdWriter* vcd)
      : o_(o), vcd_(vcd), drv_(dut_, [this](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut& out) {
          observe(c, in, out);
        }) {
    if (vcd_) {
      for (const char* pin : {"step", "dir"})
        for (unsigned a = 0; a < sim::kSimAxes; ++a)
          pins_.push_back(vcd_->add_signal(fmt::format("{}_{}", pin, sim::kSimAxisNames[a])));
      estop_signal_ = vcd_->add_signal("estop");
    }
  }

  // Runs every step of the script, then lets the card finish its motion.
  std::optional<Stopped> run(const std::vector<sim::ScriptStep>& steps) {
    drv_.reset();
    try {
      for (const sim::ScriptStep& s : steps) {
        line_ = s.line;
        if (const auto* w = std::get_if<sim::SendWords>(&s.action)) send(w->words);
        else if (const auto* d = std::get_if<sim::Wait>(&s.action)) wait(d->cycles);
        else if (std::holds_alternative<sim::RunToStop>(s.action)) run_to_stop();
        else if (const auto* e = std::get_if<sim::Estop>(&s.action)) drv_.set_estop(e->on);
      }
      line_ = 0;
      run_to_stop();
    } catch (const Stopped& s) {
      cycles_ = dut_.cycle();
      return s;
    }
    cycles_ = dut_.cycle();
    return std::nullopt;
  }

  // Reads the card's registers over the command port and prints them.
  int report(const std::optional<Stopped>& stopped) {
    const card::Status st = card::decode_status(drv_.read(card::Register::status));
    const uint32_t stretch = drv_.read(card::Register::stretch_count);
    const uint32_t moves = drv_.read(card::Register::moves_done);
    const uint32_t segments = drv_.read(card::Register::segments_done);
    std::string pos = "position";
    for (unsigned a = 0; a < sim::kSimAxes; ++a)
      pos += fmt::format(" {}={}", sim::kSimAxisNames[a], int32_t(drv_.read(card::Register::position0, a)));
    const card::ErrorName err = card::error_name(st.err_code);
    fmt::print("{}\n", pos);
    fmt::print("status running={:d} fault={:d} error={} stretched={:d} stretch_count={}\n", st.running,
               st.fault, err.name, st.stretched, stretch);
    fmt::print("counters moves_done={} segments_done={} cycles={}\n", moves, segments, cycles_);
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
  void observe(uint64_t cycle, const model::CpCoreIn& in, const model::CpCoreOut& out) {
    if (!vcd_) return;
    for (unsigned a = 0; a < sim::kSimAxes; ++a) {
      vcd_->set(pins_[a], out.step >> a & 1);
      vcd_->set(pins_[sim::kSimAxes + a], out.dir >> a & 1);
    }
    vcd_->set(estop_signal_, in.estop);
    vcd_->sample(sim::cycle_start_ps(cycle, o_.clock_hz));
  }

  std::string where() const {
    return line_ ? fmt::format("{}:{}: ", o_.file, line_) : std::string();
  }

  model::CpCoreOut step(const model::CpCoreIn& in) {
    if (dut_.cycle() >= o_.max_cycles)
      throw Stopped{fmt::format("{}stopped at --max-cycles {}{}", where(), o_.max_cycles,
                                drv_.last().running ? " with the card still running" : "")};
    return drv_.step(in);
  }

  void send(const std::vector<uint32_t>& words) {
    for (uint32_t w : words) {
      model::CpCoreIn in;
      in.cmd_valid = true;
      in.cmd_data = w;
      uint64_t stalled = 0;
      while (!step(in).cmd_ready) {
        stalled = drv_.last().running ? 0 : stalled + 1;
        if (stalled > kStoppedStallCycles)
          throw Stopped{fmt::format(
              "{}the card took no command word for {} cycles while stopped: its queues are full "
              "(send `start` before more segments)",
              where(), kStoppedStallCycles)};
      }
    }
  }

  void wait(uint64_t cycles) {
    for (uint64_t i = 0; i < cycles; ++i) step({});
  }

  // One cycle lets a START just taken show as running; then idle while it is.
  void run_to_stop() {
    step({});
    while (drv_.last().running) step({});
  }

  const SimOptions& o_;
  sim::VcdWriter* vcd_;
  Dut dut_;
  sim::CoreDriver<Dut> drv_;
  std::vector<int> pins_;
  int estop_signal_ = -1;
  unsigned line_ = 0;
  uint64_t cycles_ = 0;
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
  if (o.clock_hz == 0 || o.clock_hz > 1'000'000'000'000u) {
    fmt::print(stderr, "cpstep sim: --clock-hz must be 1..10^12\n");
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
  SimRun run(o, vcd.get());
  const auto stopped = run.run(steps);
  const int rc = run.report(stopped);
  vcd_file.close();
  if (!o.vcd.empty() && !vcd_file) {
    fmt::print(stderr, "cpstep sim: writing {} failed\n", o.vcd);
    return kExitFault;
  }
  return rc;
}

}  // namespace cpstep::cli

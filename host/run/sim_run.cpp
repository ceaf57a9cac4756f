#include "run/sim_run.h"

#include <fmt/format.h>

#include <fstream>
#include <memory>
#include <stdexcept>

#include "Vcp_core.h"
#include "sim/core_driver.h"
#include "sim/core_port.h"
#include "sim/vcd_writer.h"

namespace cpstep::run {

const char* host_fault_name(HostFault f) {
  switch (f) {
    case HostFault::position: return "POSITION";
    case HostFault::move_count: return "MOVE_COUNT";
    case HostFault::pin_count: return "PIN_COUNT";
    case HostFault::timeout: return "TIMEOUT";
    case HostFault::stall: return "STALL";
  }
  return "UNKNOWN";
}

namespace {

struct CoreRtl : sim::CorePortBase<Vcp_core, plan::kAxes> {};
using Dut = sim::RtlDut<CoreRtl>;

// Mismatching checkpoints listed one by one in the faults; the rest are counted.
constexpr uint64_t kListedMismatches = 10;
// A stopped card that takes no command word for this long has full queues and
// nothing to drain them: far beyond any pattern build.
constexpr uint64_t kStallCycles = 1'000'000;

struct SendEnd {
  enum How { done, budget, stalled } how = done;
  size_t next = 0;  // the first word not taken
};

// Sends words in order, holding each until the card takes it, within the
// cycle budget; a card that is stopped and takes nothing for kStallCycles stalls.
template <class Driver, class Stepper>
SendEnd send_words(Driver& drv, const Stepper& dut, const std::vector<uint32_t>& words, uint64_t budget) {
  SendEnd end;
  for (; end.next < words.size(); ++end.next) {
    model::CpCoreIn in;
    in.cmd_valid = true;
    in.cmd_data = words[end.next];
    for (uint64_t idle = 0;;) {
      if (dut.cycle() >= budget) {
        end.how = SendEnd::budget;
        return end;
      }
      const model::CpCoreOut o = drv.step(in);
      if (o.cmd_ready) break;
      idle = o.running ? 0 : idle + 1;
      if (idle > kStallCycles) {
        end.how = SendEnd::stalled;
        return end;
      }
    }
  }
  return end;
}

// The index after the command that word `i` belongs to (docs/CORE.md: a
// SEGMENT is 2 + N + 2 nchunks words, every other command one word).
size_t command_end(const std::vector<uint32_t>& words, size_t i) {
  for (size_t c = 0; c < words.size();) {
    const size_t len = card::command_words(words[c], plan::kAxes);
    if (i < c + len) return std::min(words.size(), c + len);
    c += len;
  }
  return words.size();
}

Fault host_fault(HostFault f, std::string message) {
  return {uint32_t(f), host_fault_name(f), std::move(message)};
}

std::string axes_text(const plan::PerAxis<int64_t>& p, const plan::Machine& m) {
  std::string s;
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present) s += fmt::format("{}{}={}", s.empty() ? "" : " ", plan::kAxisLetters[a], p[a]);
  return s;
}

// Watches every cycle: START, leading STEP edges (one cycle after their move
// event), DIR at each edge, position_o at each card segment's last move.
class Recorder {
 public:
  Recorder(const CardJob& job, CardRun& run, sim::VcdWriter* vcd, const SimRunOptions& o)
      : job_(job), run_(run), vcd_(vcd), options_(o) {
    const plan::Machine& m = job.machine;
    for (int a = 0; a < plan::kAxes; ++a) {
      // Axes the machine does not use keep the card's reset polarity (active high, DIR high = +).
      const bool present = m.axes[a].present;
      if (!present || m.axes[a].step_active_high) step_active_high_ |= 1u << a;
      if (!present || m.axes[a].dir_positive_high) dir_positive_high_ |= 1u << a;
    }
    if (vcd_) {
      for (const char* pin : {"step", "dir"})
        for (int a = 0; a < plan::kAxes; ++a)
          signals_.push_back(vcd_->add_signal(fmt::format("{}_{}", pin, plan::kAxisLetters[a])));
    }
    run_.move_cycles.reserve(job.moves());
  }

  void observe(uint64_t cycle, const model::CpCoreIn& in, const model::CpCoreOut& out) {
    if (vcd_) {
      for (int a = 0; a < plan::kAxes; ++a) {
        vcd_->set(signals_[a], out.step >> a & 1);
        vcd_->set(signals_[plan::kAxes + a], out.dir >> a & 1);
      }
      vcd_->sample(sim::cycle_start_ps(cycle, uint64_t(job_.clock_hz())));
    }
    if (options_.progress && (cycle & 0xFFFF) == 0) options_.progress(run_.move_cycles.size(), job_.moves());
    if (in.rst) {
      primed_ = false;
      return;
    }
    if (!started_ && in.cmd_valid && out.cmd_ready && in.cmd_data >> 28 == 0x3 && (in.cmd_data & 1)) {
      started_ = true;
      run_.start_cycle = cycle;
    }
    const uint32_t active = ~(out.step ^ step_active_high_) & kAxisMask;
    const uint32_t leading = primed_ ? active & ~active_ : 0;
    active_ = active;
    primed_ = true;
    if (!leading) return;
    // Every move steps its major axis, and move events are at least a cycle
    // apart: each cycle with a leading edge is one move event.
    run_.move_cycles.push_back(cycle - 1);
    for (int a = 0; a < plan::kAxes; ++a) {
      if (!(leading >> a & 1)) continue;
      const bool dir_high = out.dir >> a & 1;
      const int8_t dir = dir_high == bool(dir_positive_high_ >> a & 1) ? 1 : -1;
      run_.pulses[a].cycles.push_back(cycle);
      run_.pulses[a].dirs.push_back(dir);
      pins_[a] += dir;
    }
    check_segment_end(out);
  }

  const plan::PerAxis<int64_t>& pin_position() const { return pins_; }

 private:
  static constexpr uint32_t kAxisMask = (1u << plan::kAxes) - 1;

  void check_segment_end(const model::CpCoreOut& out) {
    if (next_ >= job_.checkpoints.size()) return;
    const Checkpoint& cp = job_.checkpoints[next_];
    if (run_.move_cycles.size() != cp.moves) return;
    ++run_.checked_segments;
    plan::PerAxis<int64_t> card{};
    bool same = true;
    for (int a = 0; a < plan::kAxes; ++a) {
      card[a] = out.position[a];
      same = same && card[a] == cp.position[a];
    }
    if (!same && run_.position_mismatches++ < kListedMismatches) {
      run_.faults.push_back(host_fault(
          HostFault::position,
          fmt::format("card segment {} ({}:{}), move {}: position_o {} but the plan says {}", next_ + 1,
                      job_.job_file, cp.loc.line, cp.moves, axes_text(card, job_.machine),
                      axes_text(cp.position, job_.machine))));
    }
    ++next_;
  }

  const CardJob& job_;
  CardRun& run_;
  sim::VcdWriter* vcd_;
  const SimRunOptions& options_;
  std::vector<int> signals_;
  uint32_t step_active_high_ = 0, dir_positive_high_ = 0;
  uint32_t active_ = 0;
  bool primed_ = false, started_ = false;
  size_t next_ = 0;
  plan::PerAxis<int64_t> pins_{};
};

}  // namespace

CardRun run_on_sim(const CardJob& job, const SimRunOptions& o) {
  CardRun run;
  std::ofstream vcd_file;
  std::unique_ptr<sim::VcdWriter> vcd;
  if (!o.vcd.empty()) {
    vcd_file.open(o.vcd, std::ios::trunc);
    if (!vcd_file) throw std::runtime_error(fmt::format("cannot write {}", o.vcd));
    vcd = std::make_unique<sim::VcdWriter>(vcd_file, "1ps", "cpstep");
  }
  Recorder rec(job, run, vcd.get(), o);
  Dut dut;
  sim::CoreDriver<Dut> drv(dut, [&rec](uint64_t c, const model::CpCoreIn& in, const model::CpCoreOut& out) {
    rec.observe(c, in, out);
  });
  const double planned_cycles = job.planned.stats.duration_s * job.clock_hz();
  const uint64_t budget = o.max_cycles ? o.max_cycles : uint64_t(2 * planned_cycles) + 10'000'000;

  drv.reset();
  const SendEnd sent = send_words(drv, dut, job.words, budget);
  bool out_of_time = sent.how == SendEnd::budget;
  if (!out_of_time && sent.how == SendEnd::done) {
    // One cycle lets a START taken last show as running; then run to the end.
    drv.step({});
    while (drv.last().running && dut.cycle() < budget) drv.step({});
    out_of_time = drv.last().running;
  }
  run.cycles = dut.cycle();
  if (out_of_time) {
    // E-stop stops the card at once whatever its command port is doing; the
    // command under way is completed (the card drops it) so that the port
    // reads commands again.
    drv.set_estop(true);
    const std::vector<uint32_t> rest(job.words.begin() + long(sent.next),
                                     job.words.begin() + long(command_end(job.words, sent.next)));
    drv.send(rest, kStallCycles);
    drv.idle(4);
    run.faults.push_back(host_fault(HostFault::timeout,
                                    fmt::format("the card was still running after {} cycles; the host "
                                                "stopped it with E-stop",
                                                budget)));
  }
  if (sent.how == SendEnd::stalled) {
    // The port takes nothing: read nothing either, keep what the pins showed.
    run.faults.push_back(host_fault(HostFault::stall,
                                    fmt::format("the card took no command word for {} cycles while "
                                                "stopped (word {} of {})",
                                                kStallCycles, sent.next + 1, job.words.size())));
    const model::CpCoreOut& last = drv.last();
    run.status = {last.running, last.fault, last.stretched, false, last.err_code, 0, 0, last.enable};
    for (int a = 0; a < plan::kAxes; ++a) run.position[a] = last.position[a];
  } else {
    run.status = card::decode_status(drv.read(card::Register::status));
    run.stretch_count = drv.read(card::Register::stretch_count);
    run.moves_done = drv.read(card::Register::moves_done);
    run.segments_done = drv.read(card::Register::segments_done);
    for (int a = 0; a < plan::kAxes; ++a)
      run.position[a] = int32_t(drv.read(card::Register::position0, unsigned(a)));
  }
  if (o.progress) o.progress(run.move_cycles.size(), job.moves());

  // The card's own fault first: it is the cause, the host's checks follow from it.
  if (run.status.fault) {
    const card::ErrorName e = card::error_name(run.status.err_code);
    run.faults.insert(run.faults.begin(), Fault{run.status.err_code, e.name, e.meaning});
  }
  if (run.move_cycles.size() != job.moves() || run.moves_done != job.moves())
    run.faults.push_back(host_fault(HostFault::move_count,
                                    fmt::format("{} move events on the pins, {} counted by the card, "
                                                "{} planned",
                                                run.move_cycles.size(), run.moves_done, job.moves())));
  if (run.position_mismatches > kListedMismatches)
    run.faults.push_back(host_fault(HostFault::position,
                                    fmt::format("{} more card segments ended off the plan",
                                                run.position_mismatches - kListedMismatches)));
  if (rec.pin_position() != run.position)
    run.faults.push_back(host_fault(HostFault::pin_count,
                                    fmt::format("STEP/DIR edges on the pins add up to {}, position_o "
                                                "reads {}",
                                                axes_text(rec.pin_position(), job.machine),
                                                axes_text(run.position, job.machine))));
  vcd.reset();
  vcd_file.close();
  if (!o.vcd.empty() && !vcd_file) throw std::runtime_error(fmt::format("writing {} failed", o.vcd));
  return run;
}

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
#include "run/sim_run.h"

#include <limits>

#include <fmt/format.h>

#include <fstream>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "run/feed_driver.h"
#include "run/measure.h"
#include "sim/card_configs.h"
#include "sim/fast_card.h"
#include "sim/sim_link.h"
#include "sim/spi_master.h"
#include "sim/twin_card.h"
#include "sim/vcd_writer.h"

namespace cpstep::run {

const char* host_fault_name(HostFault f) {
  switch (f) {
    case HostFault::position: return "POSITION";
    case HostFault::move_count: return "MOVE_COUNT";
    case HostFault::pin_count: return "PIN_COUNT";
    case HostFault::timeout: return "TIMEOUT";
    case HostFault::stall: return "STALL";
    case HostFault::link: return "LINK";
    case HostFault::late: return "LATE";
    case HostFault::engine: return "ENGINE";
    case HostFault::torch: return "TORCH";
    case HostFault::source: return "SOURCE";
  }
  return "UNKNOWN";
}

const char* engine_name(Engine e) {
  switch (e) {
    case Engine::model: return "model";
    case Engine::rtl: return "rtl";
    case Engine::lockstep: return "lockstep";
  }
  return "?";
}

std::optional<Engine> parse_engine(std::string_view name) {
  for (Engine e : {Engine::model, Engine::rtl, Engine::lockstep})
    if (name == engine_name(e)) return e;
  return std::nullopt;
}

namespace {

// Mismatching checkpoints listed one by one in the faults; the rest are counted.
constexpr uint64_t kListedMismatches = 10;
// A stopped card whose command buffer stays full this long has full queues and
// nothing to drain them: far beyond any pattern build.
constexpr uint64_t kStallCycles = 1'000'000;

}  // namespace

std::string changed_file_fault(const JobFileChanged& e, const WordSource& words) {
  return fmt::format("{}; the host sent no more (word {} of {})", e.what(), words.consumed(), words.total());
}

Fault stop_for_changed_file(const JobFileChanged& e, const WordSource& words, card::CardClient& client,
                            const card::CardClient::KeepWaiting& keep_waiting,
                            const std::function<std::optional<double>()>& since_start_s, CardRun& run) {
  std::string how;
  try {
    how = stop_short(client, words.job().caps.feed, keep_waiting, since_start_s, run.feed);
    run.feed_scaled = true;
  } catch (const card::CardError& l) {
    how = fmt::format("stopping the card: {}", l.what());
  } catch (const JobFileChanged&) {
    how = "the run's checks, which plan the job again, met the change too";
  }
  return host_fault(HostFault::source, changed_file_fault(e, words) + "; " + how);
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

void take_reply(CardRun& run, const card::Reply& r) {
  run.status = card::decode_status(r.status);
  run.stretch_count = r.stretch;
  run.moves_done = r.moves;
  run.segments_done = r.segments;
  for (int a = 0; a < plan::kAxes && size_t(a) < r.positions.size(); ++a) run.position[a] = r.positions[a];
}

void add_card_faults(const CardJob& job, CardRun& run) {
  // The card's own fault first: it is the cause, the host's checks follow from it.
  if (run.status.fault) {
    const card::ErrorName e = card::error_name(run.status.err_code);
    run.faults.insert(run.faults.begin(), Fault{run.status.err_code, e.name, e.meaning});
  }
  // A stretched move kept its place on the path but not its time: the job did not
  // run as planned, so the run is not a success (exit 1), whatever else went right.
  if (run.stretch_count > 0)
    run.faults.push_back(host_fault(
        HostFault::late, fmt::format("{} move(s) fired late: the card stretched them (a STEP pulse or DIR "
                                     "change was not ready at the planned cycle; docs/PULSE.md)",
                                     run.stretch_count)));
  // The pins show the moves that step; the card also counts the pause moves.
  const uint64_t pauses = job.card_moves() - job.moves();
  const std::string paused = pauses ? fmt::format(" (and {} pause moves)", pauses) : std::string();
  if (run.pins_observed ? run.move_events != job.moves() || run.moves_done != job.card_moves()
                        : run.moves_done != job.card_moves())
    run.faults.push_back(host_fault(
        HostFault::move_count,
        run.pins_observed ? fmt::format("{} move events on the pins, {} counted by the card, {} planned{}",
                                        run.move_events, run.moves_done, job.moves(), paused)
                          : fmt::format("{} move events counted by the card, {} planned{}", run.moves_done,
                                        job.moves(), paused)));
}

// The torch pin against the plan: exact cycles from START (tolerance 0).
// `move_edges`: the pin cycles of the first move event after each torch edge
// and of the last (all check_torch needs of the moves).
void check_torch_pin(const CardJob& job, CardRun& run, const std::vector<uint64_t>& cycles,
                     const std::vector<uint64_t>& move_edges) {
  const auto from_start = [&](uint64_t c) { return double(c) - double(run.start_cycle); };
  for (size_t k = 0; k < cycles.size(); ++k) run.torch.push_back({from_start(cycles[k]), k % 2 == 0});
  std::vector<double> moves;
  moves.reserve(move_edges.size());
  for (uint64_t c : move_edges) moves.push_back(from_start(c));
  // Under a feed override or hold the card's time is not the plan's: the edges are
  // checked in order and number (and each pierce measured), not against planned cycles.
  run.torch_verdict =
      check_torch(job, run.torch, moves, run.feed_scaled ? std::numeric_limits<double>::infinity() : 0);
  // A run already failed ends early: its torch follows where it stopped, not the plan.
  if (!run.faults.empty()) return;
  for (const std::string& e : run.torch_verdict.errors) run.faults.push_back(host_fault(HostFault::torch, e));
}

namespace {

// Watches every cycle: START, leading STEP edges (one cycle after their move
// event), DIR at each edge, position_o at each card segment's last move.
class Recorder {
 public:
  Recorder(const CardJob& job, CardRun& run, sim::VcdWriter* vcd, const SimRunOptions& o)
      : job_(job), run_(run), vcd_(vcd), options_(o), checkpoints_(job) {
    checkpoint_ = checkpoints_.next();
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
      signals_.push_back(vcd_->add_signal("torch"));
    }
    if (options_.record_pins) run_.move_cycles.reserve(job.moves());
  }

  // `count` cycles from `cycle` on with the same pins and outputs (1 from the
  // Verilated card, runs of quiet cycles from the fast engine): what changes, it
  // changes in the first.
  void observe(uint64_t cycle, uint64_t count, const sim::CardIn& in, const sim::CardOut& out) {
    if (vcd_) {
      for (int a = 0; a < plan::kAxes; ++a) {
        vcd_->set(signals_[a], out.step >> a & 1);
        vcd_->set(signals_[plan::kAxes + a], out.dir >> a & 1);
      }
      vcd_->set(signals_[2 * plan::kAxes], out.torch);
      vcd_->sample(sim::cycle_start_ps(cycle, uint64_t(job_.clock_hz())));
    }
    if (options_.pins)
      for (uint64_t i = 0; i < count; ++i) options_.pins(cycle + i, out.step, out.dir);
    // About every 65536 cycles: in each span that holds a multiple of it.
    const uint64_t low = cycle & 0xFFFF;
    if (options_.progress && (low == 0 || low + count > 0x10000))
      options_.progress(run_.move_events, job_.moves());
    if (in.rst) {
      primed_ = false;
      return;
    }
    // START taken in t shows as running_o from t+1; running_o falls in the
    // cycle after the last move of the run (or at a fault).
    if (!started_ && out.running) {
      started_ = true;
      run_.start_cycle = cycle - 1;
      if (options_.meter) options_.meter->start(run_.start_cycle, run_.start_position);
    }
    if (started_ && !end_cycle_ && !out.running) end_cycle_ = cycle + 1;
    if (out.torch != torch_) {
      torch_ = out.torch;
      torch_cycles_.push_back(cycle);
      want_move_after_ = cycle;  // the pierce: the first move event after it
    }
    const uint32_t active = ~(out.step ^ step_active_high_) & kAxisMask;
    const uint32_t leading = primed_ ? active & ~active_ : 0;
    active_ = active;
    primed_ = true;
    if (!leading) return;
    // Every move steps its major axis, and move events are at least a cycle
    // apart: each cycle with a leading edge is one move event.
    ++run_.move_events;
    if (options_.record_pins) run_.move_cycles.push_back(cycle - 1);
    plan::PerAxis<int8_t> dirs{};
    for (int a = 0; a < plan::kAxes; ++a) {
      if (!(leading >> a & 1)) continue;
      const bool dir_high = out.dir >> a & 1;
      const int8_t dir = dir_high == bool(dir_positive_high_ >> a & 1) ? 1 : -1;
      dirs[a] = dir;
      if (options_.record_pins) {
        run_.pulses[a].cycles.push_back(cycle);
        run_.pulses[a].dirs.push_back(dir);
      }
      pins_[a] += dir;
    }
    if (options_.meter) options_.meter->move(cycle, leading, dirs);
    // The moves the torch check needs: the first after each torch edge, and the last.
    if (want_move_after_ && cycle > *want_move_after_) {
      torch_moves_.push_back(cycle);
      want_move_after_.reset();
    }
    last_move_edge_ = cycle;
    check_segment_end(out);
  }

  const plan::PerAxis<int64_t>& pin_position() const { return pins_; }
  // The torch pin's changes (absolute cycles; the first is on).
  const std::vector<uint64_t>& torch_cycles() const { return torch_cycles_; }
  // The pin cycles of the first move event after each torch change and of the
  // last move event, increasing.
  std::vector<uint64_t> torch_moves() const {
    std::vector<uint64_t> m = torch_moves_;
    if (last_move_edge_ && (m.empty() || m.back() != last_move_edge_)) m.push_back(last_move_edge_);
    return m;
  }
  bool started() const { return started_; }
  // One past the first cycle running_o was low after START; 0 while it runs or never ran.
  uint64_t end_cycle() const { return end_cycle_; }

 private:
  static constexpr uint32_t kAxisMask = (1u << plan::kAxes) - 1;

  void check_segment_end(const sim::CardOut& out) {
    if (!checkpoint_) return;
    const Checkpoint& cp = *checkpoint_;
    if (run_.move_events != cp.moves) return;
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
    checkpoint_ = checkpoints_.next();
  }

  const CardJob& job_;
  CardRun& run_;
  sim::VcdWriter* vcd_;
  const SimRunOptions& options_;
  std::vector<int> signals_;
  uint32_t step_active_high_ = 0, dir_positive_high_ = 0;
  uint32_t active_ = 0;
  bool primed_ = false, started_ = false, torch_ = false;
  std::vector<uint64_t> torch_cycles_;
  std::vector<uint64_t> torch_moves_;
  std::optional<uint64_t> want_move_after_;
  uint64_t last_move_edge_ = 0;
  uint64_t end_cycle_ = 0;
  size_t next_ = 0;
  CheckpointCursor checkpoints_;  // the plan's, in order
  const Checkpoint* checkpoint_ = nullptr;
  plan::PerAxis<int64_t> pins_{};
};

// The stepper of each engine; the Verilated card may trace every signal.
template <class Dut>
std::unique_ptr<Dut> make_dut(const SimRunOptions& o) {
  if constexpr (std::is_constructible_v<Dut, std::string>) return std::make_unique<Dut>(o.fst);
  else return std::make_unique<Dut>();
}

template <class Card, class Dut>
CardRun run_on_card(const CardJob& job, const SimRunOptions& o) {
  static_assert(Card::kAxes == plan::kAxes);
  CardRun run;
  std::ofstream vcd_file;
  std::unique_ptr<sim::VcdWriter> vcd;
  if (!o.vcd.empty()) {
    vcd_file.open(o.vcd, std::ios::trunc);
    if (!vcd_file) throw std::runtime_error(fmt::format("cannot write {}", o.vcd));
    vcd = std::make_unique<sim::VcdWriter>(vcd_file, "1ps", "cpstep");
  }
  Recorder rec(job, run, vcd.get(), o);
  const std::unique_ptr<Dut> dut_ptr = make_dut<Dut>(o);
  Dut& dut = *dut_ptr;
  const sim::SpiTiming timing = sim::spi_timing_for_divider(o.sck_div);
  sim::SpiMaster<Dut> spi(dut, timing);
  spi.set_span_observer([&rec](uint64_t c, uint64_t n, const sim::CardIn& in, const sim::CardOut& out) {
    rec.observe(c, n, in, out);
  });
  sim::SimLink<Dut> sim_link(spi, double(Card::kBuild.clock_hz));
  const std::unique_ptr<card::Link> wrapped = o.wrap_link ? o.wrap_link(sim_link) : nullptr;
  WordSource words(job, watchdog_words(job, o.watchdog_s));
  const uint64_t before_job = words.prefix_words();  // the watchdog's CONFIG
  card::ClientOptions co = feed_waits(keeping_alive(o.client, o.watchdog_s), !o.feed.empty(), bool(o.feed_toggle));
  co.axes = plan::kAxes;
  co.ptimer = job.caps.ptimer;  // its commands' lengths
  co.buffer_words = job.caps.command_buffer_words();
  card::CardClient client(wrapped ? *wrapped : sim_link, co);
  // A fresh card: its segment count starts at 0 with the job's first.
  client.set_buffered_time([&words, before_job](const card::Reply& r, uint64_t handed) {
    if (!card::decode_status(r.status).running) return std::numeric_limits<double>::infinity();
    return words.buffered_seconds(r.segments, r.moves, handed > before_job ? handed - before_job : 0);
  });

  const double planned_cycles = job.planned.stats.duration_s * job.clock_hz();
  // Under a feed override the job takes planned / override, and a held card stands
  // until its event resumes it: the budget counts both.
  double slowest = o.override_pct / 100;
  for (const FeedEvent& e : o.feed)
    if (e.kind == FeedEvent::Kind::override_pct) slowest = std::min(slowest, e.pct / 100);
  const double events_cycles = o.feed.empty() ? 0 : o.feed.back().at_s * job.clock_hz();
  const uint64_t budget =
      o.max_cycles ? o.max_cycles
                   : uint64_t(2 * planned_cycles / std::max(slowest, 0.01) + events_cycles) + 10'000'000;
  sim_link.set_deadline(budget);

  // While the host waits (for room, or for the end): give up at the budget, or
  // when the card, stopped, keeps its buffer full and its free words unchanged.
  enum class GaveUp { no, out_of_time, stalled } gave_up = GaveUp::no;
  card::StallWatch stall{double(kStallCycles)};
  const auto keep_waiting = [&](const card::Reply& r) {
    const uint64_t now = dut.cycle();
    if (now >= budget) gave_up = GaveUp::out_of_time;
    else if (stall.stalled(r, double(now))) gave_up = GaveUp::stalled;
    return gave_up == GaveUp::no;
  };

  spi.reset();
  size_t sent = 0;
  // What was sent and the feed frames applied, kept when the sending stops on an error.
  FeedOutcome fed;
  const auto since_start = [&]() -> std::optional<double> {
    if (!rec.started()) return std::nullopt;
    return (double(dut.cycle()) - double(run.start_cycle)) / job.clock_hz();
  };
  try {
    client.poll();
    // The card says what it is; the job must have been planned for exactly that.
    const card::CardCaps caps = card::read_caps(client, keep_waiting);
    if (const std::string why = card::unusable(caps, plan::kAxes); !why.empty())
      throw card::CardError(why + "; nothing was sent");
    if (caps != job.caps)
      throw card::CardError(fmt::format("the job was planned for {}, but the card is {}; nothing was sent",
                                        card::describe(job.caps), card::describe(caps)));
    // Feed: the override before the job's words (its ramp's CONFIG then sets the scale
    // on it), events as their time from START comes, toggles as they are asked.
    const FeedPlan plan{o.override_pct, o.feed, o.feed_toggle};
    if (plan.any() && !caps.feed)
      throw card::CardError(fmt::format("the card, {}, has no feed hold or override; nothing was sent",
                                        card::card_name(caps)));
    send_with_feed(client, words, plan, keep_waiting, since_start, fed);
    sent = fed.take(run.feed, run.feed_scaled);
    if (sent == words.total() && gave_up == GaveUp::no) watchdog_off(client, o.watchdog_s, keep_waiting);
  } catch (const card::CardError& e) {
    sent = fed.take(run.feed, run.feed_scaled);
    run.faults.push_back(host_fault(HostFault::link, e.what()));
  } catch (const JobFileChanged& e) {
    sent = fed.take(run.feed, run.feed_scaled);
    run.faults.push_back(stop_for_changed_file(e, words, client, keep_waiting, since_start, run));
  }
  run.cycles = rec.end_cycle() ? rec.end_cycle() : dut.cycle();
  if (gave_up == GaveUp::out_of_time) {
    // E-stop stops the card at once, whatever its command buffer holds.
    spi.set_estop(true);
    spi.idle(4);
    run.faults.push_back(host_fault(HostFault::timeout,
                                    fmt::format("the card was still running after {} cycles; the host "
                                                "stopped it with E-stop",
                                                budget)));
  } else if (gave_up == GaveUp::stalled) {
    run.faults.push_back(host_fault(HostFault::stall,
                                    fmt::format("the card, stopped, took no command word for {} cycles "
                                                "(word {} of {} sent)",
                                                kStallCycles, sent, words.total())));
  }
  // The final state: one POLL (the reply needs no command port, so it comes
  // even from a stalled card).
  try {
    take_reply(run, client.poll());
  } catch (const card::CardError& e) {
    run.faults.push_back(host_fault(HostFault::link, e.what()));
  } catch (const JobFileChanged& e) {
    // The run's checks plan the job again as the card goes (CheckpointCursor, the
    // meter's MoveClock): one of them met the change.
    if (std::none_of(run.faults.begin(), run.faults.end(), [](const Fault& f) { return f.code == uint32_t(HostFault::source); }))
      run.faults.push_back(host_fault(HostFault::source, changed_file_fault(e, words)));
  }
  run.sim_cycles = dut.cycle();
  run.engine = o.engine;
  if constexpr (requires { dut.skipped(); }) run.skipped_cycles = dut.skipped();
  run.link = {"sim", sim_link.name(), client.stats(), job.clock_hz() / o.sck_div, o.sck_div,
              sim_link.busy_cycles(), double(run.sim_cycles) / job.clock_hz()};
  if (o.progress) o.progress(run.move_events, job.moves());

  add_card_faults(job, run);
  check_torch_pin(job, run, rec.torch_cycles(), rec.torch_moves());
  if (run.position_mismatches > kListedMismatches)
    run.faults.push_back(host_fault(HostFault::position,
                                    fmt::format("{} more card segments ended off the plan",
                                                run.position_mismatches - kListedMismatches)));
  if (rec.pin_position() != run.position)
    run.faults.push_back(host_fault(HostFault::pin_count,
                                    fmt::format("STEP/DIR edges on the pins add up to {}, the card's "
                                                "position reads {}",
                                                axes_text(rec.pin_position(), job.machine),
                                                axes_text(run.position, job.machine))));
  vcd.reset();
  vcd_file.close();
  if (!o.vcd.empty() && !vcd_file) throw std::runtime_error(fmt::format("writing {} failed", o.vcd));
  return run;
}

template <class Card, class Dut>
card::CardCaps connect_card() {
  Dut dut;
  sim::SpiMaster<Dut> spi(dut, sim::spi_timing_for_divider(8));
  sim::SimLink<Dut> link(spi, double(Card::kBuild.clock_hz));
  card::ClientOptions co;
  co.axes = Card::kAxes;
  card::CardClient client(link, co);
  spi.reset();
  client.poll();
  return card::read_caps(client);
}

template <class Card>
CardRun run_on_engine(const CardJob& job, const SimRunOptions& o) {
  switch (o.engine) {
    case Engine::model: return run_on_card<Card, sim::FastCardDut<Card>>(job, o);
    case Engine::rtl: return run_on_card<Card, sim::RtlDut<Card>>(job, o);
    case Engine::lockstep: break;
  }
  try {
    return run_on_card<Card, sim::TwinCardDut<Card>>(job, o);
  } catch (const sim::EngineMismatch& m) {
    // The same run on the Verilated card alone, traced, up to a little past the
    // cycle: the waveform the fault points at.
    SimRunOptions again = o;
    again.engine = Engine::rtl;
    again.fst = o.fst.empty() ? "cpstep-engine-mismatch.fst" : o.fst;
    again.max_cycles = m.cycle + 16;
    again.vcd.clear();
    again.progress = nullptr;
    CardRun run = run_on_card<Card, sim::RtlDut<Card>>(job, again);
    run.engine = Engine::lockstep;
    run.faults.insert(run.faults.begin(),
                      host_fault(HostFault::engine, fmt::format("{}; waveform of the Verilated card: {}", m.what(),
                                                                again.fst)));
    return run;
  }
}

}  // namespace

std::string sim_board_for(const CardJob& job, const SimRunOptions& o) {
  if (!o.board.empty()) return o.board;
  const builds::Build* b = card::build_of(job.caps);
  return b ? std::string(b->name) : std::string(builds::kDefaultBoard);
}

CardRun run_on_sim(const CardJob& job, const SimRunOptions& o) {
  // The simulated card is reset for the run, so its counters read 0.
  if (job.start != plan::PerAxis<int64_t>{}) {
    CardRun run;
    run.faults.push_back(host_fault(HostFault::link,
                                    fmt::format("the job was planned from {}, but a simulated card starts at 0; "
                                                "nothing was sent",
                                                axes_text(job.start, job.machine))));
    return run;
  }
  const std::string board = sim_board_for(job, o);
#define CPSTEP_RUN_ON(name) \
  if (board == #name) return run_on_engine<sim::CardOf<builds::name, Vcp_card_##name>>(job, o);
  CPSTEP_FOR_EACH_BOARD(CPSTEP_RUN_ON)
#undef CPSTEP_RUN_ON
  throw std::invalid_argument(fmt::format("no simulated board '{}' (boards: {})", board, card::board_names()));
}

card::CardCaps connect_sim(std::string_view board, Engine engine) {
#define CPSTEP_CONNECT(name)                                                                      \
  if (board == #name) {                                                                           \
    using Card = sim::CardOf<builds::name, Vcp_card_##name>;                                      \
    return engine == Engine::rtl ? connect_card<Card, sim::RtlDut<Card>>()                        \
                                 : connect_card<Card, sim::FastCardDut<Card>>();                  \
  }
  CPSTEP_FOR_EACH_BOARD(CPSTEP_CONNECT)
#undef CPSTEP_CONNECT
  throw std::invalid_argument(fmt::format("no simulated board '{}' (boards: {})", board, card::board_names()));
}

std::vector<uint32_t> watchdog_words(const CardJob& job, double watchdog_s) {
  std::vector<uint32_t> words;
  // 0 s sends nothing; any other value (a bad one throws) its CONFIG.
  if (watchdog_s != 0) card::encode_watchdog(watchdog_s, uint32_t(job.clock_hz()), words);
  return words;
}

card::ClientOptions keeping_alive(card::ClientOptions client, double watchdog_s) {
  if (watchdog_s > 0) client.keepalive_s = watchdog_s / 4;
  return client;
}

void watchdog_off(card::CardClient& client, double watchdog_s, const card::CardClient::KeepWaiting& keep) {
  if (watchdog_s <= 0 || card::decode_status(client.last().status).running) return;
  std::vector<uint32_t> off;
  card::encode_config(0, card::ConfigField::watchdog, 0, off);
  if (client.send(off, keep) == off.size()) client.settle(keep);
}

}  // namespace cpstep::run

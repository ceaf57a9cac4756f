// SPDX-License-Identifier: MIT
// `cpstep home` on the simulated card: the card behind its SPI pins (run/home.h's
// driver over card::CardClient, as on a real card) and a simulated machine around it
// whose limit switches close where the machine file places them, driven by the axis
// positions counted on the STEP/DIR pins.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <fstream>
#include <sstream>
#include <type_traits>

#include "card/job.h"
#include "plan/gcode.h"
#include "run/card_job.h"
#include "run/home.h"
#include "run/sim_run.h"
#include "sim/card_configs.h"
#include "sim/fast_card.h"
#include "sim/sim_link.h"
#include "sim/spi_master.h"
#include "sim/twin_card.h"

namespace cpstep::run {
namespace {

// The clocks a wait is cut into, so that a switch closes within this many clocks
// of the pins reaching it (far below a step at homing speeds: at 48 MHz, 21 us).
constexpr uint64_t kWorldChunk = 1024;

// The simulated machine: positions from the pins, switches from the positions.
class World {
 public:
  // The homing switches where home.sim_switch_mm places them (others rest open), the
  // probe where inputs.sim_probe_mm does.
  void configure(const plan::Machine& m) {
    for (int a = 0; a < plan::kAxes; ++a) {
      const plan::AxisConfig& ax = m.axes[a];
      if (!ax.present || ax.step_active_high) step_high_ |= 1u << a;
      if (!ax.present || ax.dir_positive_high) dir_high_ |= 1u << a;
      // A wired switch rests at its inactive level; the homing one closes at its place.
      const auto rest = [](plan::SwitchLevel l) { return l == plan::SwitchLevel::active_low; };
      if (ax.present && rest(ax.limit_min)) min_rest_ |= 1u << a;
      if (ax.present && rest(ax.limit_max)) max_rest_ |= 1u << a;
      if (ax.present && ax.home.present && ax.home.sim_switch_mm) {
        homed_ |= 1u << a;
        at_max_[a] = ax.home.at_max;
        switch_at_[a] = std::llround(*ax.home.sim_switch_mm * ax.steps_per_mm);
      }
    }
    probe_high_ = m.inputs.probe_active_high;
    probe_axis_ = m.inputs.sim_probe_axis;
    if (probe_axis_ >= 0) {
      const plan::AxisConfig& ax = m.axes[probe_axis_];
      probe_at_ = ax.present ? std::llround(m.inputs.sim_probe_mm * ax.steps_per_mm) : 0;
    }
    fresh_ = true;
  }
  // After each span of clocks: the pins' leading STEP edges counted, the switches set.
  template <class Spi>
  void observe(Spi& spi, uint64_t c, const sim::CardOut& out) {
    const uint32_t active = ~(out.step ^ step_high_) & 0xF;
    if (!seen_) {
      prev_ = active;
      seen_ = true;
    }
    const bool first = fresh_;  // a switch closed from the start is no trip
    fresh_ = false;
    for (int a = 0; a < plan::kAxes; ++a)
      if ((active >> a & 1) && !(prev_ >> a & 1)) pins_[a] += ((out.dir >> a & 1) == (dir_high_ >> a & 1)) ? 1 : -1;
    prev_ = active;
    uint32_t mins = min_rest_, maxs = max_rest_;
    for (int a = 0; a < plan::kAxes; ++a) {
      if (!(homed_ >> a & 1)) continue;
      const bool closed = at_max_[a] ? pins_[a] >= switch_at_[a] : pins_[a] <= switch_at_[a];
      if (closed && !closed_[a] && !first) trips_.push_back({a, c, pins_[a]});
      closed_[a] = closed;
      uint32_t& bits = at_max_[a] ? maxs : mins;
      // Active high: closed is high; active low: closed is low.
      if (closed != bool(bits >> a & 1)) bits |= 1u << a;
      else bits &= ~(1u << a);
    }
    // The probe: in contact on the far side of its plane from the start (counters 0).
    bool contact = false;
    if (probe_axis_ >= 0) {
      const int64_t p = pins_[probe_axis_];
      contact = probe_at_ > 0 ? p >= probe_at_ : p <= probe_at_;
      if (contact && !contact_ && !first) contacts_.push_back({probe_axis_, c, p});
    }
    contact_ = contact;
    const bool probe = contact == probe_high_;
    if (mins != mins_ || maxs != maxs_ || probe != probe_pin_ || !set_) {
      spi.set_inputs(mins, maxs, probe);
      mins_ = mins;
      maxs_ = maxs;
      probe_pin_ = probe;
      set_ = true;
    }
  }
  const std::vector<SimHomeSwitchTrip>& contacts() const { return contacts_; }
  int64_t probe_at() const { return probe_at_; }
  const plan::PerAxis<int64_t>& pins() const { return pins_; }
  const plan::PerAxis<int64_t>& switch_at() const { return switch_at_; }
  const std::vector<SimHomeSwitchTrip>& trips() const { return trips_; }

 private:
  uint32_t step_high_ = 0, dir_high_ = 0, min_rest_ = 0, max_rest_ = 0, homed_ = 0;
  bool probe_high_ = true, contact_ = false, probe_pin_ = false;
  int probe_axis_ = -1;
  int64_t probe_at_ = 0;
  std::vector<SimHomeSwitchTrip> contacts_;
  plan::PerAxis<bool> at_max_{}, closed_{};
  plan::PerAxis<int64_t> switch_at_{}, pins_{};
  uint32_t prev_ = 0, mins_ = 0, maxs_ = 0;
  bool seen_ = false, set_ = false, fresh_ = false;
  std::vector<SimHomeSwitchTrip> trips_;
};

// The link the host's client talks over: the simulated card's, with waits cut into
// kWorldChunk clocks so that the world keeps up with the pins.
template <class Dut>
class WorldLink final : public card::Link {
 public:
  WorldLink(sim::SimLink<Dut>& inner, double clock_hz) : inner_(inner), clock_hz_(clock_hz) {}
  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override { return inner_.transfer(mosi); }
  void wait(double seconds) override {
    uint64_t n = std::max<uint64_t>(1, uint64_t(std::ceil(seconds * clock_hz_)));
    while (n > 0) {
      const uint64_t k = std::min(n, kWorldChunk);
      inner_.spi().idle(k);
      n -= k;
    }
  }
  [[nodiscard]] double now_s() const override { return inner_.now_s(); }
  [[nodiscard]] std::string name() const override { return inner_.name(); }

 private:
  sim::SimLink<Dut>& inner_;
  double clock_hz_;
};

// The simulated card behind its pins, the simulated machine around it, the host's
// client, the card's capabilities and the machine file bound to them.
template <class Card, class Dut>
struct Session {
  static_assert(Card::kAxes == plan::kAxes);
  std::unique_ptr<Dut> dut_ptr = make();
  Dut& dut = *dut_ptr;
  double clock_hz = double(Card::kBuild.clock_hz);
  sim::SpiMaster<Dut> spi{dut, sim::spi_timing_for_divider(8)};
  World world;
  sim::SimLink<Dut> sim_link{spi, clock_hz};
  WorldLink<Dut> link{sim_link, clock_hz};
  card::CardClient client{link, options()};
  card::CardCaps caps;
  plan::Machine machine;

  static std::unique_ptr<Dut> make() {
    if constexpr (std::is_constructible_v<Dut, std::string>) return std::make_unique<Dut>(std::string());
    else return std::make_unique<Dut>();
  }
  static card::ClientOptions options() {
    card::ClientOptions co;
    co.axes = Card::kAxes;
    co.ptimer = Card::kBuild.ptimer != 0;  // a phase-timer card's commands (docs/CORE.md)
    return co;
  }
  // Resets the card, reads what it is, loads the machine file for it: "" or why not.
  std::string open(const std::string& machine_file) {
    spi.set_span_observer([this](uint64_t c, uint64_t n, const sim::CardIn&, const sim::CardOut& out) {
      world.observe(spi, c + n - 1, out);
    });
    spi.reset();
    client.poll();
    caps = card::read_caps(client);
    plan::Result<plan::Machine> m = load_card_machine(machine_file, caps);
    if (!m.ok()) return m.errors.empty() ? std::string("the machine file was refused") : m.errors.front().str();
    machine = *m.value;
    return "";
  }
  // The world placed (switches, probe) and looked at once before anything moves.
  void place() {
    world.configure(machine);
    world.observe(spi, 0, spi.last());
  }
  plan::PerAxis<int64_t> counts() {
    const card::Reply end = client.poll();
    plan::PerAxis<int64_t> p{};
    for (int a = 0; a < plan::kAxes; ++a) p[a] = end.positions.at(size_t(a));
    return p;
  }
};

template <class Card, class Dut>
SimHomeRun home_on_card(const std::string& machine_file) {
  SimHomeRun run;
  Session<Card, Dut> s;
  run.error = s.open(machine_file);
  if (!run.error.empty()) return run;
  run.machine = s.machine;
  run.error = homing_refusal(run.machine, s.caps);
  if (!run.error.empty()) return run;
  for (const int a : homing_order(run.machine)) {
    const plan::AxisConfig& ax = run.machine.axes[a];
    if (!ax.home.sim_switch_mm) {
      run.error = fmt::format("{}:{}:{}: axes.{}.home.sim_switch_mm: missing: homing on the simulated card needs "
                              "the simulated switch's place (mm from the start)",
                              run.machine.file, ax.home.loc.line, ax.home.loc.col, plan::kAxisLetters[a]);
      return run;
    }
  }
  s.place();
  run.switch_at = s.world.switch_at();
  run.result = home_axes(s.client, run.machine, s.caps);
  run.counts = s.counts();
  run.pins = s.world.pins();
  run.trips = s.world.trips();
  run.cycles = s.dut.cycle();
  return run;
}

template <class Card, class Dut>
SimProbeRun probe_on_card(const std::string& gcode_file, const std::string& machine_file) {
  SimProbeRun run;
  Session<Card, Dut> s;
  run.error = s.open(machine_file);
  if (!run.error.empty()) return run;
  run.machine = s.machine;
  const plan::Machine& m = run.machine;
  if (!s.caps.inputs) {
    run.error = "the card has no limit and probe inputs (READ 0x23 [24]): it cannot probe";
    return run;
  }
  std::ifstream in(gcode_file, std::ios::binary);
  if (!in) {
    run.error = fmt::format("{}: cannot open file", gcode_file);
    return run;
  }
  std::stringstream text;
  text << in.rdbuf();
  // The whole program read first, every probe taken as touching at its target: what
  // the text can be refused for is refused before anything is sent.
  plan::GcodeOptions dry = plan::gcode_options(m);
  dry.probe = [&m](const plan::ProbeRequest& r) {
    plan::ProbeResult res{true, r.to, ""};
    for (int a = 0; a < plan::kAxes; ++a) {
      const plan::AxisConfig& ax = m.axes[a];
      if (ax.present && (r.to[a] < ax.travel_min_mm || r.to[a] > ax.travel_max_mm))
        res.error = fmt::format("{} {:.3f} mm is outside the travel {:g}..{:g} mm of axis {}",
                                char(std::toupper(plan::kAxisLetters[a])), r.to[a], ax.travel_min_mm,
                                ax.travel_max_mm, plan::kAxisLetters[a]);
    }
    return res;
  };
  const plan::Result<plan::Job> checked = plan::parse_gcode(text.str(), gcode_file, dry);
  run.warnings = checked.warnings;
  if (!checked.ok()) {
    run.errors = checked.errors;
    return run;
  }
  if (m.inputs.sim_probe_axis < 0) {
    run.error = fmt::format("{}: inputs.sim_probe_mm: missing: probing on the simulated card needs the simulated "
                            "probe's place (one axis, mm from the start)",
                            m.file);
    return run;
  }
  s.place();
  std::vector<uint32_t> setup;
  card::encode_inputs(m, setup);
  s.client.send(setup);
  plan::GcodeOptions live = plan::gcode_options(m);
  live.probe = [&](const plan::ProbeRequest& r) {
    plan::ProbeResult res;
    if (!r.before.empty()) {
      plan::Job pre{gcode_file, std::vector<plan::MotionBlock>(r.before.begin(), r.before.end())};
      const BlocksRun b = run_blocks(s.client, m, s.caps, pre, card::seek_mode::off);
      run.moves += b.moves;
      if (!b.error.empty()) {
        res.error = "before the probe: " + b.error;
        return res;
      }
    }
    const bool active = (s.client.read_register(card::Register::inputs) & card::inputs_bits::probe) != 0;
    if (active == r.contact) {
      res.error = r.contact ? "the probe is already in contact" : "the probe is not in contact";
      return res;
    }
    plan::MotionBlock b;
    b.kind = plan::MotionKind::linear;
    b.loc = r.loc;
    b.start = r.from;
    b.end = r.to;
    b.feed = r.feed;
    const plan::Job move{gcode_file, {b}};
    const BlocksRun p = run_blocks(s.client, m, s.caps, move,
                                   r.contact ? card::seek_mode::probe_contact : card::seek_mode::probe_loss);
    run.moves += p.moves;
    res.error = p.error;
    res.tripped = p.tripped;
    ProbeEvent e;
    e.loc = r.loc;
    e.code = r.code;
    e.tripped = p.tripped;
    for (int a = 0; a < plan::kAxes; ++a) {
      e.counts[a] = p.positions.at(size_t(a));
      res.at[a] = m.axes[a].present ? double(e.counts[a]) / m.axes[a].steps_per_mm : r.from[a];
    }
    e.at = res.at;
    run.probes.push_back(e);
    return res;
  };
  const plan::Result<plan::Job> job = plan::parse_gcode(text.str(), gcode_file, live);
  run.errors = job.errors;
  if (job.ok()) {
    const std::vector<plan::MotionBlock> rest(job.value->blocks.begin() + std::ptrdiff_t(job.value->probed_blocks),
                                              job.value->blocks.end());
    if (!rest.empty()) {
      const BlocksRun b = run_blocks(s.client, m, s.caps, plan::Job{gcode_file, rest}, card::seek_mode::off);
      run.moves += b.moves;
      if (!b.error.empty()) run.errors.push_back({gcode_file, {}, "after the last probe: " + b.error});
    }
  }
  run.counts = s.counts();
  run.pins = s.world.pins();
  run.contacts = s.world.contacts();
  run.probe_at = s.world.probe_at();
  run.cycles = s.dut.cycle();
  return run;
}

template <class Card>
SimHomeRun home_on_engine(const std::string& machine_file, Engine e) {
  switch (e) {
    case Engine::model: return home_on_card<Card, sim::FastCardDut<Card>>(machine_file);
    case Engine::rtl: return home_on_card<Card, sim::RtlDut<Card>>(machine_file);
    case Engine::lockstep: break;
  }
  return home_on_card<Card, sim::TwinCardDut<Card>>(machine_file);
}

template <class Card>
SimProbeRun probe_on_engine(const std::string& gcode_file, const std::string& machine_file, Engine e) {
  switch (e) {
    case Engine::model: return probe_on_card<Card, sim::FastCardDut<Card>>(gcode_file, machine_file);
    case Engine::rtl: return probe_on_card<Card, sim::RtlDut<Card>>(gcode_file, machine_file);
    case Engine::lockstep: break;
  }
  return probe_on_card<Card, sim::TwinCardDut<Card>>(gcode_file, machine_file);
}

}  // namespace

SimHomeRun home_on_sim(const std::string& machine_file, std::string_view board, std::string_view engine) {
  const std::optional<Engine> e = parse_engine(engine);
  if (!e) throw std::invalid_argument(fmt::format("no engine '{}' (model, rtl, lockstep)", engine));
#define CPSTEP_HOME_ON(name) \
  if (board == #name) return home_on_engine<sim::CardOf<builds::name, Vcp_card_##name>>(machine_file, *e);
  CPSTEP_FOR_EACH_BOARD(CPSTEP_HOME_ON)
#undef CPSTEP_HOME_ON
  throw std::invalid_argument(fmt::format("no simulated board '{}' (boards: {})", board, card::board_names()));
}

SimProbeRun probe_job_on_sim(const std::string& gcode_file, const std::string& machine_file, std::string_view board,
                             std::string_view engine) {
  const std::optional<Engine> e = parse_engine(engine);
  if (!e) throw std::invalid_argument(fmt::format("no engine '{}' (model, rtl, lockstep)", engine));
#define CPSTEP_PROBE_ON(name) \
  if (board == #name) return probe_on_engine<sim::CardOf<builds::name, Vcp_card_##name>>(gcode_file, machine_file, *e);
  CPSTEP_FOR_EACH_BOARD(CPSTEP_PROBE_ON)
#undef CPSTEP_PROBE_ON
  throw std::invalid_argument(fmt::format("no simulated board '{}' (boards: {})", board, card::board_names()));
}

bool job_probes(const std::string& gcode_file) {
  return plan::file_has_probe_words(gcode_file);  // line by line: the text is not held
}

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
#include "run/home.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "card/frame.h"
#include "card/job.h"
#include "card/protocol.h"
#include "plan/gcode.h"
#include "run/card_job.h"

namespace cpstep::run {

std::vector<int> homing_order(const plan::Machine& m) {
  std::vector<int> order;
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present && m.axes[a].home.present) order.push_back(a);
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return m.axes[x].home.sequence < m.axes[y].home.sequence; });
  return order;
}

std::string homing_refusal(const plan::Machine& m, const card::CardCaps& caps) {
  if (homing_order(m).empty()) return fmt::format("{}: no axis has an [axes.X.home] table", m.file);
  if (!caps.inputs) return "the card has no limit and probe inputs (READ 0x23 [24]): it cannot home";
  return "";
}

namespace {

// The machine the homing moves are planned on: the travel limits do not hold while
// the position is not known (LinuxCNC lifts its soft limits while homing too).
plan::Machine homing_machine(const plan::Machine& m) {
  plan::Machine h = m;
  for (plan::AxisConfig& ax : h.axes) {
    ax.travel_min_mm = -1e9;
    ax.travel_max_mm = 1e9;
  }
  return h;
}

std::string first_error(const std::vector<plan::Diagnostic>& errors) {
  return errors.empty() ? std::string("unknown error") : errors.front().message;
}

}  // namespace

BlocksRun run_blocks(card::CardClient& c, const plan::Machine& m, const card::CardCaps& caps, const plan::Job& job,
                     uint32_t seek) {
  BlocksRun o;
  const card::Reply before = c.poll();
  plan::PerAxis<int64_t> at{};
  for (int i = 0; i < plan::kAxes && size_t(i) < before.positions.size(); ++i) at[i] = before.positions[size_t(i)];
  o.positions = before.positions;
  plan::Result<CardJob> planned = plan_card_job(job, m, caps, at);
  if (!planned.errors.empty() || !planned.value) {
    o.error = first_error(planned.errors);
    return o;
  }
  CardJob& cj = *planned.value;
  cj.wire.seek = seek;
  std::vector<uint32_t> words;
  if (caps.ptimer) {
    // A phase-timer card's job (its phases and segments as planned): the seek's CONFIG
    // after its preamble.
    if (!c.options().ptimer)
      throw std::logic_error("run_blocks: a phase-timer card needs a client that frames its commands");
    words = cj.words;
    std::vector<uint32_t> arm;
    if (seek != card::seek_mode::off) card::encode_config(0, card::ConfigField::seek, seek, arm);
    words.insert(words.begin() + std::ptrdiff_t(cj.preamble_words), arm.begin(), arm.end());
  } else {
    words = card::encode_job(cj.machine, cj.wire);
  }
  const double t0 = c.link().now_s();
  const double budget = 2 * cj.planned.stats.duration_s + 1;
  bool out_of_time = false;
  // Wait while the card runs, or has not started yet; give up at a fault, at the trip
  // (stopped after moving), or past the budget.
  const auto keep = [&](const card::Reply& r) {
    const card::Status st = card::decode_status(r.status);
    if (st.fault) return false;
    if (c.link().now_s() - t0 > budget) {
      out_of_time = true;
      return false;
    }
    return st.running || r.moves == before.moves;
  };
  const size_t sent = c.send(words, keep);
  if (sent == words.size()) c.wait_until_stopped(keep);
  const card::Reply after = c.poll();
  const card::Status st = card::decode_status(after.status);
  o.positions = after.positions;
  o.moves = after.moves - before.moves;
  // FLUSH first: a READ waits behind the words the card holds, and a tripped card
  // holds the rest of the move.
  if (seek != card::seek_mode::off || sent < words.size() || st.running) c.urgent(card::urgent::flush);
  // (READ 0x27's tripped stays until the next seek is armed: a move without one
  // trips nothing.)
  if (seek != card::seek_mode::off) {
    o.tripped = (c.read_register(card::Register::inputs) & card::inputs_bits::tripped) != 0;
    if (!o.tripped) {
      std::vector<uint32_t> off;
      card::encode_config(0, card::ConfigField::seek, card::seek_mode::off, off);
      c.send(off);
    }
  }
  if (st.fault) {
    const card::ErrorName n = card::error_name(st.err_code);
    o.error = fmt::format("the card latched {} ({}): {}", n.name, st.err_code, n.meaning);
  } else if (out_of_time) {
    o.error = fmt::format("the move did not end within {:.1f} s", budget);
  }
  return o;
}

namespace {

class Homer {
 public:
  Homer(card::CardClient& c, const plan::Machine& m, const card::CardCaps& caps)
      : c_(c), m_(m), hm_(homing_machine(m)), caps_(caps) {}

  HomeResult run() {
    HomeResult r;
    // The switches enabled and filtered as configured before the first look at them.
    std::vector<uint32_t> setup;
    card::encode_inputs(m_, setup);
    if (c_.send(setup) != setup.size()) {
      r.error = "the card did not take the inputs' configuration";
      return r;
    }
    for (const int a : homing_order(m_)) {
      r.axes.push_back({});
      std::string e = home(a, r.axes.back());
      if (!e.empty()) {
        r.error = fmt::format("homing {}: {}", char(std::toupper(plan::kAxisLetters[a])), e);
        break;
      }
    }
    return r;
  }

 private:
  struct Outcome {
    bool tripped = false;
    int64_t count = 0;
    std::string error;
  };

  int64_t count(int a) { return c_.poll().positions.at(size_t(a)); }

  bool switch_closed(int a, bool at_max) {
    const uint32_t in = c_.read_register(card::Register::inputs);
    return (in >> (at_max ? 8 + a : a) & 1) != 0;
  }

  // One move of axis `a` by `delta_mm` at `speed` mm/s from where the card stands,
  // the seek armed in `seek` (card::seek_mode); runs it to its end or its trip.
  Outcome move(int a, double delta_mm, double speed, uint32_t seek) {
    Outcome o;
    const card::Reply before = c_.poll();
    plan::PerAxis<int64_t> at{};
    plan::PerAxis<double> at_mm{};
    for (int i = 0; i < plan::kAxes; ++i) {
      at[i] = before.positions.at(size_t(i));
      if (hm_.axes[i].present) at_mm[i] = double(at[i]) / hm_.axes[i].steps_per_mm;
    }
    const std::string text = fmt::format("G21 G91 G1 {}{:.6f} F{:.6f}\n", char(std::toupper(plan::kAxisLetters[a])),
                                         delta_mm, speed * 60);
    plan::Result<plan::Job> job = plan::parse_gcode(text, "homing", plan::gcode_options(hm_, at_mm));
    if (!job.errors.empty() || !job.value) {
      o.error = first_error(job.errors);
      return o;
    }
    const BlocksRun r = run_blocks(c_, hm_, caps_, *job.value, seek);
    o.tripped = r.tripped;
    o.count = r.positions.at(size_t(a));
    o.error = r.error;
    return o;
  }

  std::string home(int a, HomedAxis& h) {
    const plan::AxisConfig& ax = m_.axes[a];
    const plan::HomeConfig& cfg = ax.home;
    h.axis = a;
    const double toward = cfg.at_max ? 1 : -1;
    const double search_mm = 1.5 * (ax.travel_max_mm - ax.travel_min_mm) + 2 * cfg.backoff_mm;
    const auto step = [&](const char* what, double delta, double speed, uint32_t seek) {
      const int64_t from = count(a);
      Outcome o = move(a, delta, speed, seek);
      h.moves.push_back({what, from, o.count, o.tripped});
      return o;
    };
    const auto closed_error = [&] {
      return fmt::format("its {} switch is still closed after backing off {} mm", cfg.at_max ? "max" : "min",
                         cfg.backoff_mm);
    };
    // On the switch already: off it first.
    if (switch_closed(a, cfg.at_max)) {
      const Outcome o = step("clear", -toward * cfg.backoff_mm, cfg.search_mm_s, card::seek_mode::off);
      if (!o.error.empty()) return o.error;
      if (switch_closed(a, cfg.at_max)) return closed_error();
    }
    Outcome o = step("search", toward * search_mm, cfg.search_mm_s, card::seek_mode::limit);
    if (!o.error.empty()) return o.error;
    if (!o.tripped) return fmt::format("no switch within {:.3f} mm", search_mm);
    h.search_trip = o.count;
    o = step("backoff", -toward * cfg.backoff_mm, cfg.search_mm_s, card::seek_mode::off);
    if (!o.error.empty()) return o.error;
    if (switch_closed(a, cfg.at_max)) return closed_error();
    o = step("latch", toward * 2 * cfg.backoff_mm, cfg.latch_mm_s, card::seek_mode::limit);
    if (!o.error.empty()) return o.error;
    if (!o.tripped) return fmt::format("the switch did not trip again within {:.3f} mm", 2 * cfg.backoff_mm);
    h.latch_trip = o.count;
    h.offset = h.latch_trip - std::llround(cfg.position_mm * ax.steps_per_mm);
    o = step("final", -toward * cfg.backoff_mm, cfg.search_mm_s, card::seek_mode::off);
    if (!o.error.empty()) return o.error;
    h.final_count = o.count;
    h.final_mm = double(h.final_count - h.offset) / ax.steps_per_mm;
    return "";
  }

  card::CardClient& c_;
  const plan::Machine& m_;
  plan::Machine hm_;
  const card::CardCaps& caps_;
};

}  // namespace

HomeResult home_axes(card::CardClient& c, const plan::Machine& m, const card::CardCaps& caps) {
  HomeResult r;
  r.error = homing_refusal(m, caps);
  if (!r.error.empty()) return r;
  return Homer(c, m, caps).run();
}

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
#include "run/link_run.h"

#include <limits>
#include <string_view>

#include <fmt/format.h>

#include "card/frame.h"
#include "run/feed_driver.h"

namespace cpstep::run {

namespace {

// A stopped card whose command buffer stays full this long is stalled (as the
// sim's 10^6 cycles at 48 MHz).
constexpr double kStallSeconds = 0.02;

}  // namespace

CardRun run_on_link(const CardJob& job, card::Link& link, const LinkRunOptions& o) {
  CardRun run;
  run.pins_observed = false;
  card::ClientOptions co = feed_waits(keeping_alive(o.client, o.watchdog_s), !o.feed.empty(), bool(o.feed_toggle));
  co.axes = plan::kAxes;
  co.ptimer = job.caps.ptimer;  // its commands' lengths
  co.buffer_words = job.caps.command_buffer_words();
  card::CardClient client(link, co);
  const double t0 = link.now_s();
  const auto finish = [&] {
    run.link = {"spidev", link.name(), client.stats(), o.sck_hz, 0, 0, link.now_s() - t0};
    run.sim_cycles = 0;
    return run;
  };

  card::Reply first;
  try {
    first = client.poll();
  } catch (const card::CardError& e) {
    run.faults.push_back(host_fault(HostFault::link, fmt::format("{}; nothing was sent", e.what())));
    return finish();
  }
  for (int a = 0; a < plan::kAxes; ++a) run.start_position[a] = first.positions[size_t(a)];
  const card::Status st0 = card::decode_status(first.status);
  // An E-stop latched (docs/CORE.md "Faults"): only the acknowledge clears it.
  const bool estop_latched = st0.fault && std::string_view(card::error_name(st0.err_code).name) == "ESTOP";
  std::string refuse;
  if (run.start_position != job.start)
    refuse = fmt::format("the card is at {}, but the job was planned from {} (cpstep run plans from the "
                         "position the card reports)",
                         axes_text(run.start_position, job.machine), axes_text(job.start, job.machine));
  else if (st0.running) refuse = "the card is running";
  else if (first.flags & card::reply_flag::busy) refuse = "the card's command buffer holds words";
  else if (first.flags & card::reply_flag::estop) refuse = "the card's E-stop input is active";
  else if (estop_latched && !o.ack_estop)
    refuse = "the card latched an E-stop (ESTOP, code 10); with its input released, acknowledge it "
             "(cpstep run --ack-estop)";
  if (!refuse.empty()) {
    take_reply(run, first);
    run.faults.push_back(host_fault(HostFault::link, fmt::format("{}; nothing was sent", refuse)));
    return finish();
  }
  // What the card says it is: the job must have been planned for it.
  try {
    const card::CardCaps caps = card::read_caps(client);
    if (const std::string why = card::unusable(caps, plan::kAxes); !why.empty()) refuse = why;
    else if (caps != job.caps)
      refuse = fmt::format("the job was planned for {}, but the card is {}", card::describe(job.caps),
                           card::describe(caps));
  } catch (const card::CardError& e) {
    refuse = fmt::format("reading the card's capabilities: {}", e.what());
  }
  if (!refuse.empty()) {
    take_reply(run, client.last());
    run.faults.push_back(host_fault(HostFault::link, fmt::format("{}; nothing was sent", refuse)));
    return finish();
  }
  std::vector<uint32_t> words;
  if (estop_latched) {
    try {
      client.urgent(card::urgent::ack);  // the operator's acknowledge (ack_estop)
    } catch (const card::CardError& e) {
      take_reply(run, client.last());
      run.faults.push_back(host_fault(HostFault::link, fmt::format("acknowledging the E-stop: {}", e.what())));
      return finish();
    }
  } else if (st0.fault) {
    card::encode_control(false, false, true, words);  // CLEAR the fault left latched
  }
  const std::vector<uint32_t> dog = watchdog_words(job, o.watchdog_s);
  words.insert(words.end(), dog.begin(), dog.end());
  const uint64_t before_job = words.size();  // the job's first word
  WordSource source(job, std::move(words));
  // The card's segment count goes on from the last job's.
  client.set_buffered_time([&source, &first, before_job](const card::Reply& r, uint64_t handed) {
    if (!card::decode_status(r.status).running) return std::numeric_limits<double>::infinity();
    return source.buffered_seconds(uint32_t(r.segments - first.segments), uint32_t(r.moves - first.moves),
                                   handed > before_job ? handed - before_job : 0);
  });

  const double timeout = o.timeout_s > 0 ? o.timeout_s : 2 * job.planned.stats.duration_s + 10;
  enum class GaveUp { no, out_of_time, stalled } gave_up = GaveUp::no;
  card::StallWatch stall(kStallSeconds);
  const auto keep_waiting = [&](const card::Reply& r) {
    const double now = link.now_s();
    if (o.progress) o.progress(r.moves - first.moves, job.moves());
    if (now - t0 >= timeout) gave_up = GaveUp::out_of_time;
    else if (stall.stalled(r, now)) gave_up = GaveUp::stalled;
    return gave_up == GaveUp::no;
  };
  size_t sent = 0;
  // What was sent and the feed frames applied, kept when the sending stops on an error.
  FeedOutcome fed;
  // START: the first reply that shows the card running (the feed's events are timed from it).
  std::optional<double> started_at;
  const auto watching = [&](const card::Reply& r) {
    if (!started_at && card::decode_status(r.status).running) started_at = link.now_s();
    return keep_waiting(r);
  };
  const auto since_start = [&]() -> std::optional<double> {
    if (!started_at) return std::nullopt;
    return link.now_s() - *started_at;
  };
  try {
    const FeedPlan plan{o.override_pct, o.feed, o.feed_toggle};
    if (plan.any() && !job.caps.feed)
      throw card::CardError(fmt::format("the card, {}, has no feed hold or override", card::card_name(job.caps)));
    send_with_feed(client, source, plan, watching, since_start, fed);
    sent = fed.take(run.feed, run.feed_scaled);
    if (sent == source.total() && fed.stopped) watchdog_off(client, o.watchdog_s, keep_waiting);
    if (gave_up == GaveUp::out_of_time) {
      std::vector<uint32_t> abort;
      card::encode_control(false, true, false, abort);
      const double until = link.now_s() + 1;
      client.send(abort, [&](const card::Reply&) { return link.now_s() < until; });
      client.settle([&](const card::Reply&) { return link.now_s() < until; });
    }
  } catch (const card::CardError& e) {
    sent = fed.take(run.feed, run.feed_scaled);
    run.faults.push_back(host_fault(HostFault::link, e.what()));
  } catch (const JobFileChanged& e) {
    sent = fed.take(run.feed, run.feed_scaled);
    run.faults.push_back(stop_for_changed_file(e, source, client, keep_waiting, since_start, run));
  }
  if (gave_up == GaveUp::out_of_time)
    run.faults.push_back(host_fault(HostFault::timeout,
                                    fmt::format("the card was still running after {:.3f} s; the host sent "
                                                "CONTROL abort",
                                                timeout)));
  else if (gave_up == GaveUp::stalled)
    run.faults.push_back(host_fault(HostFault::stall,
                                    fmt::format("the card, stopped, took no command word for {:.3f} s "
                                                "(word {} of {} sent)",
                                                kStallSeconds, sent, source.total())));
  try {
    take_reply(run, client.poll());
    const card::Reply& last = client.last();
    run.moves_done = last.moves - first.moves;
    run.segments_done = last.segments - first.segments;
    run.stretch_count = last.stretch - first.stretch;
  } catch (const card::CardError& e) {
    run.faults.push_back(host_fault(HostFault::link, e.what()));
  }
  if (o.progress) o.progress(run.moves_done, job.moves());

  add_card_faults(job, run);
  if (job.checkpoint_count) {
    plan::PerAxis<int64_t> want{}, moved{};
    for (int a = 0; a < plan::kAxes; ++a) {
      want[a] = job.final_position[a] - job.start[a];
      moved[a] = run.position[a] - run.start_position[a];
    }
    if (moved != want)
      run.faults.push_back(host_fault(HostFault::position,
                                      fmt::format("the card moved {} (from {} to {}) but the plan moves {}",
                                                  axes_text(moved, job.machine),
                                                  axes_text(run.start_position, job.machine),
                                                  axes_text(run.position, job.machine),
                                                  axes_text(want, job.machine))));
  }
  return finish();
}

}  // namespace cpstep::run

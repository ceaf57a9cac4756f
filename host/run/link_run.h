// SPDX-License-Identifier: MIT
// Runs a CardJob on a card over any card::Link — the transport `spidev` of
// `cpstep run`, and the same code over the simulated card in the tests. Nothing
// of the card's pins is seen: what the run reports is what the card's replies say.
#pragma once

#include <functional>

#include "card/card_client.h"
#include "card/link.h"
#include "run/card_job.h"
#include "run/sim_run.h"

namespace cpstep::run {

struct LinkRunOptions {
  card::ClientOptions client;  // axes is set to the machine's card (4)
  double timeout_s = 0;        // on the link's clock; 0: twice the planned job time plus 10 s
  double sck_hz = 0;           // the SCK rate, for the report
  // The card's watchdog for the job (docs/CORE.md "Watchdog"): set before it, kept
  // alive by a frame at least every quarter of it, off again at its end; 0: off.
  double watchdog_s = 0;
  // Called with (moves done, moves planned) at every wait.
  std::function<void(uint64_t, uint64_t)> progress;
  // An E-stop fault the card latched is cleared only by an explicit acknowledge
  // (docs/CORE.md "Faults"): with this set the host sends it (an URGENT ACK frame)
  // once the input is released; without it such a card is refused.
  bool ack_estop = false;
  // Feed (cards with FEED): as SimRunOptions's; the events' times count from the first
  // reply that shows the card running.
  double override_pct = 100;
  std::vector<FeedEvent> feed;
  std::function<bool()> feed_toggle;
};

// Polls the card; refuses to start (a LINK fault, nothing sent) when no card
// answers, when it is running or holds words, or when its E-stop input is
// active, or has an E-stop latched and ack_estop is not set; clears a fault it has
// latched (CONTROL clear before the job's words; an E-stop's by an URGENT ACK);
// sends the job; waits until it stopped; takes the final state from a POLL.
// Counters are the job's (the card's minus their values before it); positions
// are the card's, and the job's end is checked as start + the plan's end. A run
// longer than the timeout is stopped with CONTROL abort (it runs after the words
// already in the card's buffer) and reported as TIMEOUT.
CardRun run_on_link(const CardJob& job, card::Link& link, const LinkRunOptions& options);

}  // namespace cpstep::run

// SPDX-License-Identifier: MIT
// The loop both runners share (run_on_sim, run_on_link): send a job's words and wait
// for its end, sending the feed's URGENT frames (docs/CORE.md "Feed hold and
// override") as they fall due — the override before the words, each event when the
// time since START reaches it, each toggle (SIGUSR1) when asked — and recording them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "card/card_client.h"
#include "run/card_job.h"
#include "run/feed.h"

namespace cpstep::run {

struct FeedPlan {
  double override_pct = 100;     // 100: none sent
  std::vector<FeedEvent> events;  // at seconds from START, in order
  std::function<bool()> toggle;   // true once per toggle asked (HOLD, then RESUME, ...)
  [[nodiscard]] bool any() const { return override_pct != 100 || !events.empty() || toggle; }
};

struct FeedOutcome {
  size_t sent = 0;       // words handed to frames
  bool stopped = false;  // the wait for the end completed
  std::vector<FeedApplied> applied;

  // The frames applied moved into a run's record (`scaled`: any was sent);
  // returns the words sent.
  size_t take(std::vector<FeedApplied>& record, bool& scaled) {
    record = std::move(applied);
    applied.clear();
    scaled = !record.empty();
    return sent;
  }
};

// The client's options with no wait longer than the feed needs: 5 ms while events are
// planned (each lands within 5 ms of its time), 50 ms with a toggle (SIGUSR1).
card::ClientOptions feed_waits(card::ClientOptions client, bool events, bool toggle);

// Sends the words of `words` (a window of them at a time: a streamed job's are
// made as they go) with `client` and waits until the card stopped, as CardClient::send and
// wait_until_stopped do with `keep_waiting`, sending the plan's feed frames on the way.
// since_start_s: the card's seconds since START, nullopt before it started (events wait
// for it). The override goes before the words; an event due after the end is not sent.
// `out` is filled as it goes: when it throws what CardClient or the words throw
// (JobFileChanged), the words sent and the feed frames applied before are in it.
void send_with_feed(card::CardClient& client, WordSource& words, const FeedPlan& plan,
                    const card::CardClient::KeepWaiting& keep_waiting,
                    const std::function<std::optional<double>()>& since_start_s, FeedOutcome& out);

// The job's words stop short of its end (its file written over since it was
// planned: JobFileChanged). A card with FEED is held — its timer's scale ramps
// to 0, so the motion stops on the card's feed ramp, on the planned path, not
// at speed — and once it stands is flushed (its queues emptied, the run off,
// no fault) and resumed (not left held for the next job); a card without FEED
// runs what it holds and underruns. The HOLD goes into `applied`. Returns how
// the card was stopped, for the fault's message. Throws what CardClient throws.
std::string stop_short(card::CardClient& client, bool feed, const card::CardClient::KeepWaiting& keep_waiting,
                       const std::function<std::optional<double>()>& since_start_s,
                       std::vector<FeedApplied>& applied);

}  // namespace cpstep::run

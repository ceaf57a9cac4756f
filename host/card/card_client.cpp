// SPDX-License-Identifier: MIT
#include "card/card_client.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "card/protocol.h"

namespace cpstep::card {

namespace {

constexpr uint32_t kOpRead = 0x4;

std::string result_text(uint8_t code) {
  const ResultName n = frame_result_name(code);
  return std::string(n.name) + " (" + std::to_string(code) + "): " + n.meaning;
}

bool damage(uint8_t code) {
  return code == uint8_t(FrameResult::bad_crc) || code == uint8_t(FrameResult::truncated);
}

// A refusal the client repairs by sending the same frame again.
bool resendable(uint8_t code) { return damage(code) || code == uint8_t(FrameResult::no_room); }

uint16_t count_reads(std::span<const uint32_t> words, unsigned axes, bool ptimer) {
  uint16_t n = 0;
  for (size_t i = 0; i < words.size(); i += command_words(words[i], axes, ptimer))
    if (words[i] >> 28 == kOpRead) ++n;
  return n;
}

}  // namespace

CardClient::CardClient(Link& link, ClientOptions options) : link_(link), o_(options) {
  if (o_.axes < 1 || o_.axes > 8) throw std::invalid_argument("a card has 1 to 8 axes");
}

const Reply& CardClient::poll() {
  while (!poll_once()) {
  }
  return last_;
}

bool CardClient::poll_once() {
  const uint8_t seq = next_seq_++;
  const std::vector<uint8_t> bytes = encode_poll(seq, o_.axes);
  ++stats_.polls;
  return on_reply(link_.transfer(bytes), {Kind::poll, seq, 0});
}

void CardClient::send_frame(std::vector<uint32_t> frame_words, size_t caller_words) {
  const uint8_t seq = next_seq_++;
  const std::vector<uint8_t> bytes =
      encode_frame(FrameType::commands, seq, frame_words, reply_bytes(o_.axes));
  ++stats_.command_frames;
  Pending p;
  p.reads = count_reads(frame_words, o_.axes, o_.ptimer);
  p.caller_words = caller_words;
  p.seq = seq;
  const size_t n = frame_words.size();
  p.words = std::move(frame_words);
  // This reply reports on the frame before (pipelined: the previous COMMANDS frame).
  on_reply(link_.transfer(bytes), {Kind::commands, seq, n});
  pending_ = std::move(p);
}

bool CardClient::urgent(uint32_t word, const KeepWaiting& keep) {
  if (!settle(keep)) return false;
  for (unsigned tries = 0;; ++tries) {
    const uint8_t seq = next_seq_++;
    const uint32_t words[1] = {word};
    ++stats_.urgent_frames;
    // Nothing of it enters the buffer: accounted as a POLL is.
    on_reply(link_.transfer(encode_frame(FrameType::urgent, seq, words, reply_bytes(o_.axes))), {Kind::poll, seq, 0});
    do {
      if (keep && have_reply_ && !keep(last_)) return false;
    } while (!poll_once());
    if (last_.last_seq == seq && last_.last_result == uint8_t(FrameResult::ok)) {
      // After a FLUSH no word sent before it runs: the READs among them never reply.
      if (word & urgent::flush) reads_expected_ = last_.reads;
      return true;
    }
    if (!damage(last_.last_result) || tries >= o_.max_retries)
      throw CardError(link_.name() + ": the card refused URGENT frame " + std::to_string(seq) + ": " +
                      result_text(last_.last_result));
  }
}

bool CardClient::on_reply(std::span<const uint8_t> miso, const Sent& sent) {
  const size_t need = reply_bytes(o_.axes);
  if (miso.size() < need)
    throw LinkError(link_.name() + ": " + std::to_string(miso.size()) + " bytes came back for a transfer of " +
                    std::to_string(need) + " or more");
  const Reply r = decode_reply(miso.first(need), o_.axes);
  const Sent before = prev_;
  prev_ = sent;
  const bool ended_before = transfers_done_ > 0;
  const double now = link_.now_s();
  if (ended_before) stats_.longest_gap_s = std::max(stats_.longest_gap_s, now - last_frame_end_s_);
  last_frame_end_s_ = now;
  ++transfers_done_;
  ++stats_.transfers;
  stats_.bytes += miso.size();
  if (!r.ok()) {
    ++stats_.bad_replies;
    if (sent.kind == Kind::commands) unaccounted_ += sent.nwords;
    if (pending_ && pending_->state == State::sent && before.kind == Kind::commands &&
        before.seq == pending_->seq) {
      ++stats_.lost_results;
      if (!o_.confirm_each_frame)
        throw CardError(link_.name() + ": the result of COMMANDS frame " + std::to_string(before.seq) +
                        " was lost in a damaged reply (" + r.error + ")");
      pending_->state = State::lost;
    }
    if (++bad_in_a_row_ > o_.max_retries)
      throw CardError(link_.name() + ": " + std::to_string(bad_in_a_row_) + " bad replies in a row; the last: " +
                      r.error);
    return false;
  }
  bad_in_a_row_ = 0;
  if (ended_before && (r.flags & reply_flag::fresh))
    throw CardError(link_.name() + ": the card was reset during the session (its reply says no frame has "
                    "ended since its reset): the words in its buffer and its state are lost");
  if (!have_reply_) {
    first_ = r;
    have_reply_ = true;
    reads_expected_ = r.reads;
  }
  last_ = r;
  unaccounted_ = sent.kind == Kind::commands ? sent.nwords : 0;
  resolve(r, before);
  return true;
}

void CardClient::resolve(const Reply& r, const Sent& before) {
  if (before.kind == Kind::none) return;
  const bool about_pending = pending_ && pending_->state == State::sent && before.kind == Kind::commands &&
                             before.seq == pending_->seq;
  const auto mismatch = [&] {
    return CardError(link_.name() + ": the reply reports frame " + std::to_string(r.last_seq) +
                     " as accepted, but the frame before it was " + std::to_string(before.seq) +
                     " (another master on the bus?)");
  };
  if (!about_pending) {
    // A POLL, or a frame already settled: nothing of it executes either way.
    if (r.last_result != uint8_t(FrameResult::ok)) ++stats_.damaged;
    else if (r.last_seq != before.seq) throw mismatch();
    return;
  }
  if (r.last_result == uint8_t(FrameResult::ok)) {
    if (r.last_seq != before.seq) throw mismatch();
    stats_.words += pending_->caller_words;
    stats_.markers += pending_->words.size() - pending_->caller_words;
    reads_expected_ = uint16_t(reads_expected_ + pending_->reads);
    damaged_in_a_row_ = 0;
    pending_.reset();
    return;
  }
  const uint8_t code = r.last_result;
  if (damage(code)) ++stats_.damaged;
  if (code == uint8_t(FrameResult::no_room)) ++stats_.no_room;
  const std::string what = link_.name() + ": the card refused COMMANDS frame " + std::to_string(pending_->seq) +
                           " (" + std::to_string(pending_->words.size()) + " words): " + result_text(code);
  if (!resendable(code)) throw CardError(what);
  if (prev_.kind == Kind::commands)
    throw CardError(what + "; the next frame was already sent, so its commands would run out of order");
  pending_->state = State::refused;
  pending_->refusal = code;
}

size_t CardClient::room() const {
  return last_.free_words > unaccounted_ ? last_.free_words - unaccounted_ : 0;
}

bool CardClient::pause(const KeepWaiting& keep, double seconds) {
  if (keep && !keep(last_)) return false;
  ++stats_.waits;
  double wait = std::max(seconds, o_.poll_interval_s);
  if (o_.keepalive_s > 0) wait = std::min(wait, o_.keepalive_s);  // the watchdog's frame comes in time
  link_.wait(wait);
  return true;
}

double CardClient::buffered_s() const {
  return buffered_time_ && have_reply_ ? buffered_time_(last_, handed_) : std::numeric_limits<double>::infinity();
}

bool CardClient::may_batch() const {
  if (!buffered_time_ || o_.buffer_words == 0 || o_.batch_share <= 0) return false;
  // Only while the card runs (before START nothing drains: what fits goes, as
  // without a plan) and holds enough motion (short of it: whatever fits goes).
  const double held = buffered_s();
  return std::isfinite(held) && held >= o_.urgent_s;
}

size_t CardClient::batch_words(size_t remaining) const {
  if (!may_batch()) return 0;
  return std::min(remaining, size_t(o_.batch_share * double(o_.buffer_words)));
}

bool CardClient::wait_for_room(size_t least, const KeepWaiting& keep, size_t batch) {
  double since = -1;  // when this wait began (the first time room was short)
  const size_t n = std::max(least, batch);
  for (;;) {
    if (!have_reply_) {
      poll();
      continue;
    }
    // A batch's room, unless the card stopped or runs short of motion meanwhile.
    if (room() >= least && (room() >= n || !may_batch())) {
      if (since >= 0) room_wait_avg_s_ = 0.7 * room_wait_avg_s_ + 0.3 * (link_.now_s() - since);
      return true;
    }
    if (!(last_.flags & reply_flag::busy) && unaccounted_ == 0) {
      if (room() >= least) return true;  // an empty buffer holds no batch: what fits goes
      throw CardError(link_.name() + ": a frame of " + std::to_string(n) + " words does not fit the card's empty "
                      "command buffer of " + std::to_string(last_.free_words) + " words");
    }
    double delay = 0;
    const double now = link_.now_s();
    if (since < 0) since = now;
    const double left = room_wait_avg_s_ - (now - since);  // of a wait like the last ones
    if (buffered_time_) {
      // The plan says how long the card can run on what it holds: a quarter to
      // a half of that, and within it a share of what is left of a wait like
      // the last ones (a few POLLs a wait, each closer than the one before).
      const double held = buffered_s();
      delay = std::max(o_.first_wait_share * left, 0.0);
      if (std::isfinite(held)) delay = std::clamp(delay, 0.25 * held, 0.5 * held);
    } else if (now == since) {
      delay = std::min(o_.first_wait_share * room_wait_avg_s_, o_.max_first_wait_s);
    }
    if (!pause(keep, delay)) return false;
    poll_once();
  }
}

bool CardClient::settle_lost(const KeepWaiting& keep) {
  // The marker READ is the frame's last command: once the card's READ count has
  // moved past every READ accepted before and this frame's, the frame ran; if
  // the buffer is empty and the count did not move, it was refused.
  for (;;) {
    if (poll_once()) {
      const auto ran = int16_t(uint16_t(last_.reads - reads_expected_));
      if (ran == int16_t(pending_->reads)) {
        stats_.words += pending_->caller_words;
        stats_.markers += pending_->words.size() - pending_->caller_words;
        reads_expected_ = uint16_t(reads_expected_ + pending_->reads);
        pending_.reset();
        return true;
      }
      if (!(last_.flags & reply_flag::busy)) {
        if (ran != 0)
          throw CardError(link_.name() + ": the card's READ count is " + std::to_string(last_.reads) +
                          ", neither " + std::to_string(reads_expected_) + " nor " +
                          std::to_string(uint16_t(reads_expected_ + pending_->reads)) +
                          ": the result of COMMANDS frame " + std::to_string(pending_->seq) +
                          " cannot be told");
        pending_->state = State::refused;
        pending_->refusal = 0xFF;
        return true;
      }
    }
    if (!pause(keep)) return false;
  }
}

bool CardClient::settle(const KeepWaiting& keep) {
  while (pending_) {
    switch (pending_->state) {
      case State::sent:
        poll_once();
        break;
      case State::lost:
        if (!o_.confirm_each_frame)
          throw CardError(link_.name() + ": the result of COMMANDS frame " + std::to_string(pending_->seq) +
                          " was lost");
        if (!settle_lost(keep)) return false;
        break;
      case State::refused: {
        if (pending_->refusal != uint8_t(FrameResult::no_room) && ++damaged_in_a_row_ > o_.max_retries)
          throw CardError(link_.name() + ": COMMANDS frame refused " + std::to_string(damaged_in_a_row_) +
                          " times in a row, the last: " + result_text(pending_->refusal));
        Pending p = std::move(*pending_);
        pending_.reset();
        if (!wait_for_room(p.words.size(), keep)) {
          pending_ = std::move(p);
          return false;
        }
        ++stats_.resent;
        send_frame(std::move(p.words), p.caller_words);
        break;
      }
    }
  }
  return true;
}

size_t CardClient::send(std::span<const uint32_t> words, const KeepWaiting& keep) {
  // Whole commands only (throws std::invalid_argument naming the word).
  split_commands(words, o_.axes, SIZE_MAX, o_.ptimer);
  const size_t marker = marker_words();
  size_t pos = 0;
  for (;;) {
    if (pending_ && (o_.confirm_each_frame || pending_->state != State::sent)) {
      if (!settle(keep)) return pos;
      continue;
    }
    if (pos == words.size()) return pos;
    if (!have_reply_) {
      poll();
      continue;
    }
    const size_t first_len = command_words(words[pos], o_.axes, o_.ptimer);
    if (o_.max_frame_words && first_len + marker > o_.max_frame_words)
      throw std::invalid_argument("a command of " + std::to_string(first_len) + " words (and " +
                                  std::to_string(marker) + " marker) does not fit frames of at most " +
                                  std::to_string(o_.max_frame_words) + " words");
    // Batching: mid-stream, a frame waits for a share of the buffer while the
    // card holds enough motion.
    if (const size_t want = batch_words(words.size() - pos + marker); want > room()) {
      if (!wait_for_room(first_len + marker, keep, want)) return pos;
    }
    size_t limit = room();
    if (o_.max_frame_words) limit = std::min(limit, o_.max_frame_words);
    size_t take = 0;
    while (pos + take < words.size()) {
      const size_t len = command_words(words[pos + take], o_.axes, o_.ptimer);
      if (take + len + marker > limit) break;
      take += len;
    }
    if (take == 0) {
      if (!wait_for_room(first_len + marker, keep)) return pos;
      continue;
    }
    std::vector<uint32_t> frame(words.begin() + long(pos), words.begin() + long(pos + take));
    if (marker) encode_read(Register::id, 0, frame);
    send_frame(std::move(frame), take);
    pos += take;
    handed_ += take;
  }
}

uint32_t CardClient::read_register(Register r, unsigned axis, const KeepWaiting& keep) {
  const auto gave_up = [&] { return CardError(link_.name() + ": gave up waiting to read a register"); };
  if (!settle(keep)) throw gave_up();
  if (!wait_for_room(1, keep)) throw gave_up();
  std::vector<uint32_t> frame;
  encode_read(r, axis, frame);
  send_frame(std::move(frame), 1);
  if (!settle(keep)) throw gave_up();
  // Accepted: wait until the core has taken it (its READ count catches up).
  for (;;) {
    poll();
    if (last_.reads == reads_expected_) return last_.last_read;
    if (!pause(keep)) throw gave_up();
  }
}

CardCaps read_caps(CardClient& client, const CardClient::KeepWaiting& keep) {
  std::array<uint32_t, kCapsRegisters.size()> v{};
  for (size_t i = 0; i < v.size(); ++i) v[i] = client.read_register(kCapsRegisters[i], 0, keep);
  return decode_caps(v);
}

bool CardClient::wait_until_stopped(const KeepWaiting& keep) {
  for (;;) {
    if (!settle(keep)) return false;
    poll();
    if (pending_) continue;
    if (!(last_.status & 1) && !(last_.flags & reply_flag::busy)) return true;
    // The card cannot be done before the motion it holds is (the plan's bound).
    const double left = buffered_s();
    if (!pause(keep, std::isfinite(left) ? left : 0)) return false;
  }
}

}  // namespace cpstep::card

// SPDX-License-Identifier: MIT
// The host's side of the card's SPI protocol (docs/PROTOCOL.md) over any Link:
// command words go out as COMMANDS frames of whole commands that fit the room
// the card announces, every reply is checked (CRC, magic, last_seq,
// last_result), refused frames are sent again when that is safe, and the card's
// state comes back in POLL replies.
//
// Order. The card does not order frames: if frame k is refused and k+1
// accepted, k+1 runs without k. So with `confirm_each_frame` (the default) the
// client learns each COMMANDS frame's result from a POLL before it sends the
// next one, and resends a frame the card refused as damaged (BAD_CRC,
// TRUNCATED) or for lack of room (NO_ROOM). Each such frame ends with a READ of
// the card's id register (a *marker*): if the reply that carries a frame's
// result is itself damaged, the result is lost (the next reply reports the POLL
// in between), and the card's count of READ replies tells whether the frame ran
// — the client waits until that count moves or the card's buffer is empty. So
// nothing runs twice and nothing is skipped.
//
// Without `confirm_each_frame` (pipelined: `cpstep sim`, where frames are never
// damaged) the next frame's own reply carries the result and no marker is sent;
// a refusal seen there is an error, since the frame after it already went in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "card/caps.h"
#include "card/frame.h"
#include "card/link.h"

namespace cpstep::card {

// The card refused a frame in a way the client does not repair (with its code
// name), stopped answering, or was reset during the session.
class CardError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ClientOptions {
  unsigned axes = 4;              // the card's N (the reply has 7 + N words)
  bool ptimer = false;            // a phase-timer card (READ 0x23 [26]): its commands' lengths (command_words)
  size_t max_frame_words = 0;     // at most this many words per frame (marker included); 0: no limit of
                                  // the host's (the card's free words always limit)
  double poll_interval_s = 1e-3;  // between POLLs while waiting for room, a lost result or the end
  // > 0: no wait between frames is longer than this (the card's watchdog: a quarter of
  // its timeout keeps it alive, docs/CORE.md "Watchdog"); 0: no such bound.
  double keepalive_s = 0;
  // Waiting for room, the first POLL comes after this share of the last waits for
  // room (their moving average), at least poll_interval_s and at most
  // max_first_wait_s; then every poll_interval_s. The card drains its buffer at
  // the job's pace, so most waits are alike: fewer POLLs on the link. 0: every
  // poll_interval_s from the start.
  double first_wait_share = 0.8;
  // The ceiling keeps a frame from being held back longer than the card's buffer
  // and queues can run on their own after a slow stretch (a long segment, then
  // short ones); a job whose buffered motion is shorter than this starves on it.
  double max_first_wait_s = 0.01;
  // Batching, with a BufferedTime (CardClient::set_buffered_time): a frame in the
  // middle of a stream waits until this share of the card's command buffer
  // (buffer_words, its CBUF_WORDS) is free, so that few large frames go instead
  // of one small one per segment and a POLL or two for each; every wait is at
  // most half the motion the card still holds, and while that is below urgent_s,
  // or the card is not running (before START), whatever fits goes at once. 0 (or
  // no BufferedTime, or buffer_words 0): a frame goes as soon as the next command
  // fits.
  size_t buffer_words = 0;
  double batch_share = 0.25;
  double urgent_s = 0.02;
  bool confirm_each_frame = true; // see above
  unsigned max_retries = 16;      // a frame damaged this many times in a row, or this many bad replies
                                  // in a row: CardError
};

// What went over the link.
struct LinkStats {
  uint64_t transfers = 0;       // CS-low periods (frames of any kind)
  uint64_t command_frames = 0;  // COMMANDS frames, resends included
  uint64_t polls = 0;           // POLL frames
  uint64_t urgent_frames = 0;   // URGENT frames, resends included
  uint64_t bytes = 0;           // bytes clocked out (and in): frames padded to a whole reply
  uint64_t words = 0;           // command words the card accepted (markers not included)
  uint64_t markers = 0;         // marker READs the card accepted
  uint64_t resent = 0;          // COMMANDS frames sent again
  uint64_t damaged = 0;         // frames of ours the card refused as BAD_CRC or TRUNCATED
  uint64_t no_room = 0;         // frames of ours refused with NO_ROOM
  uint64_t bad_replies = 0;     // replies with a CRC mismatch or without the magic byte
  uint64_t lost_results = 0;    // COMMANDS frames whose result reply was damaged (settled by the marker)
  uint64_t waits = 0;           // waits between POLLs (poll_interval_s, or longer: first_wait_share)
  // The longest time on the link's clock from one frame's end to the next's: what the
  // card's watchdog sees of the host (docs/CORE.md "Watchdog").
  double longest_gap_s = 0;
};

class CardClient {
 public:
  // Called with the latest good reply before each wait; false gives up the wait
  // (send and wait_until_stopped then return early).
  using KeepWaiting = std::function<bool(const Reply&)>;
  // The seconds of motion the card still holds, at least (a lower bound: the
  // planned time from the end of the segment it runs to the end of the last
  // one whose words are handed to frames), given its latest reply and how many
  // words send() has handed to frames since the client began; infinity when
  // the card is not consuming (not started). The caller knows the plan.
  using BufferedTime = std::function<double(const Reply&, uint64_t words_handed)>;

  explicit CardClient(Link& link, ClientOptions options = {});

  // Sizes waits and batches frames by the motion buffered in the card (see
  // ClientOptions::batch_share).
  void set_buffered_time(BufferedTime f) { buffered_time_ = std::move(f); }

  // POLLs until a good reply comes (at most max_retries bad ones) and returns it.
  const Reply& poll();

  // Sends `words` (whole commands, docs/CORE.md) in order, in frames that fit the
  // card's free words. With confirm_each_frame it returns when every frame is
  // accepted; pipelined, the last frame's result is learned by the next transfer.
  // Returns the number of words handed to frames: words.size() unless
  // keep_waiting gave up. Throws CardError (a refusal named by its code), LinkError,
  // std::invalid_argument (the stream ends inside a command).
  size_t send(std::span<const uint32_t> words, const KeepWaiting& keep_waiting = nullptr);

  // Learns the result of the last frame sent, resending it if it was refused as
  // damaged or for room. false: keep_waiting gave up.
  bool settle(const KeepWaiting& keep_waiting = nullptr);

  // Reads one READ register: a frame of that READ alone (it is its own marker:
  // the card's READ count tells that it ran, and running it twice is harmless),
  // then POLLs until the READ has run; the reply's last_read is the register,
  // read as the reply went out. The card's command port must be free to take it
  // (true at connect). Throws CardError as send() does, or when keep_waiting
  // gives up.
  uint32_t read_register(Register r, unsigned axis = 0, const KeepWaiting& keep_waiting = nullptr);

  // Sends an URGENT frame (docs/PROTOCOL.md "Out of band": `word` of urgent::start,
  // urgent::stop, urgent::flush), which acts at once, past every word the card's command buffer
  // holds; settles first, then POLLs until the card reports it accepted, sending it
  // again while it arrives damaged. false: keep_waiting gave up. Throws CardError
  // when the card refuses it otherwise.
  bool urgent(uint32_t word, const KeepWaiting& keep_waiting = nullptr);

  // Settles, then POLLs every poll_interval_s until the card is not running and
  // its command buffer is empty (with a BufferedTime: not before the motion the
  // card holds is done). false: keep_waiting gave up.
  bool wait_until_stopped(const KeepWaiting& keep_waiting = nullptr);

  // The latest good reply (after at least one poll or frame), and the first.
  [[nodiscard]] const Reply& last() const { return last_; }
  [[nodiscard]] const Reply& first() const { return first_; }
  [[nodiscard]] bool has_reply() const { return have_reply_; }
  [[nodiscard]] const LinkStats& stats() const { return stats_; }
  [[nodiscard]] const ClientOptions& options() const { return o_; }
  Link& link() { return link_; }

 private:
  enum class Kind { none, poll, commands };
  struct Sent {
    Kind kind = Kind::none;
    uint8_t seq = 0;
    size_t nwords = 0;
  };
  enum class State { sent, lost, refused };
  struct Pending {
    std::vector<uint32_t> words;  // the frame's words (marker included)
    size_t caller_words = 0;      // of them, the caller's
    uint8_t seq = 0;
    uint16_t reads = 0;           // READ commands among them
    State state = State::sent;
    uint8_t refusal = 0;          // FrameResult when refused
  };

  bool poll_once();
  void send_frame(std::vector<uint32_t> frame_words, size_t caller_words);
  bool on_reply(std::span<const uint8_t> miso, const Sent& sent);
  void resolve(const Reply& r, const Sent& sent);
  bool settle_lost(const KeepWaiting& keep);
  // Until `least` words fit, and `batch` unless the card runs short of motion.
  bool wait_for_room(size_t least, const KeepWaiting& keep, size_t batch = 0);
  bool pause(const KeepWaiting& keep, double seconds = 0);
  [[nodiscard]] size_t room() const;
  [[nodiscard]] size_t marker_words() const { return o_.confirm_each_frame ? 1 : 0; }

  Link& link_;
  ClientOptions o_;
  LinkStats stats_;
  Reply last_, first_;
  bool have_reply_ = false;
  size_t unaccounted_ = 0;        // words sent since the transfer of last_ (its own included)
  Sent prev_;                     // the previous transfer: the next reply reports on it
  uint64_t transfers_done_ = 0;
  double last_frame_end_s_ = 0;  // the link's clock when the last frame ended
  std::optional<Pending> pending_;
  uint16_t reads_expected_ = 0;   // the card's READ count once every accepted READ has run
  uint8_t next_seq_ = 1;
  unsigned bad_in_a_row_ = 0, damaged_in_a_row_ = 0;
  double room_wait_avg_s_ = 0;    // moving average of the waits for room (first_wait_share)
  BufferedTime buffered_time_;
  uint64_t handed_ = 0;           // caller words handed to frames by send()
  [[nodiscard]] double buffered_s() const;
  [[nodiscard]] bool may_batch() const;
  [[nodiscard]] size_t batch_words(size_t remaining) const;
};

// Reads the capability registers (card/caps.h) at connect.
CardCaps read_caps(CardClient& client, const CardClient::KeepWaiting& keep_waiting = nullptr);

// Whether a card is stalled: stopped, its command buffer holding words and its
// free words unchanged for longer than `limit` (in the caller's unit of time:
// cycles or seconds). Fed every reply the host waits on.
class StallWatch {
 public:
  explicit StallWatch(double limit) : limit_(limit) {}
  bool stalled(const Reply& r, double now) {
    if ((r.status & 1) || !(r.flags & reply_flag::busy) || int(r.free_words) != free_) {
      since_ = now;
      free_ = r.free_words;
    }
    return now - since_ > limit_;
  }

 private:
  double limit_, since_ = 0;
  int free_ = -1;
};

}  // namespace cpstep::card

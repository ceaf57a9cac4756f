// SPDX-License-Identifier: MIT
// The card's golden model (model::CpCard: cp_spi, cp_core and the E-stop
// synchronizer) in lockstep with the Verilated card (rtl/cp_card.v), driven through
// the pins by the pin-level SPI master: every output of the card (MISO and its
// enable, STEP, DIR, ENABLE, running, fault, stretched, the error code, the
// positions) is compared on every cycle; the first mismatch throws, naming the
// cycle and the signal, and leaves an FST waveform in $CPSTEP_WAVE_DIR.
//
// - RealJob: pulse timing, three segments (one with add2) and START over COMMANDS
//   frames, POLLs while it runs, to the end; the replies' results, counters and
//   positions are checked against the job.
// - Random: random frames (valid command lists, random bytes, frames cut
//   anywhere, a flipped bit, NO_ROOM, BAD_CMD, SPLIT, BAD_TYPE), random SPI timings
//   down to one clock per SCK phase (faster than the legal clk/8, so the
//   synchronizers are exercised at the edge), raw random pin toggling, E-stop
//   toggles, resets mid-frame and glitched frames. Whenever the bench knows what
//   the card saw, the next reply must carry docs/PROTOCOL.md's result for it
//   (card_harness.h's reference) and the frame's seq. RandomCi: a few seeds per
//   card (e2e); RandomLong: a seed sweep (long). CPSTEP_SEED moves the seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "card_harness.h"
#include "common/lockstep.h"
#include "model/cp_conic.h"
#include "model/cp_conic_serial.h"
#include "sim/fast_card.h"

namespace cpstep::tb {
namespace {

using sim::CardIn;
using sim::SpiTiming;

uint64_t base_seed() {
  const char* s = std::getenv("CPSTEP_SEED");
  return s ? std::strtoull(s, nullptr, 0) : 0x5EED'CA2Dull;
}

// MISO is sampled by the master at an SCK rise; the card moves it 3 cycles after
// the rise before (or after CS fall), so a reply reads back whole when an SCK
// period and the CS setup are at least 3 cycles (docs/PROTOCOL.md asks for 8 and 4).
bool reply_readable(const SpiTiming& t) { return t.sck_low + t.sck_high >= 3 && t.cs_setup >= 3; }

// One card in lockstep with its model, with the host's view of the link.
template <class P>
class Bench {
 public:
  static constexpr unsigned N = P::kAxes;
  static constexpr bool kConic = P::kBuild.conic != 0;
  static constexpr bool kPtimer = P::kBuild.ptimer != 0;
  using Ls = Lockstep<P>;

  explicit Bench(uint64_t seed = 1, SpiTiming t = {}) : ls_("card_model"), spi_(ls_, t), rng_(seed) {
    spi_.reset();
    expect_reset();
  }

  Ls& ls() { return ls_; }
  sim::SpiMaster<Ls>& spi() { return spi_; }
  std::mt19937_64& rng() { return rng_; }
  uint64_t cycle() const { return ls_.cycle(); }
  const Ls& lockstep() const { return ls_; }
  const sim::CardOut& pins() const { return spi_.last(); }
  const model::CpCard& model() { return ls_.model().card(); }
  uint32_t rand(uint32_t lo, uint32_t hi) { return std::uniform_int_distribution<uint32_t>(lo, hi)(rng_); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }

  // What the bench knows the next reply must report (the frame before it).
  void expect_reset() { want_ = Want{0, 0, true}; }
  void forget() { want_.reset(); }
  void set_estop(bool on) {
    estop_ = on;
    spi_.set_estop(on);
  }
  bool estop() const { return estop_; }

  // The first `bits` bits of `bytes` in one CS-low period. Checks the reply
  // against what the bench expects of it, then learns this frame's result
  // (docs/PROTOCOL.md via expected_result) when it can tell what the card saw.
  // Returns the decoded reply when it was read back whole.
  std::optional<card::Reply> frame(std::vector<uint8_t> bytes, size_t bits) {
    const size_t reply_len = card::reply_bytes(N);
    const bool readable = reply_readable(spi_.timing());
    const auto miso = spi_.transfer_bits(bytes, bits);
    std::optional<card::Reply> reply;
    if (readable && bits >= 8 * reply_len) {
      reply = card::decode_reply(miso, N);
      EXPECT_TRUE(reply->ok()) << reply->error << " at cycle " << cycle();
      if (want_) {
        ++checked_;
        EXPECT_EQ(unsigned(reply->last_result), unsigned(want_->result)) << "at cycle " << cycle();
        EXPECT_EQ(reply->last_seq, want_->seq) << "at cycle " << cycle();
        EXPECT_EQ(bool(reply->flags & card::reply_flag::fresh), want_->fresh) << "at cycle " << cycle();
      }
      for (size_t i = reply_len; i < miso.size(); ++i) EXPECT_EQ(miso[i], 0) << "reply padding, byte " << i;
    }
    // This frame's result: the free words it was judged against are in its reply's
    // word 1; without them, only when the result does not depend on them.
    const uint8_t seq = bits >= 16 ? bytes[1] : (want_ ? want_->seq : 0);
    frame_free_.reset();
    if (readable && bits >= 64) {
      const size_t free = size_t(miso[4]) << 8 | miso[5];
      want_ = Want{expected_result(bytes, bits, free, N, kConic, kPtimer), seq, false};
      frame_free_ = free;
    } else {
      const uint8_t lo = expected_result(bytes, bits, 0, N, kConic, kPtimer),
                    hi = expected_result(bytes, bits, 0xFFFF, N, kConic, kPtimer);
      if (lo == hi && (want_ || bits >= 16)) want_ = Want{lo, seq, false};
      else want_.reset();
    }
    if (want_) ++seen_[want_->result];
    return reply;
  }
  std::optional<card::Reply> frame(std::vector<uint8_t> bytes) {
    if (bytes.size() < card::reply_bytes(N)) bytes.resize(card::reply_bytes(N), 0);
    const size_t bits = 8 * bytes.size();
    return frame(std::move(bytes), bits);
  }
  std::vector<uint8_t> encode(uint8_t type, std::span<const uint32_t> words) {
    return card::encode_frame(type, ++seq_, words, card::reply_bytes(N));
  }
  card::Reply commands(std::span<const uint32_t> words) {
    return must(frame(encode(uint8_t(card::FrameType::commands), words)));
  }
  card::Reply poll() { return must(frame(card::encode_poll(++seq_, N))); }

  size_t checked() const { return checked_; }
  const std::array<size_t, 8>& results_seen() const { return seen_; }
  // The free words the last frame was judged against, when its reply said.
  std::optional<size_t> frame_free() const { return frame_free_; }
  std::optional<uint8_t> wanted() const { return want_ ? std::optional<uint8_t>(want_->result) : std::nullopt; }

 private:
  struct Want {
    uint8_t result, seq;
    bool fresh;
  };
  card::Reply must(std::optional<card::Reply> r) {
    if (!r) {
      ADD_FAILURE() << "no reply read back (timing too fast for MISO)";
      return {};
    }
    return *r;
  }

  Ls ls_;
  sim::SpiMaster<Ls> spi_;
  std::mt19937_64 rng_;
  uint8_t seq_ = 0;
  std::optional<Want> want_;
  size_t checked_ = 0;
  std::array<size_t, 8> seen_{};
  std::optional<size_t> frame_free_;
  bool estop_ = false;
};

// ---------------------------------------------------------------------------------
// Segments a build accepts (docs/CORE.md): U <= W (so every pattern fits), k <=
// KMAX, chunks whose counts sum to U * 2^k with positive, monotone delays.
struct SegmentShape {
  uint32_t u;
  unsigned k;
  std::vector<uint32_t> v;
  std::vector<bool> positive;
  std::vector<card::WireChunk> chunks;
};
card::WireSegment to_wire(const SegmentShape& s, bool end) {
  card::WireSegment w;
  w.u = s.u;
  w.k = s.k;
  w.end = end;
  w.v = s.v;
  w.dir_positive = s.positive;
  w.chunks = s.chunks;
  return w;
}
std::vector<int32_t> deltas(const SegmentShape& s) {
  std::vector<int32_t> d;
  for (size_t a = 0; a < s.v.size(); ++a) d.push_back(int32_t(s.v[a] << s.k) * (s.positive[a] ? 1 : -1));
  return d;
}

template <class P>
SegmentShape random_segment(Bench<P>& b, const builds::Build& build) {
  SegmentShape s;
  s.u = b.rand(1, std::min(build.w, 20u));
  s.k = b.rand(0, std::min(build.kmax, 2u));
  for (unsigned a = 0; a < P::kAxes; ++a) {
    s.v.push_back(b.rand(0, s.u));
    s.positive.push_back(b.chance(0.5));
  }
  uint32_t left = s.u << s.k;
  const uint32_t nch = std::min<uint32_t>(b.rand(1, 3), left);
  const bool add2 = b.chance(0.3);
  for (uint32_t c = 0; c < nch; ++c) {
    const uint32_t count = c + 1 == nch ? left : b.rand(1, left - (nch - 1 - c));
    left -= count;
    card::WireChunk ch;
    ch.interval = b.rand(20, 160);
    ch.count = uint16_t(count);
    ch.add = int16_t(b.rand(0, 6));
    if (add2) ch.add2 = int16_t(b.rand(0, 2));
    s.chunks.push_back(ch);
  }
  return s;
}

// A CONIC over a random segment's T and chunks: a circle of radius 3..12 about the
// origin, walked from (r, 0) by the walker's rule (the model's, as the host runs it)
// to the node T moves on; now and then an end off the walk (CONIC_END), a plane
// axis with v (CONIC_AXES) or equal plane axes.
template <class P>
card::WireConic random_conic(Bench<P>& b, const SegmentShape& s) {
  constexpr unsigned N = P::kAxes;
  card::WireConic k;
  k.t = 0;
  for (const card::WireChunk& ch : s.chunks) k.t += ch.count;
  k.cw = b.chance(0.5);
  k.axis_u = b.rand(0, N - 1);
  k.axis_v = (k.axis_u + b.rand(1, N - 1)) % N;
  if (b.chance(0.03)) k.axis_v = k.axis_u;
  k.dir_positive = s.positive;
  k.v = s.v;
  for (unsigned a = 0; a < N; ++a) k.v[a] = std::min<uint32_t>(k.v[a], k.t);
  if (!b.chance(0.03)) k.v[k.axis_u] = k.v[k.axis_v] = 0;
  const int64_t r = b.rand(3, 12);
  const model::CpConic::Coeffs co{256, 0, 256, 0, 0, -256 * r * r};
  model::CpConic::Node n = model::CpConic::at(co, r, 0);
  const model::CpConic::Node start = n;
  int64_t du = 0, dv = 0;
  for (uint32_t j = 0; j < k.t; ++j) {
    int dx = 0, dy = 0;
    model::CpConicSerial::rule(co, n, k.cw, 40, dx, dy);
    n = model::CpConic::advance(co, n, dx, dy);
    du += dx;
    dv += dy;
  }
  if (b.chance(0.15)) du += b.chance(0.5) ? 1 : -1;
  const auto w = model::CpConicSerial::words(co, start, k.cw, du, dv);
  k.a = int32_t(w[0] & 0xFFFF);
  k.b = int32_t(w[0] >> 16);
  k.c = int32_t(w[1] & 0xFFFF);
  k.g = int32_t(w[2]);
  k.gx = int32_t(w[3]);
  k.gy = int32_t(w[4]);
  k.du = int32_t(du);
  k.dv = int32_t(dv);
  k.chunks = s.chunks;
  return k;
}

// A random command list of at most `max_words` words: READs, CONFIGs, drivers on
// and off, CONTROL (START more often than ABORT and CLEAR), segments (now and
// then a bad one: the core refuses it and faults).
template <class P>
std::vector<uint32_t> random_commands(Bench<P>& b, const builds::Build& build, size_t max_words) {
  constexpr unsigned N = P::kAxes;
  std::vector<uint32_t> w;
  const unsigned ncmd = b.rand(1, 6);
  for (unsigned i = 0; i < ncmd && w.size() < max_words; ++i) {
    std::vector<uint32_t> c;
    switch (b.rand(0, 9)) {
      case 0:
      case 1: c.push_back(0x4u << 28 | b.rand(0, 0x27) | (b.chance(0.1) ? 0xC0 : 0)); break;
      case 2:
        card::encode_config(b.rand(0, N - 1), card::ConfigField(b.rand(0, 4)), b.rand(0, 5), c);
        break;
      case 3: card::encode_drivers(b.chance(0.8), c); break;
      case 4: card::encode_control(true, false, false, c); break;
      case 5: card::encode_control(b.chance(0.3), b.chance(0.2), b.chance(0.8), c); break;
      default: {
        SegmentShape s = random_segment(b, build);
        if (build.ptimer) {
          // A phase-timer card (docs/CORE.md "Phase-timer builds"): PHASE commands of
          // every kind with random fields, segments with a length per move and no
          // chunks, in the compact axis form or with every axis's v.
          if (b.chance(0.4)) {
            card::WirePhase ph;
            ph.kind = b.rand(0, 15);
            ph.ticks = b.chance(0.5) ? b.rand(0, 40) : b.rand(0, 0xFFFFFF);
            ph.u = int32_t(b.rand(0, 0xFFFFFF)) - 0x800000;
            ph.r_top = uint64_t(b.rand(0, 0xFFFFFFFF)) << 32 | b.rand(0, 0xFFFFFFFF);
            ph.s = int64_t(b.rand(0, 0xFFFFFF)) << b.rand(0, 30);
            ph.h = int64_t(b.rand(0, 0xFFFFFF)) << b.rand(0, 14);
            card::encode_phase(ph, c);
            break;
          }
          card::WireSegment ws = to_wire(s, b.chance(0.5));
          ws.length = b.chance(0.05) ? 0 : b.rand(1, 0xFFFFFFFF);  // 0: SEG_LENGTH
          if (b.chance(0.08)) ws.v[0] = ws.u + 1;                    // SEG_V_GT_U
          card::encode_segment(ws, c, b.chance(0.3));
          break;
        }
        if (build.conic && b.chance(0.3)) {
          card::encode_conic(random_conic(b, s), c);
          break;
        }
        if (b.chance(0.08)) s.v[0] = s.u + 1;  // SEG_V_GT_U
        if (b.chance(0.05)) s.chunks[0].count = 0;
        card::encode_segment(to_wire(s, b.chance(0.5)), c);
        break;
      }
    }
    if (w.size() + c.size() > max_words) break;
    w.insert(w.end(), c.begin(), c.end());
  }
  if (w.empty()) card::encode_read(card::Register::status, 0, w);
  return w;
}

SpiTiming random_timing(std::mt19937_64& rng, bool legal) {
  auto r = [&](unsigned lo, unsigned hi) { return std::uniform_int_distribution<unsigned>(lo, hi)(rng); };
  SpiTiming t;
  if (legal) {
    t.sck_low = r(4, 6);
    t.sck_high = r(4, 6);
    t.sck_low = std::max(t.sck_low, 8 - t.sck_high);
    t.cs_setup = r(4, 6);
    t.cs_hold = r(2, 5);
    t.cs_idle = r(2, 6);
  } else {
    t.sck_low = r(1, 6);
    t.sck_high = r(1, 6);
    t.cs_setup = r(1, 6);
    t.cs_hold = r(0, 4);
    t.cs_idle = r(1, 5);
  }
  return t;
}

// The pins of a frame as SpiMaster drives them, for the bench to damage: rst
// pulses, CS glitches, runt SCK pulses, a dropped SCK edge.
std::vector<CardIn> frame_pins(std::span<const uint8_t> bytes, size_t bits, const SpiTiming& t) {
  std::vector<CardIn> v;
  auto bit = [&](size_t i) { return bool(bytes[i / 8] >> (7 - i % 8) & 1); };
  CardIn in;
  in.cs_n = false;
  in.mosi = bits > 0 && bit(0);
  v.insert(v.end(), t.cs_setup, in);
  for (size_t i = 0; i < bits; ++i) {
    in.sck = true;
    v.insert(v.end(), t.sck_high, in);
    in.sck = false;
    if (i + 1 < bits) {
      in.mosi = bit(i + 1);
      v.insert(v.end(), t.sck_low, in);
    }
  }
  v.insert(v.end(), t.cs_hold, in);
  v.insert(v.end(), t.cs_idle, CardIn{});
  return v;
}

// ---------------------------------------------------------------------------------
template <class P>
class CardModel : public ::testing::Test {};

struct CardNames {
  template <class P>
  static std::string GetName(int) {
    if constexpr (std::is_same_v<P, CardSmall>) return "Small";
    else if constexpr (std::is_same_v<P, sim::CardIcebreaker>) return "Icebreaker";
    else if constexpr (std::is_same_v<P, sim::CardHx8k>) return "Hx8k";
    else if constexpr (std::is_same_v<P, sim::CardHx8kPt>) return "Hx8kPt";
    else if constexpr (std::is_same_v<P, sim::Fast<CardSmall>>) return "FastSmall";
    else if constexpr (std::is_same_v<P, sim::Fast<sim::CardIcebreaker>>) return "FastIcebreaker";
    else if constexpr (std::is_same_v<P, sim::Fast<sim::CardHx8k>>) return "FastHx8k";
    else return "FastHx8kPt";
  }
};
// The golden model clocked every cycle, and the fast engine (sim::FastCardDut:
// the same model advanced event to event, frames clocked in the front end alone).
using Cards = ::testing::Types<CardSmall, sim::CardIcebreaker, sim::CardHx8k, sim::CardHx8kPt, sim::Fast<CardSmall>,
                               sim::Fast<sim::CardIcebreaker>, sim::Fast<sim::CardHx8k>, sim::Fast<sim::CardHx8kPt>>;
TYPED_TEST_SUITE(CardModel, Cards, CardNames);

TYPED_TEST(CardModel, ModelParamsAreTheBuilds) {
  const model::CpCardParams p = TypeParam::model_params();
  EXPECT_EQ(p.core.n, TypeParam::kAxes);
  EXPECT_EQ(1u << p.core.cbuf_aw, TypeParam::kCbufWords);
  EXPECT_EQ(p.core.w, TypeParam::kBuild.w);
  EXPECT_EQ(p.core.pw, 32u);
}

TYPED_TEST(CardModel, RealJob) {
  constexpr unsigned N = TypeParam::kAxes;
  if constexpr (TypeParam::kBuild.ptimer != 0)
    GTEST_SKIP() << "a chunk job; the phase-timer card's real jobs: Boards.AGcodeJobRunsOnTheCard/hx8k_pt "
                    "(tab.ngc through the host, the Verilated card and this model in lockstep), PhaseTimerRun.*";
  Bench<TypeParam> b;
  const card::Reply hello = b.poll();
  EXPECT_EQ(hello.last_result, 0);
  EXPECT_EQ(hello.flags, card::reply_flag::fresh);
  EXPECT_EQ(hello.free_words, TypeParam::kCbufWords);

  // Drivers on, the pulse timing of every axis, and a READ.
  std::vector<uint32_t> w;
  card::encode_drivers(true, w);
  for (unsigned a = 0; a < N; ++a) {
    card::encode_config(a, card::ConfigField::step_high, 3, w);
    card::encode_config(a, card::ConfigField::step_low, 4, w);
    card::encode_config(a, card::ConfigField::dir_setup, 2, w);
    card::encode_config(a, card::ConfigField::dir_hold, 2, w);
  }
  card::encode_read(card::Register::id, 0, w);
  b.commands(w);
  card::Reply r = b.poll();
  EXPECT_EQ(r.last_result, 0);
  EXPECT_EQ(r.reads, 1);
  EXPECT_EQ(r.last_read, card::kCardId);
  // (The buffer may still hold some of the frame's words when the POLL starts.)
  EXPECT_EQ(r.flags & ~card::reply_flag::busy, card::reply_flag::drivers);

  // Three segments: two chunks; two chunks with add2 (three words each); one
  // chunk of 20 moves with the end flag. Then START in a frame of its own.
  auto shape = [&](uint32_t u, unsigned k, std::vector<card::WireChunk> chunks) {
    SegmentShape s{u, k, {}, {}, std::move(chunks)};
    for (unsigned a = 0; a < N; ++a) {
      s.v.push_back(a == 0 ? u : (u * (a + 2) / (a + 5)));
      s.positive.push_back(a % 2 == 0);
    }
    return s;
  };
  const std::vector<SegmentShape> segs = {
      shape(8, 1, {{480, 10, 8, 0}, {600, 6, -12, 0}}),
      shape(6, 0, {{400, 3, 4, 4}, {360, 3, 0, 0}}),
      shape(5, 2, {{320, 20, 0, 0}}),
  };
  std::vector<uint32_t> f1, f2, start;
  card::encode_segment(to_wire(segs[0], false), f1);
  card::encode_segment(to_wire(segs[1], false), f1);
  card::encode_segment(to_wire(segs[2], true), f2);
  card::encode_control(true, false, false, start);
  ASSERT_LE(f1.size() + f2.size() + start.size(), TypeParam::kCbufWords);
  ASSERT_EQ(f1[0] >> 22 & 1, 0u);
  ASSERT_EQ(f1[2 + N + 4] >> 22 & 1, 1u) << "the second segment carries add2";
  b.commands(f1);
  b.commands(f2);
  r = b.poll();
  EXPECT_EQ(r.last_result, 0);
  EXPECT_FALSE(r.status & 1) << "not started yet";
  b.commands(start);

  std::vector<int32_t> want(N, 0);
  uint32_t moves = 0;
  for (const SegmentShape& s : segs) {
    const auto d = deltas(s);
    for (unsigned a = 0; a < N; ++a) want[a] += d[a];
    moves += s.u << s.k;
  }
  unsigned polls_running = 0;
  uint32_t last_moves = 0;
  for (int i = 0; i < 100; ++i) {
    b.spi().idle(1200);
    r = b.poll();
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.last_result, 0);
    EXPECT_GE(r.moves, last_moves);
    last_moves = r.moves;
    if (r.status & 1) ++polls_running;
    else if (!(r.flags & card::reply_flag::busy)) break;
  }
  EXPECT_GE(polls_running, 3u) << "POLLs while it runs";
  EXPECT_FALSE(r.status & 1) << "the job ended";
  EXPECT_EQ(r.moves, moves);
  EXPECT_EQ(r.segments, 3u);
  EXPECT_EQ(r.positions, want);
  EXPECT_EQ(r.status >> 8 & 0xFF, 0u) << "no error";
  EXPECT_EQ(r.free_words, TypeParam::kCbufWords);
  EXPECT_FALSE(b.pins().fault);
  EXPECT_TRUE(b.pins().enable);
  for (unsigned a = 0; a < N; ++a) EXPECT_EQ(b.pins().position[a], want[a]) << "axis " << a;

  // A READ of the last axis's position comes back in the next reply.
  w.clear();
  card::encode_read(card::Register::position0, N - 1, w);
  b.commands(w);
  r = b.poll();
  EXPECT_EQ(int32_t(r.last_read), want[N - 1]);
  EXPECT_EQ(r.reads, 2);
  EXPECT_GT(b.checked(), 10u);
  // Idle pins: the front end's synchronizers settle, the buffer is empty.
  b.spi().idle(4);
  EXPECT_TRUE(b.model().spi().pins_settled());
  EXPECT_TRUE(b.model().pins_settled());
  EXPECT_EQ(b.model().spi().cbuf_used(), 0u);
  // A CS pulse of one cycle (a frame of no bits): unsettled until it has passed
  // both flops and the edge detector.
  CardIn cs_low;
  cs_low.cs_n = false;
  b.spi().step(cs_low);
  EXPECT_FALSE(b.model().pins_settled());
  for (int i = 0; i < 2; ++i) {
    b.spi().step(CardIn{});
    EXPECT_FALSE(b.model().spi().pins_settled()) << i;
  }
  b.spi().step(CardIn{});
  EXPECT_TRUE(b.model().pins_settled());
  b.forget();
  EXPECT_EQ(b.poll().last_result, 1) << "TRUNCATED";
  std::printf("%llu cycles in lockstep, %u POLLs while running\n", (unsigned long long)b.cycle(), polls_running);
}

// ---------------------------------------------------------------------------------
// One random run of about `budget` cycles.
struct RandomStats {
  std::array<size_t, 8> seen{};          // frames by their result code
  size_t checked = 0;                    // replies checked against the expected result
  std::array<size_t, 2> no_room_edge{};  // frames of exactly the free words, and of one more
  uint64_t cycles = 0, skipped = 0, front_end = 0;  // the fast engine: cycles skipped, and in frames
};

template <class P>
void random_run(uint64_t seed, uint64_t budget, RandomStats& stats) {
  constexpr unsigned N = P::kAxes;
  const builds::Build& build = P::kBuild;
  SCOPED_TRACE("seed " + std::to_string(seed));
  Bench<P> b(seed);
  auto& rng = b.rng();
  unsigned big_no_room = 0;
  auto words_of = [&](uint32_t n) {
    std::vector<uint32_t> w;
    for (uint32_t i = 0; i < n; ++i) card::encode_read(card::Register::status, 0, w);
    return w;
  };
  auto with_crc_flip = [&](std::vector<uint8_t> bytes, size_t len) {
    const size_t bit = b.rand(0, uint32_t(8 * len - 1));
    bytes[bit / 8] ^= uint8_t(0x80 >> (bit % 8));
    return bytes;
  };

  while (b.cycle() < budget) {
    // Timing: mostly legal, now and then faster than clk/8.
    if (b.chance(0.3)) b.spi().set_timing(random_timing(rng, b.chance(0.6)));
    // E-stop: pressed now and then, released soon.
    if (b.chance(b.estop() ? 0.3 : 0.03)) b.set_estop(!b.estop());
    const unsigned action = b.rand(0, 99);
    if (action < 30) {
      // A valid COMMANDS frame (NO_ROOM when the buffer is too full).
      const auto w = random_commands(b, build, std::min<size_t>(24, P::kCbufWords));
      b.frame(b.encode(0x01, w));
    } else if (action < 40) {
      b.frame(card::encode_poll(uint8_t(b.rand(0, 255)), N));
    } else if (action < 46) {
      // A frame cut anywhere.
      const auto w = random_commands(b, build, 12);
      const auto bytes = b.encode(0x01, w);
      b.frame(bytes, b.rand(0, uint32_t(8 * bytes.size())));
    } else if (action < 52) {
      // One bit flipped (header, words or CRC): BAD_CRC, or a header that no longer parses.
      const auto w = random_commands(b, build, 12);
      auto bytes = b.encode(0x01, w);
      b.frame(with_crc_flip(bytes, card::frame_bytes(w.size())));
    } else if (action < 56) {
      // Random bytes, any length.
      std::vector<uint8_t> bytes(b.rand(1, 80));
      for (auto& x : bytes) x = uint8_t(b.rand(0, 255));
      if (b.chance(0.5)) bytes[0] = b.rand(0, 1);
      if (b.chance(0.5) && bytes.size() > 3) bytes[2] = 0, bytes[3] = uint8_t(b.rand(0, 6));
      b.frame(bytes, 8 * bytes.size());
    } else if (action < 60) {
      // NO_ROOM at its edge: a POLL tells the free words, then a frame of exactly
      // that many READs (accepted) or one more (refused); the count holds still
      // when the buffer is empty or the core stalls on full queues. Now and then
      // far more than the buffer holds. A big buffer once per run, at a fast clock.
      const bool big = P::kCbufWords > 64;
      if (big) {
        if (big_no_room == 2) continue;
        ++big_no_room;
        SpiTiming t = b.spi().timing();
        t.sck_low = 1;  // a period of 3 cycles: the reply still reads back
        t.sck_high = 2;
        t.cs_setup = 3;
        b.spi().set_timing(t);
      }
      b.frame(card::encode_poll(uint8_t(b.rand(0, 255)), N));
      const size_t polled = b.frame_free().value_or(P::kCbufWords);
      const uint32_t n = !big && b.chance(0.2) ? P::kCbufWords + b.rand(1, 4)
                                               : uint32_t(polled) + (big ? big_no_room - 1 : b.rand(0, 1));
      const auto w = words_of(n);
      b.frame(b.encode(0x01, w));
      if (const auto f = b.frame_free()) {
        EXPECT_EQ(*b.wanted(), n > *f ? 4 : 0) << "NO_ROOM edge: " << n << " words, " << *f << " free";
        if (n <= *f + 1) ++stats.no_room_edge[n > *f];
      }
    } else if (action < 64) {
      // BAD_CMD: an unknown opcode at a command boundary.
      auto w = random_commands(b, build, 8);
      std::vector<size_t> starts;
      for (size_t i = 0; i <= w.size(); i += card::command_words(w[i], N, build.ptimer)) {
        starts.push_back(i);
        if (i == w.size()) break;
      }
      // (5 is CONIC where the card's core takes conics, 6 PHASE on a phase-timer card.)
      const uint32_t op = b.chance(0.3) ? 0 : b.rand(build.ptimer ? 7 : Bench<P>::kConic ? 6 : 5, 15);
      const size_t at = starts[b.rand(0, uint32_t(starts.size() - 1))];
      w.insert(w.begin() + ptrdiff_t(at), op << 28 | b.rand(0, 0xFFFFFF));
      b.frame(b.encode(0x01, w));
      if (const auto f = b.frame_free()) {
        EXPECT_EQ(*b.wanted(), w.size() > *f ? 4 : 5) << "BAD_CMD";
      }
    } else if (action < 68) {
      // SPLIT: a frame ending inside a segment.
      std::vector<uint32_t> w;
      card::encode_read(card::Register::moves_done, 0, w);
      card::WireSegment seg = to_wire(random_segment(b, build), true);
      if (build.ptimer) seg.length = b.rand(1, 0xFFFFFFFF);  // its axis form's v words and L
      card::encode_segment(seg, w, b.chance(0.5));
      w.resize(b.rand(2, uint32_t(w.size() - 1)));
      b.frame(b.encode(0x01, w));
      if (const auto f = b.frame_free()) {
        EXPECT_EQ(*b.wanted(), w.size() > *f ? 4 : 6) << "SPLIT";
      }
    } else if (action < 69) {
      // BAD_TYPE: an unknown type, a POLL with words, an URGENT frame of 0 or 2 words.
      const auto w = words_of(b.rand(0, 2));
      uint8_t type = w.empty() ? uint8_t(b.rand(2, 255)) : uint8_t(b.chance(0.5) ? 0 : b.rand(2, 255));
      if (type == 2 && w.size() == 1) type = 3;
      b.frame(b.encode(type, w));
      if (b.wanted()) {
        EXPECT_EQ(*b.wanted(), 3) << "BAD_TYPE";
      }
    } else if (action < 72) {
      // URGENT (docs/PROTOCOL.md "Out of band"): START, STOP, FLUSH, ACK in any mix,
      // mostly with ACK (a CLEAR in band does not clear an E-stop: without the ACK
      // the random E-stops would keep the card faulted).
      const uint32_t bits = b.rand(0, 15) | (b.chance(0.7) ? card::urgent::ack : 0) |
                            (b.chance(0.1) ? b.rand(0, 0xFFFF) << 4 : 0);
      b.frame(b.encode(0x02, std::vector<uint32_t>{bits}));
      if (b.wanted()) {
        EXPECT_EQ(*b.wanted(), 0) << "URGENT";
      }
    } else if (action < 78) {
      // A damaged frame: a reset pulse, a CS glitch, a runt or a missing SCK pulse.
      const auto w = random_commands(b, build, 10);
      const auto bytes = b.encode(0x01, w);
      auto pins = frame_pins(bytes, 8 * bytes.size(), b.spi().timing());
      const size_t at = b.rand(0, uint32_t(pins.size() - 1));
      const unsigned len = b.rand(1, 3);
      switch (b.rand(0, 3)) {
        case 0:
          for (size_t i = at; i < std::min(pins.size(), at + len); ++i) pins[i].rst = true;
          break;
        case 1:
          for (size_t i = at; i < std::min(pins.size(), at + len); ++i) pins[i].cs_n = true;
          break;
        case 2:
          for (size_t i = at; i < std::min(pins.size(), at + len); ++i) pins[i].sck = !pins[i].sck;
          break;
        default:
          for (size_t i = at; i < std::min(pins.size(), at + len); ++i) pins[i].mosi = !pins[i].mosi;
      }
      for (const CardIn& in : pins) b.spi().step(in);
      b.forget();
    } else if (action < 84) {
      // Raw random pins, rst and E-stop included, for up to a few thousand cycles.
      const unsigned cycles = b.rand(50, 3000);
      const double p = b.chance(0.5) ? 0.5 : 0.08;
      CardIn in;
      for (unsigned i = 0; i < cycles; ++i) {
        if (b.chance(p)) in.sck = !in.sck;
        if (b.chance(p / 4)) in.cs_n = !in.cs_n;
        if (b.chance(p)) in.mosi = !in.mosi;
        in.rst = b.chance(0.002);
        if (b.chance(0.003)) b.set_estop(!b.estop());
        b.spi().step(in);
      }
      b.spi().step(CardIn{});
      b.spi().step(CardIn{});
      b.forget();
    } else if (action < 88) {
      // A reset between frames.
      b.spi().reset(b.rand(1, 3));
      b.expect_reset();
    } else {
      // Let the card run a while.
      b.spi().idle(b.rand(0, 4000));
    }
  }
  // The end: a clean poll must come back whole.
  b.spi().set_timing({});
  b.set_estop(false);
  b.poll();
  const card::Reply r = b.poll();
  EXPECT_TRUE(r.ok()) << r.error;
  for (unsigned i = 0; i < 8; ++i) stats.seen[i] += b.results_seen()[i];
  stats.checked += b.checked();
  stats.cycles += b.cycle();
  if constexpr (requires { b.lockstep().model_stepper().front_end_cycles(); }) {
    stats.skipped += b.lockstep().model_stepper().skipped();
    stats.front_end += b.lockstep().model_stepper().front_end_cycles();
  }
}

template <class P>
void random_seeds(unsigned seeds, uint64_t budget, uint64_t first) {
  RandomStats st;
  for (unsigned s = 0; s < seeds; ++s) {
    random_run<P>(first + s, budget, st);
    if (::testing::Test::HasFatalFailure()) return;
  }
  // The frames reached every result code, and the replies were checked.
  for (unsigned code = 0; code <= 6; ++code) EXPECT_GT(st.seen[code], 0u) << "result code " << code;
  EXPECT_GT(st.checked, seeds * budget / 60'000);
  EXPECT_GT(st.no_room_edge[0], 0u) << "a frame of exactly the free words";
  EXPECT_GT(st.no_room_edge[1], 0u) << "a frame of one word more than free";
  std::printf("%u seeds, %zu replies checked, results 0..6:", seeds, st.checked);
  for (unsigned code = 0; code <= 6; ++code) std::printf(" %zu", st.seen[code]);
  std::printf("; frames of exactly the free words %zu, of one more %zu\n", st.no_room_edge[0], st.no_room_edge[1]);
  if constexpr (requires { typename P::ModelStepper; }) {
    // The fast engine took its shortcuts (a model that never did would pass too).
    std::printf("fast engine: %llu of %llu cycles skipped, %llu clocked in the front end alone\n",
                (unsigned long long)st.skipped, (unsigned long long)st.cycles, (unsigned long long)st.front_end);
    EXPECT_GT(st.skipped, st.cycles / 50);
    EXPECT_GT(st.front_end, st.cycles / 100);
  }
}

// Different stimulus for cards of the same shape (the iCEBreaker and the HX8K).
template <class P>
uint64_t card_salt() {
  uint64_t h = 0;
  for (char c : P::kBuild.name) h = h * 131 + uint8_t(c);
  return h << 20;
}

TYPED_TEST(CardModel, RandomCi) {
  // About 2 s per card and seed (a million cycles in lockstep take about a second).
  const uint64_t budget = std::is_same_v<TypeParam, CardSmall> ? 2'500'000 : 1'500'000;
  random_seeds<TypeParam>(4, budget, base_seed() + card_salt<TypeParam>());
}

TYPED_TEST(CardModel, RandomLong) {
  random_seeds<TypeParam>(40, 3'000'000, base_seed() + 1000 + card_salt<TypeParam>());
}

}  // namespace
}  // namespace cpstep::tb

// SPDX-License-Identifier: MIT
// cp_fifo: RTL vs model every cycle under random traffic, and an independent
// scoreboard: committed words come out in order, rolled-back words never do.
#include <gtest/gtest.h>

#include <deque>
#include <random>

#include "Vcp_fifo_d100.h"
#include "Vcp_fifo_d40.h"
#include "common/lockstep.h"
#include "sim/fifo_port.h"

namespace cpstep::tb {
namespace {

using Fifo40 = sim::FifoPort<Vcp_fifo_d40, 40, 3>;
using Fifo100 = sim::FifoPort<Vcp_fifo_d100, 100, 2>;

model::FifoWord random_word(std::mt19937_64& rng, unsigned dw) {
  model::FifoWord w{rng(), rng(), 0, 0};
  if (dw < 64) w[0] &= (uint64_t(1) << dw) - 1;
  w[1] = dw <= 64 ? 0 : dw < 128 ? w[1] & ((uint64_t(1) << (dw - 64)) - 1) : w[1];
  return w;
}

template <class P>
void random_traffic(uint64_t seed, int cycles) {
  const unsigned dw = P::model_params().dw, depth = 1u << P::model_params().aw;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pct(0, 99);
  Lockstep<P> ls;
  ls.reset();
  std::deque<model::FifoWord> committed, pending;
  unsigned max_level = 0;
  uint64_t popped = 0, rolled_back = 0;
  StreamContract contract("fifo out");
  for (int c = 0; c < cycles; ++c) {
    model::CpFifoIn in;
    in.wr = pct(rng) < 60;
    in.wr_data = random_word(rng, dw);
    in.commit = pct(rng) < 25;
    in.rollback = !in.commit && pct(rng) < 5;
    in.out_ready = pct(rng) < (c / 500 % 2 ? 80 : 30);  // phases of filling and draining
    in.clear = pct(rng) < 1;
    const model::CpFifoOut o = ls.step(in);
    contract.check(c, o.out_valid, in.out_ready, o.out_data[0] ^ o.out_data[1]);
    ASSERT_EQ(o.level, committed.size());
    ASSERT_EQ(o.used, committed.size() + pending.size());
    ASSERT_EQ(o.full, committed.size() + pending.size() - o.out_valid >= depth);
    max_level = std::max(max_level, o.used);
    if (o.out_valid && in.out_ready) {
      ASSERT_FALSE(committed.empty());
      ASSERT_EQ(o.out_data, committed.front()) << "cycle " << c;
      committed.pop_front();
      ++popped;
    }
    if (in.clear) {  // a clear empties the head too: no transfer is pending after it
      committed.clear();
      pending.clear();
      contract = StreamContract("fifo out");
      continue;
    }
    if (in.wr && !o.full) pending.push_back(in.wr_data);
    if (in.rollback) {
      rolled_back += pending.size();
      pending.clear();
    } else if (in.commit) {
      committed.insert(committed.end(), pending.begin(), pending.end());
      pending.clear();
    }
  }
  EXPECT_EQ(max_level, depth + 1) << "the traffic should fill the FIFO";
  EXPECT_GT(popped, uint64_t(cycles) / 10);
  EXPECT_GT(rolled_back, 0u);
}

TEST(Fifo, RandomTrafficNarrow) { random_traffic<Fifo40>(1, 60000); }
TEST(Fifo, RandomTrafficWide) { random_traffic<Fifo100>(2, 60000); }

TEST(Fifo, CommittedWordFallsThroughTwoCyclesAfterItsWrite) {
  Lockstep<Fifo40> ls;
  ls.reset();
  model::CpFifoIn in;
  in.wr = in.commit = true;
  in.wr_data = {0x12345, 0, 0, 0};
  EXPECT_FALSE(ls.step(in).out_valid);  // written and committed at this edge
  EXPECT_FALSE(ls.step({}).out_valid);  // fetched into the head at this edge
  const auto o = ls.step({});
  EXPECT_TRUE(o.out_valid);
  EXPECT_EQ(o.out_data[0], 0x12345u);
}

TEST(Fifo, UncommittedWordsStayInvisibleAndRollBackWhole) {
  Lockstep<Fifo40> ls;
  ls.reset();
  model::CpFifoIn in;
  in.wr = true;
  for (int i = 0; i < 3; ++i) {
    in.wr_data = {uint64_t(i + 1), 0, 0, 0};
    EXPECT_FALSE(ls.step(in).out_valid);
  }
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(ls.step({}).out_valid);
  model::CpFifoIn rb;
  rb.rollback = true;
  EXPECT_EQ(ls.step(rb).used, 3u);
  EXPECT_EQ(ls.step({}).used, 0u);
}

}  // namespace
}  // namespace cpstep::tb

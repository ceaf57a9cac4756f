// SPDX-License-Identifier: MIT
// The seed paper's worked example, (u, v) = (51, 11), SPEC §1: the register table
// row by row, the 51-move output, and its doubled forms.
#include <gtest/gtest.h>

#include "engine_bench.h"

namespace cpstep::tb {
namespace {

// SPEC §1, transcribed from the seed paper.
const std::vector<oracle::Iteration> kPaperTable = {
    {29, 11, "0", "01"},
    {18, 11, "0", "010"},
    {7, 11, "0", "0010"},
    {7, 4, "00100", "0010"},
    {3, 4, "00100", "001000100"},
    {3, 1, "00100010000100", "001000100"},
    {2, 1, "00100010000100", "00100010000100001000100"},
    {1, 1, "00100010000100", "0010001000010000100010000100001000100"},
};
const std::string kPaperOutput = "001000100001000010001000010000100010000100001000100";

void expect_table(const std::vector<oracle::Iteration>& got, unsigned scale) {
  ASSERT_EQ(got.size(), kPaperTable.size());
  for (size_t i = 0; i < got.size(); ++i) {
    SCOPED_TRACE("iteration " + std::to_string(i + 1));
    EXPECT_EQ(got[i].x, kPaperTable[i].x * scale);
    EXPECT_EQ(got[i].y, kPaperTable[i].y * scale);
    EXPECT_EQ(got[i].m1, kPaperTable[i].m1);
    EXPECT_EQ(got[i].m2, kPaperTable[i].m2);
  }
}

TEST(Paper, OracleStringAlgorithmReproducesTheTable) {
  std::vector<oracle::Iteration> table;
  EXPECT_EQ(oracle::castle_pitteway(51, 11, &table), kPaperOutput);
  expect_table(table, 1);
  EXPECT_EQ(oracle::closed_form(51, 11), kPaperOutput);
}

TEST(Paper, EngineRegisterTableAndOutput) {
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  const auto run = run_lockstep(ls, {51, 11, 0, 1});
  EXPECT_EQ(run.err_code, 0u);
  expect_table(run.iterations, 1);
  EXPECT_EQ(run.moves, kPaperOutput);
}

TEST(Paper, DoubledSegmentSameIterationsTwiceTheOutput) {
  Lockstep<sim::EngineDefault> ls;
  ls.reset();
  // (102, 22) as a segment: every comparison of the loop is the same, x and y doubled.
  const auto scaled = run_lockstep(ls, {102, 22, 0, 1});
  expect_table(scaled.iterations, 2);
  EXPECT_EQ(scaled.moves, kPaperOutput + kPaperOutput);
  // (51, 11) with k = 1: the same loop, replayed twice.
  const auto doubled = run_lockstep(ls, {51, 11, 1, 1});
  expect_table(doubled.iterations, 1);
  EXPECT_EQ(doubled.moves, kPaperOutput + kPaperOutput);
  EXPECT_EQ(doubled.build_cycles(), run_lockstep(ls, {51, 11, 0, 1}).build_cycles());
}

}  // namespace
}  // namespace cpstep::tb

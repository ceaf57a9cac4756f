// SPDX-License-Identifier: MIT
// plan/queue_step.h: Klipper's queue_step cost of a job's steps, the yardstick
// of the compact wire (issue 13). Expected values are worked out by hand from
// Klipper's protocol document (integer encoding, 64-byte blocks of 5 bytes'
// framing), not taken from the code.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "plan/pipeline.h"
#include "plan/queue_step.h"

using namespace cpstep::plan;

TEST(QueueStep, IntegerLengthsAtEveryBoundary) {
    // Klipper's docs/Protocol.md: -32..95 one byte, -4096..12287 two,
    // -524288..1572863 three, -67108864..201326591 four, else five.
    const struct {
        std::int64_t v;
        unsigned bytes;
    } cases[] = {{0, 1},          {-32, 1},         {95, 1},         {-33, 2},        {96, 2},
                 {-4096, 2},      {12287, 2},       {-4097, 3},      {12288, 3},      {-524288, 3},
                 {1572863, 3},    {-524289, 4},     {1572864, 4},    {-67108864, 4},  {201326591, 4},
                 {-67108865, 5},  {201326592, 5},   {4294967295, 5}};
    for (const auto& c : cases) EXPECT_EQ(klipper_vlq_bytes(c.v), c.bytes) << c.v;
}

TEST(QueueStep, ConstantRateIsOneMessage) {
    // 1000 steps 100 cycles apart: one queue_step (interval 100, count 1000, add 0),
    // plus the stepper's reset_step_clock and set_next_step_dir.
    StepperSteps s;
    for (int i = 1; i <= 1000; ++i) {
        s.cycles.push_back(std::uint64_t(100 * i));
        s.dirs.push_back(1);
    }
    const QueueStepCost c = queue_step_cost(std::span<const StepperSteps>(&s, 1), 0.5);
    ASSERT_TRUE(c.error.empty()) << c.error;
    EXPECT_EQ(c.steps, 1000u);
    EXPECT_EQ(c.queue_step, 1u);
    EXPECT_EQ(c.set_next_step_dir, 1u);
    EXPECT_EQ(c.reset_step_clock, 1u);
    // reset_step_clock: id, oid, clock 0 = 3; set_next_step_dir: id, oid, dir = 3;
    // queue_step: id, oid, 100 (2), 1000 (2), 0 (1) = 7. One block: + 5.
    EXPECT_EQ(c.message_bytes, 13u);
    EXPECT_EQ(c.blocks, 1u);
    EXPECT_EQ(c.bytes, 18u);
}

TEST(QueueStep, DirectionChangesAndLongRunsSplitMessages) {
    // 70000 steps forward (past the 16-bit count), then 10 back: three queue_step
    // messages and two direction messages.
    StepperSteps s;
    std::uint64_t t = 0;
    for (int i = 0; i < 70000; ++i) {
        s.cycles.push_back(t += 50);
        s.dirs.push_back(1);
    }
    for (int i = 0; i < 10; ++i) {
        s.cycles.push_back(t += 50);
        s.dirs.push_back(-1);
    }
    const QueueStepCost c = queue_step_cost(std::span<const StepperSteps>(&s, 1), 0.5);
    ASSERT_TRUE(c.error.empty()) << c.error;
    EXPECT_EQ(c.queue_step, 3u);
    EXPECT_EQ(c.set_next_step_dir, 2u);
}

TEST(QueueStep, MessagesFillBlocksOfSixtyFourBytes) {
    // Ten steppers of one step each at cycle 20000 (3 bytes): each costs 3 + 3 + 2 + 3 + 1 + 1 = 13
    // message bytes; 4 of them fill a block's 59 content bytes (52), so 10 take 3 blocks.
    std::vector<StepperSteps> v(10);
    for (StepperSteps& s : v) {
        s.cycles = {20000};
        s.dirs = {-1};
    }
    const QueueStepCost c = queue_step_cost(v, 0.5);
    ASSERT_TRUE(c.error.empty()) << c.error;
    EXPECT_EQ(c.message_bytes, 130u);
    EXPECT_EQ(c.blocks, 3u);
    EXPECT_EQ(c.bytes, 145u);
}

TEST(QueueStep, AcceleratingStepsNeedMoreMessagesAtTighterError) {
    // t = sqrt(k): a tolerance 25 times tighter needs more messages, never fewer,
    // and every message keeps its steps within the error (checked by expanding).
    StepperSteps s;
    for (int k = 1; k <= 4000; ++k) {
        s.cycles.push_back(std::uint64_t(std::llround(1e5 * std::sqrt(double(k)))));
        s.dirs.push_back(1);
    }
    const QueueStepCost loose = queue_step_cost(std::span<const StepperSteps>(&s, 1), 1000);
    const QueueStepCost tight = queue_step_cost(std::span<const StepperSteps>(&s, 1), 40);
    ASSERT_TRUE(loose.error.empty() && tight.error.empty());
    EXPECT_GT(loose.queue_step, 1u);
    EXPECT_GT(tight.queue_step, loose.queue_step);
    EXPECT_GT(tight.bytes, loose.bytes);
}

TEST(QueueStep, PathStepsSitWhereThePathCrossesHalfSteps) {
    auto m = load_machine(CPSTEP_EXAMPLES_DIR "/machines/seed002.toml");   // 80 steps/mm
    ASSERT_TRUE(m.ok()) << join(m.errors);
    ASSERT_TRUE(bind_card(*m.value, {"test", 48e6, 1024, 8, 16}).empty());
    auto job = parse_gcode("G1 X20 Y6.25 F1200\nG1 X10 Y6.25\n", "job.ngc");
    ASSERT_TRUE(job.ok());
    auto pj = plan_job(*job, *m.value);
    ASSERT_TRUE(pj.ok()) << join(pj.errors);
    const auto steps = path_steps(*pj.value, 48e6);
    ASSERT_EQ(steps.size(), 2u);   // x, y
    const StepperSteps& x = steps[0];
    const StepperSteps& y = steps[1];
    ASSERT_EQ(x.cycles.size(), 1600u + 800u);
    ASSERT_EQ(y.cycles.size(), 500u);
    for (std::size_t i = 0; i < x.cycles.size(); ++i) EXPECT_EQ(x.dirs[i], i < 1600 ? 1 : -1) << i;
    for (std::size_t i = 1; i < x.cycles.size(); ++i) ASSERT_GT(x.cycles[i], x.cycles[i - 1]) << i;
    // Along the first line y's step k is (k - 1/2)/500 of the way: every x step
    // at a smaller fraction of the line, (m - 1/2)/1600, comes no later, every
    // one at a larger fraction no sooner.
    for (std::size_t k = 1; k <= 500; ++k) {
        const double f = (double(k) - 0.5) / 500;
        for (std::size_t mi = 1; mi <= 1600; ++mi) {
            const double g = (double(mi) - 0.5) / 1600;
            if (g < f) {
                EXPECT_LE(x.cycles[mi - 1], y.cycles[k - 1]) << k << " " << mi;
            } else if (g > f) {
                EXPECT_GE(x.cycles[mi - 1], y.cycles[k - 1]) << k << " " << mi;
            }
        }
    }
    // The last step comes before the job ends, the first after it starts.
    EXPECT_GT(x.cycles.front(), 0u);
    EXPECT_LT(double(x.cycles.back()), pj.value->stats.duration_s * 48e6);
}

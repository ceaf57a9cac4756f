// SPDX-License-Identifier: MIT
// plan/queue_step.h: Klipper's queue_step cost of a job's steps, the yardstick
// of the compact wire (issue 13). Expected values are worked out by hand from
// Klipper's protocol document (integer encoding, 64-byte blocks of 5 bytes'
// framing), not taken from the code.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

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

namespace {

// Steps of one stepper built piece by piece, each piece starting where the last ended.
struct TrainBuilder {
    StepperSteps s;
    double t = 0;
    std::int8_t dir = 1;

    void step() {
        s.cycles.push_back(static_cast<std::uint64_t>(std::llround(t)));
        s.dirs.push_back(dir);
    }
    // n steps `interval` cycles apart, the interval growing by `slope` a step.
    void run(std::size_t n, double interval, double slope = 0) {
        for (std::size_t k = 0; k < n; ++k) {
            t += std::max(1.0, interval + slope * double(k));
            step();
        }
    }
};

// A random step train of about `pieces` pieces: constant and slowly varying
// rates, bursts of irregular steps, pauses, direction changes (some a single
// step back and forth). `long_run` steps at a constant rate and as many at a
// slowly varying one come somewhere among them.
StepperSteps random_train(std::mt19937_64& rng, int pieces, std::size_t long_run) {
    auto pick = [&](std::int64_t lo, std::int64_t hi) { return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng); };
    TrainBuilder b;
    b.t = double(pick(0, 100000));
    b.dir = pick(0, 1) != 0 ? 1 : -1;
    const int long_at = int(pick(0, pieces - 1));
    for (int p = 0; p < pieces; ++p) {
        if (pick(0, 3) == 0) b.dir = std::int8_t(-b.dir);
        if (p == long_at && long_run > 0) {
            b.run(long_run, double(pick(30, 400)));
            b.run(long_run, double(pick(200, 400)), -double(pick(0, 100)) / double(long_run));
            continue;
        }
        switch (pick(0, 4)) {
            case 0: b.run(std::size_t(pick(1, 400)), double(pick(20, 5000))); break;
            case 1: b.run(std::size_t(pick(1, 400)), double(pick(100, 3000)), double(pick(-20, 20)) / 100); break;
            case 2:   // a burst of irregular steps
                for (std::int64_t k = pick(1, 60); k > 0; --k) b.run(1, double(pick(1, 300)));
                break;
            case 3: b.t += double(pick(1000, 10000000)); break;
            default:   // back and forth, a step each way
                for (std::int64_t k = pick(1, 6); k > 0; --k) {
                    b.dir = std::int8_t(-b.dir);
                    b.run(1, double(pick(5, 500)));
                }
        }
    }
    return b.s;
}

// queue_step_cost() of the axes that step, in axis order.
QueueStepCost whole_cost(const PerAxis<StepperSteps>& axes, double e, const ChunkLimits& lim) {
    std::vector<StepperSteps> v;
    for (const StepperSteps& s : axes)
        if (!s.cycles.empty()) v.push_back(s);
    return queue_step_cost(v, e, lim);
}

// The counter fed the axes' steps interleaved at random, each axis's in order.
QueueStepCost counted_cost(const PerAxis<StepperSteps>& axes, double e, const ChunkLimits& lim, std::size_t window,
                           std::mt19937_64& rng) {
    QueueStepCounter counter(e, lim, window);
    PerAxis<std::size_t> next{};
    std::vector<int> left;
    for (int a = 0; a < kAxes; ++a)
        if (!axes[a].cycles.empty()) left.push_back(a);
    while (!left.empty()) {
        const std::size_t pick = std::uniform_int_distribution<std::size_t>(0, left.size() - 1)(rng);
        const int a = left[pick];
        // A few steps of the axis at a time, up to a whole burst of them.
        const std::size_t n = std::uniform_int_distribution<std::size_t>(1, 64)(rng);
        for (std::size_t k = 0; k < n && next[a] < axes[a].cycles.size(); ++k, ++next[a])
            counter.add(a, axes[a].cycles[next[a]], axes[a].dirs[next[a]]);
        if (next[a] == axes[a].cycles.size()) left.erase(left.begin() + std::ptrdiff_t(pick));
    }
    return counter.finish();
}

std::string cost_text(const QueueStepCost& c) {
    return fmt::format("steps {} queue_step {} set_next_step_dir {} reset_step_clock {} message_bytes {} blocks {} "
                       "bytes {} error '{}'",
                       c.steps, c.queue_step, c.set_next_step_dir, c.reset_step_clock, c.message_bytes, c.blocks,
                       c.bytes, c.error);
}

void expect_same_cost(const QueueStepCost& got, const QueueStepCost& want, const std::string& what) {
    EXPECT_TRUE(got == want) << what << "\n got:  " << cost_text(got) << "\n want: " << cost_text(want);
}

// 1 to 4 of the axes (any of them) with random trains.
PerAxis<StepperSteps> random_axes(std::mt19937_64& rng, int pieces, std::size_t long_run) {
    PerAxis<StepperSteps> axes;
    const auto used = std::uniform_int_distribution<int>(1, (1 << kAxes) - 1)(rng);
    for (int a = 0; a < kAxes; ++a)
        if ((used >> a & 1) != 0) axes[a] = random_train(rng, pieces, long_run);
    return axes;
}

}  // namespace

TEST(QueueStepCounter, NoStepsCostNothing) {
    QueueStepCounter counter(0.5);
    expect_same_cost(counter.finish(), queue_step_cost({}, 0.5), "no steps");
}

TEST(QueueStepCounter, EqualsTheWholeCountOnRandomSteps) {
    // Klipper's limits, the default window: the interleaving, the direction
    // messages and the blocks chained across steppers.
    std::mt19937_64 rng(1);
    for (int trial = 0; trial < 40; ++trial) {
        const PerAxis<StepperSteps> axes = random_axes(rng, 30, 0);
        for (double e : {0.5, 7.0, 60.0}) {
            const QueueStepCost want = whole_cost(axes, e, klipper_chunk_limits());
            ASSERT_TRUE(want.error.empty()) << want.error;
            expect_same_cost(counted_cost(axes, e, klipper_chunk_limits(), 0, rng), want,
                             fmt::format("trial {} error {}", trial, e));
        }
    }
}

TEST(QueueStepCounter, EqualsTheWholeCountOnRunsLongerThanTheWindow) {
    // Klipper's limits and the default window (2 * 65535 steps): runs of 300000
    // steps at a constant rate and as many at a slowly varying one are counted
    // a window at a time.
    std::mt19937_64 rng(2);
    for (int trial = 0; trial < 2; ++trial) {
        PerAxis<StepperSteps> axes;
        axes[0] = random_train(rng, 8, 300000);
        axes[2] = random_train(rng, 8, trial == 0 ? 300000 : 0);
        for (double e : {0.5, 25.0}) {
            const QueueStepCost want = whole_cost(axes, e, klipper_chunk_limits());
            ASSERT_TRUE(want.error.empty()) << want.error;
            EXPECT_GT(want.queue_step, 2u * 4u);   // more than the runs' count limit alone asks for
            expect_same_cost(counted_cost(axes, e, klipper_chunk_limits(), 0, rng), want,
                             fmt::format("trial {} error {}", trial, e));
        }
    }
}

TEST(QueueStepCounter, EqualsTheWholeCountWithSmallWindows) {
    // A count limit of 5 to 12 moves and windows from that limit up: most
    // messages are counted from a window that ends before their run does, and
    // a message decided from too few moves would change the count.
    std::mt19937_64 rng(3);
    for (int trial = 0; trial < 60; ++trial) {
        ChunkLimits lim = klipper_chunk_limits();
        lim.max_count = std::uint32_t(5 + trial % 8);
        const PerAxis<StepperSteps> axes = random_axes(rng, 12, 300);
        for (double e : {0.5, 3.0, 25.0}) {
            const QueueStepCost want = whole_cost(axes, e, lim);
            ASSERT_TRUE(want.error.empty()) << want.error;
            for (std::size_t window : {std::size_t{lim.max_count}, std::size_t{lim.max_count} + 1,
                                       std::size_t{2 * lim.max_count}, std::size_t{3 * lim.max_count + 5}})
                expect_same_cost(counted_cost(axes, e, lim, window, rng), want,
                                 fmt::format("trial {} max_count {} error {} window {}", trial, lim.max_count, e, window));
        }
    }
}

TEST(QueueStepCounter, ReportsTheWholeCountsError) {
    // Steps no message can time: a step at its predecessor's cycle (a delay of
    // 0), one after a pause longer than the 32-bit interval, or every step at a
    // negative error (no whole cycle in its tolerance). Axes 1 and 3 hold the
    // bad step, deep in a run longer than the window: the whole count stops at
    // axis 1's, whichever the counter meets first, and the counts up to it agree.
    std::mt19937_64 rng(4);
    for (int trial = 0; trial < 12; ++trial) {
        const int kind = trial % 3;
        const bool small = trial % 2 == 1;
        ChunkLimits lim = klipper_chunk_limits();
        std::size_t window = 0;   // 2 * 65535
        if (small) {
            lim.max_count = 7;
            window = 9;
        }
        PerAxis<StepperSteps> axes;
        for (int a = 0; a < kAxes; ++a) {
            TrainBuilder b;
            b.run(100, 300);
            b.dir = -1;
            b.run((small ? 2000 : 140000) + std::size_t(a) * 100, 200);
            if (kind != 2 && (a == 1 || a == 3)) {
                if (kind == 0) b.step();   // at the last step's cycle
                else b.run(1, 5e9);
                b.run(50, 200);
            }
            axes[a] = b.s;
        }
        const double e = kind == 2 ? -0.5 : 2.0;
        const QueueStepCost want = whole_cost(axes, e, lim);
        ASSERT_FALSE(want.error.empty()) << trial;
        expect_same_cost(counted_cost(axes, e, lim, window, rng), want, fmt::format("trial {}: {}", trial, want.error));
    }
}

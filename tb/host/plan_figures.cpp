// Measurements quoted in docs/PLANNING.md (not a test).
//   plan_figures chunks MACHINE JOB   moves per chunk with and without add2
//   plan_figures split                worst split deviation, exhaustive + random
#include <cstdio>
#include <numeric>
#include <random>
#include <string>

#include <fmt/format.h>

#include "plan/pipeline.h"

using namespace cpstep::plan;

namespace {

int chunks(const char* mpath, const char* jpath) {
    auto m = load_machine(mpath);
    auto job = load_gcode(jpath);
    if (!m.ok() || !job.ok()) {
        fmt::print(stderr, "{}\n{}\n", join(m.errors), join(job.errors));
        return 1;
    }
    for (bool add2 : {false, true}) {
        PlanOptions o;
        o.add2_from_machine = false;
        o.chunk_limits.enable_add2 = add2;
        auto p = plan_job(*job, *m, o);
        if (!p.ok()) {
            fmt::print(stderr, "{}\n", join(p.errors));
            return 1;
        }
        const auto& s = p->stats;
        fmt::print("{} {} add2={}: step_segments={} card_segments={} moves={} chunks={} "
                   "moves/chunk={:.2f} duration={:.3f}s worst_split_error={:.4f}\n",
                   mpath, jpath, add2 ? "on" : "off", s.step_segments, s.card_segments, s.moves,
                   s.chunks, s.moves_per_chunk(), s.duration_s, s.worst_split_error);
    }
    return 0;
}

int split() {
    // Exhaustive: 2 axes, every T <= 300 and 0 <= D <= T, W in {4, 16, 64}.
    for (std::uint32_t W : {4u, 16u, 64u}) {
        double worst = 0, worst_ep = 0;
        std::uint64_t parts = 0, segs = 0;
        for (std::int64_t T = 1; T <= 300; ++T) {
            for (std::int64_t D = 0; D <= T; ++D) {
                const PerAxis<std::int64_t> d{T, D, 0, 0};
                auto r = reduce_segment(d, W, 0.02);
                worst = std::max(worst, max_deviation(d, r.parts) - 0.5);
                worst_ep = std::max(worst_ep, r.endpoint_error);
                parts += r.parts.size();
                ++segs;
            }
        }
        fmt::print("exhaustive 2-axis T<=300 W={}: worst deviation 0.5 + {:.4f} steps "
                   "(worst split-point error {:.4f}), {:.2f} parts/segment\n",
                   W, worst, worst_ep, static_cast<double>(parts) / static_cast<double>(segs));
    }
    // Random: 2 or 4 axes, |d| up to 2^19, W = 1024 (the default), 3 minor axes.
    for (int axes : {2, 4}) {
        std::mt19937_64 rng(1);
        double worst = 0;
        std::uint64_t parts = 0, split_segs = 0;
        const int N = 40;
        for (int k = 0; k < N; ++k) {
            PerAxis<std::int64_t> d{};
            for (int a = 0; a < axes; ++a) {
                d[static_cast<std::size_t>(a)] = static_cast<std::int64_t>(rng() % (1 << 20)) - (1 << 19);
            }
            auto r = reduce_segment(d, 1024, 0.02);
            worst = std::max(worst, max_deviation(d, r.parts) - 0.5);
            parts += r.parts.size();
            split_segs += r.parts.size() > 1;
        }
        fmt::print("random {}-axis |d|<2^19 W=1024 ({} segments, {} split): worst deviation "
                   "0.5 + {:.4f} steps, {:.1f} parts/segment\n",
                   axes, N, split_segs, worst, static_cast<double>(parts) / N);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string cmd = argc > 1 ? argv[1] : "";
    if (cmd == "chunks" && argc == 4) return chunks(argv[2], argv[3]);
    if (cmd == "split") return split();
    fmt::print(stderr, "usage: plan_figures chunks MACHINE JOB | plan_figures split\n");
    return 2;
}

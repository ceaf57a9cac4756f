// SPDX-License-Identifier: MIT
#include "plan/steptime.h"

namespace cpstep::plan {

std::vector<double> ideal_move_times(const PlannedSegment& seg, std::uint64_t total_moves,
                                     std::uint64_t first, std::uint64_t count, double clock_hz) {
    std::vector<double> t;
    t.reserve(count);
    const double T = static_cast<double>(total_moves);
    for (std::uint64_t i = first + 1; i <= first + count; ++i) {
        // The last move lands exactly on the segment's end time.
        const double local = i == total_moves
                                 ? seg.profile.duration
                                 : seg.profile.time_at(seg.length * static_cast<double>(i) / T);
        t.push_back((seg.t_start + local) * clock_hz);
    }
    return t;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
#include "plan/kinematics.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace cpstep::plan {

AxisPeaks realized_peaks(std::span<const double> times, std::span<const int> dirs,
                         double spm, double h, int evaluations_per_window) {
    AxisPeaks pk;
    if (times.size() < 2 || h <= 0) return pk;
    const auto m = static_cast<std::size_t>(std::max(1, evaluations_per_window));
    const double dt = h / static_cast<double>(m);
    // Cumulative position after each event.
    std::vector<double> pos(times.size());
    double p = 0;
    for (std::size_t k = 0; k < times.size(); ++k) {
        p += dirs[k] >= 0 ? 1 : -1;
        pos[k] = p;
    }
    const double t0 = times.front(), t1 = times.back();
    const auto n = static_cast<std::size_t>(std::floor((t1 - t0) / dt)) + 1;
    std::vector<double> g(n);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double t = t0 + static_cast<double>(i) * dt;
        while (k + 1 < times.size() && times[k + 1] <= t) ++k;
        if (k + 1 < times.size() && times[k + 1] > times[k]) {
            const double f = (t - times[k]) / (times[k + 1] - times[k]);
            g[i] = pos[k] + f * (pos[k + 1] - pos[k]);
        } else {
            g[i] = pos[k];
        }
    }
    for (std::size_t i = m; i + m < n; ++i) {
        pk.v = std::max(pk.v, std::abs(g[i + m] - g[i - m]) / (2 * h) / spm);
        pk.a = std::max(pk.a, std::abs(g[i + m] - 2 * g[i] + g[i - m]) / (h * h) / spm);
    }
    for (std::size_t i = 2 * m; i + 2 * m < n; ++i) {
        pk.j = std::max(pk.j, std::abs(g[i + 2 * m] - 2 * g[i + m] + 2 * g[i - m] - g[i - 2 * m]) /
                                  (2 * h * h * h) / spm);
    }
    return pk;
}

}  // namespace cpstep::plan

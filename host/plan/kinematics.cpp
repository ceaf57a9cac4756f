// SPDX-License-Identifier: MIT
#include "plan/kinematics.h"

#include <algorithm>
#include <bit>
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

// The ring starts with room for one stencil (4m + 1 samples) and one sample
// computed ahead of the grid's end (see push).
PeakMeter::PeakMeter(double steps_per_mm, double window_s, int evaluations_per_window)
    : spm_(steps_per_mm),
      h_(window_s),
      m_(static_cast<std::size_t>(std::max(1, evaluations_per_window))),
      dt_(window_s / static_cast<double>(m_)),
      enabled_(window_s > 0),
      next_va_(m_),
      next_j_(2 * m_),
      ring_(std::bit_ceil(4 * m_ + 2)) {}

// Central differences over the window h, centred on sample c, for every c
// whose stencil ends before `limit`: v and a read c - m .. c + m, j reads
// c - 2m .. c + 2m, in the order and with the expressions realized_peaks uses.
template <class At>
void PeakMeter::fold(std::size_t limit, const At& at, AxisPeaks& pk, std::size_t& va,
                     std::size_t& j) const {
    const std::size_t m = m_;
    const double h = h_;
    for (; va + m < limit; ++va) {
        const double lo = at(va - m), mid = at(va), hi = at(va + m);
        pk.v = std::max(pk.v, std::abs(hi - lo) / (2 * h) / spm_);
        pk.a = std::max(pk.a, std::abs(hi - 2 * mid + lo) / (h * h) / spm_);
    }
    for (; j + 2 * m < limit; ++j) {
        const double third = at(j + 2 * m) - 2 * at(j + m) + 2 * at(j - m) - at(j - 2 * m);
        pk.j = std::max(pk.j, std::abs(third) / (2 * h * h * h) / spm_);
    }
}

void PeakMeter::add(double time, int dir) {
    const double pos = last_pos_ + (dir >= 0 ? 1 : -1);
    if (events_++ == 0) t0_ = time;
    if (enabled_) {
        n_ = static_cast<std::size_t>(std::floor((time - t0_) / dt_)) + 1;
        const auto ring_at = [this](std::size_t i) { return ring_[i & (ring_.size() - 1)]; };
        // Every sample not yet computed is at t >= last_t_ (the grid times
        // t0 + i dt never decrease with i); those before `time` lie between
        // the previous event and this one, whatever events follow. A sample
        // at exactly `time` waits: it belongs to this event's segment.
        for (;;) {
            const double t = t0_ + static_cast<double>(produced_) * dt_;
            if (!(t < time)) break;
            const double f = (t - last_t_) / (time - last_t_);
            push(last_pos_ + f * (pos - last_pos_));
            // Fold as we go, so that a long gap between two events needs no
            // more than one stencil of samples. A sample at t < time can
            // still lie past the grid's current end n_ by rounding: the
            // differences reading it wait until the grid is known to hold it.
            fold(std::min(produced_, n_), ring_at, pk_, next_va_, next_j_);
        }
    }
    last_t_ = time;
    last_pos_ = pos;
}

// The samples still missing, up to the grid's end, are at t >= last_t_, past
// the last event, where the curve holds its final position: the rest of the
// grid is known without touching the state, so finish() can be const.
AxisPeaks PeakMeter::finish() const {
    if (events_ < 2 || !enabled_) return {};
    AxisPeaks pk = pk_;
    std::size_t va = next_va_, j = next_j_;
    fold(
        n_,
        [this](std::size_t i) {
            return i < produced_ ? ring_[i & (ring_.size() - 1)] : last_pos_;
        },
        pk, va, j);
    return pk;
}

// Stores the next sample. The ring must keep every sample from next_j_ - 2m
// (the lowest a pending difference reads) on: one stencil while the samples
// stay inside the grid, one more for a sample rounded ahead of the grid's
// end. More only if the grid spacing is within a few ulps of the event
// times; then the ring doubles, keeping its live samples.
void PeakMeter::push(double sample) {
    const std::size_t oldest = next_j_ - 2 * m_;
    if (produced_ - oldest >= ring_.size()) {
        std::vector<double> wider(2 * ring_.size());
        for (std::size_t i = oldest; i < produced_; ++i)
            wider[i & (wider.size() - 1)] = ring_[i & (ring_.size() - 1)];
        ring_ = std::move(wider);
    }
    ring_[produced_ & (ring_.size() - 1)] = sample;
    ++produced_;
}

}  // namespace cpstep::plan

// SPDX-License-Identifier: MIT
// The streaming planners' window over a job (plan::FeedPlanner, plan::StepSegmenter):
// entries of global indices [base, end) in a vector whose front is dropped in bulk.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cpstep::plan::detail {

template <class T>
class Window {
public:
    T& operator[](std::size_t i) { return v_[i - base_]; }
    const T& operator[](std::size_t i) const { return v_[i - base_]; }
    T& back() { return v_.back(); }
    void push_back(const T& x) { v_.push_back(x); }
    void reserve(std::size_t n) { v_.reserve(n); }
    [[nodiscard]] std::size_t end() const { return base_ + v_.size(); }
    // Entries held that are still wanted (not before drop_before's mark).
    [[nodiscard]] std::size_t held() const { return end() - std::max(dropped_, base_); }
    // Entries before `i` are no longer needed (amortized: erased when they are
    // at least half of what is held).
    void drop_before(std::size_t i) {
        i = std::min(i, end());
        if (i <= dropped_) return;
        dropped_ = i;
        const std::size_t n = i - base_;
        if (n >= 1024 && 2 * n >= v_.size()) {
            v_.erase(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(n));
            base_ = i;
        }
    }

private:
    std::vector<T> v_;
    std::size_t base_ = 0, dropped_ = 0;
};

}  // namespace cpstep::plan::detail

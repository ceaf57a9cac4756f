// SPDX-License-Identifier: MIT
// The streaming planners' window over a job (plan::FeedPlanner, plan::StepSegmenter):
// entries of global indices [base, end) in blocks, the front ones freed as they are passed.
#pragma once

#include <algorithm>
#include <cstddef>
#include <deque>
#include <vector>

namespace cpstep::plan::detail {

template <class T>
class Window {
public:
    T& operator[](std::size_t i) {
        const std::size_t k = i - base_;
        return blocks_[k / kBlock][k % kBlock];
    }
    const T& operator[](std::size_t i) const {
        const std::size_t k = i - base_;
        return blocks_[k / kBlock][k % kBlock];
    }
    T& back() { return blocks_.back().back(); }
    void push_back(const T& x) {
        if (blocks_.empty() || blocks_.back().size() == kBlock) {
            blocks_.emplace_back(std::move(spare_));
            spare_ = {};
            blocks_.back().reserve(kBlock);
        }
        blocks_.back().push_back(x);
        ++end_;
    }
    [[nodiscard]] std::size_t end() const { return end_; }
    // Entries held that are still wanted (not before drop_before's mark).
    [[nodiscard]] std::size_t held() const { return end_ - std::max(dropped_, base_); }
    // Entries before `i` are no longer needed: their blocks are freed once
    // passed. Blocks, not one vector: a window that grows to a long lookahead
    // and shrinks again never copies what it holds nor leaves a large block
    // behind (the process's peak memory), and allocates once in kBlock entries.
    void drop_before(std::size_t i) {
        dropped_ = std::max(dropped_, std::min(i, end_));
        while (!blocks_.empty() && base_ + kBlock <= dropped_) {
            // One block passed is kept for the next one: a window sliding along
            // the job allocates nothing once it holds what it needs, rather than
            // freeing a block and allocating another every kBlock entries.
            if (spare_.capacity() == 0) {
                spare_ = std::move(blocks_.front());
                spare_.clear();
            }
            blocks_.pop_front();
            base_ += kBlock;
        }
    }

private:
    static constexpr std::size_t kBlock = 256;
    std::deque<std::vector<T>> blocks_;  // each of kBlock entries but the last
    std::vector<T> spare_;               // a block passed, empty, kept for the next
    std::size_t base_ = 0, end_ = 0, dropped_ = 0;
};

}  // namespace cpstep::plan::detail

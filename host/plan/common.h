// SPDX-License-Identifier: MIT
// Value types shared by every stage of the planning core: axis indexing,
// source locations and diagnostics. No I/O, no global state.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace cpstep::plan {

// The card drives a fixed number of axes; an axis may be unused.
inline constexpr int kAxes = 4;
inline constexpr std::array<char, kAxes> kAxisLetters = {'x', 'y', 'z', 'a'};

template <class T>
using PerAxis = std::array<T, kAxes>;

// Where a thing came from: a file and a 1-based line and column (0 = unknown).
struct SourceLoc {
    int line = 0;
    int col = 0;
    friend bool operator==(const SourceLoc&, const SourceLoc&) = default;
};

// One message about an input. Rendered as "file:line:col: message", or
// "file: message" when there is no position (e.g. a missing field).
struct Diagnostic {
    std::string file;
    SourceLoc loc;
    std::string message;
    [[nodiscard]] std::string str() const;
};

// Either a value or the complete list of errors that refused it. Warnings
// travel with both outcomes.
template <class T>
struct Result {
    std::optional<T> value;
    std::vector<Diagnostic> errors;
    std::vector<Diagnostic> warnings;

    [[nodiscard]] bool ok() const { return value.has_value() && errors.empty(); }
    const T& operator*() const { return *value; }
    const T* operator->() const { return &*value; }
};

// All diagnostics joined with newlines (for printing and for tests).
std::string join(const std::vector<Diagnostic>& diags);

}  // namespace cpstep::plan

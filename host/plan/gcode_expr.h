// SPDX-License-Identifier: MIT
// The RS274NGC line reader: comments, whitespace anywhere, words whose values
// are numbers, parameters (#1, #<name>) or [expressions] with LinuxCNC's
// functions and operators, and parameter assignments. Pure: no I/O.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cpstep::plan::gcode {

// Highest numbered parameter (LinuxCNC's RS274NGC_MAX_PARAMETERS).
inline constexpr int kMaxParameter = 5602;

struct Parameters {
    std::map<int, double> numbered;       // unset numbered parameters read as 0
    std::map<std::string, double> named;  // lower case, no whitespace; unset ones are an error
    // Parameters whose assignment failed: they read as 0 without a further error
    // (the failure was already reported), so later lines report nothing new.
    std::map<int, bool> numbered_poisoned;
    std::map<std::string, bool> named_poisoned;
    // System parameters computed from the interpreter's state (e.g. #5420); nullopt
    // when the number is an ordinary one.
    std::function<std::optional<double>(int)> system;
    // Whether a numbered parameter may be written (system ones may not).
    std::function<bool(int)> writable;
};

struct Word {
    char letter = 0;    // upper case
    double value = 0;
    int col = 0;        // 1-based column of the letter in the original line
    std::string text;   // the letter and its value as written, whitespace removed
    bool known = true;  // false: the value could not be computed (already reported or
                        // depending on a failed parameter); the word still counts as given
};

struct Assignment {
    int col = 0;
    bool named = false;
    int number = 0;
    std::string name;
    double value = 0;
    bool known = true;
};

struct LineError {
    int col = 0;
    std::string message;
};

struct ReadLine {
    std::vector<Word> words;
    std::vector<Assignment> assignments;
    std::optional<LineError> error;  // reading stops at the first error of a line
    bool block_delete = false;       // the line started with '/'
    bool o_word = false;             // an O-word was found (reported as an error)
    bool tape = false;               // a '%' line
    [[nodiscard]] bool empty() const { return words.empty() && assignments.empty(); }
};

// Read one line (without its newline). Values of parameters are those before
// the line: assignments take effect after it (apply_assignments).
ReadLine read_line(std::string_view line, const Parameters& params);

// Store the line's assignments; returns errors (e.g. writing a system parameter).
std::vector<LineError> apply_assignments(const ReadLine& line, Parameters& params);

// Evaluate one expression text such as "[1 + 2 * 3]" or "sin[30]" (for tests).
// nullopt with `error` set on failure.
std::optional<double> evaluate(std::string_view text, const Parameters& params,
                               std::string* error = nullptr);

}  // namespace cpstep::plan::gcode

// SPDX-License-Identifier: MIT
// `cpstep accuracy U V [--k K] [--engine rtl|model|oracle] [--grid fine|base]`:
// the deviation of the stream an engine emitted from the ideal line, as the seed
// paper computes it (docs/ACCURACY.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct AccuracyOptions {
  uint64_t u = 0, v = 0, k = 0;
  std::string engine = "rtl";
  std::string grid = "fine";  // fine: every fine step; base: every 2^k-th (base steps)
  std::string curve;          // optional file of "i error" lines
};

struct AccuracyStats {
  double mean = 0, std = 0, max = 0;   // std: sample standard deviation (n - 1)
  std::vector<double> errors;          // per sample, in base steps
  std::vector<uint64_t> at;            // the fine step index of each sample
};

// Errors |y_i - (v/u) i| / 2^k for i = 0..u*2^k (every 2^k-th with base_grid),
// y_i the count of diagonal moves among the first i of `moves`.
AccuracyStats accuracy_of(const std::string& moves, uint64_t u, uint64_t v, unsigned k,
                          bool base_grid);

CLI::App* add_accuracy_command(CLI::App& app, AccuracyOptions& options);
// Exit codes: 0, or 2 for a request the engine refuses (one line on stderr).
int run_accuracy(const AccuracyOptions& options);

}  // namespace cpstep::cli

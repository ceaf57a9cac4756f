// SPDX-License-Identifier: MIT
// `cpstep vectors OUT_DIR`: conformance vectors for other step generators
// (docs/VALIDATING.md): segments with their expected move strings and positions.
#pragma once

#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct VectorsOptions {
  std::string out_dir;
  uint64_t seed = 1;
  unsigned random = 200;   // random 4-axis segments
};

CLI::App* add_vectors_command(CLI::App& app, VectorsOptions& options);
int run_vectors(const VectorsOptions& options);

}  // namespace cpstep::cli

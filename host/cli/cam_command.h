// SPDX-License-Identifier: MIT
// `cpstep cam PART.dxf... --sheet SHEET.toml [-o JOB.ngc] [--svg PREVIEW.svg]
// [--run --machine M.toml]`: DXF parts laid out on a sheet, kerf-compensated, given
// leads and pierces, ordered, written as G-code (docs/PLASMA.md); --run hands the
// job to `cpstep run`.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace cpstep::cli {

struct CamOptions {
  std::vector<std::string> parts;
  std::string sheet, out, svg, machine;
  std::vector<std::string> transforms;  // applied in order to every part: rotate:DEG, scale:S[:SY], move:DX:DY, mirror:x|y
  int count = -1;                       // overrides layout.count
  bool run = false;
  std::string report, plots, vcd, board;  // passed to run
  bool quiet = false;
};

CLI::App* add_cam_command(CLI::App& app, CamOptions& options);

// `run_job`: how --run runs the written job (cpstep run's code path); empty: --run is refused.
// Exit codes: 0 written (and run), 2 refused (nothing written), 1 the run failed or a file could not be written.
int run_cam(const CamOptions& options,
            const std::function<int(const CamOptions&, const std::string& job)>& run_job = {});

}  // namespace cpstep::cli

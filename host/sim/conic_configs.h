// SPDX-License-Identifier: MIT
// The Verilated conic engine configurations (rtl/CMakeLists.txt) behind their
// port adaptors: the defaults (QW 16, LW 32, FW 48, PW 20, NMAX 2^20 - 1), which
// `cpstep conic --engine rtl` runs, and a narrow one for the benches' refusals.
#pragma once

#include "Vcp_conic.h"
#include "Vcp_conic_small.h"
#include "sim/conic_port.h"

namespace cpstep::sim {

using ConicDefault = ConicPort<Vcp_conic, 16, 32, 48, 20, 1048575>;
using ConicSmall = ConicPort<Vcp_conic_small, 8, 16, 24, 10, 5000>;

}  // namespace cpstep::sim

// SPDX-License-Identifier: MIT
// The Verilated cp_engine configurations built by rtl/CMakeLists.txt.
#pragma once

#include "Vcp_engine.h"
#include "Vcp_engine_w100.h"
#include "Vcp_engine_w32u.h"
#include "Vcp_engine_w64.h"
#include "sim/engine_port.h"

namespace cpstep::sim {

using EngineDefault = EnginePort<Vcp_engine, 1024, 8, 16>;  // W = 1024, KMAX = 8
using EngineW64 = EnginePort<Vcp_engine_w64, 64, 3, 4>;
using EngineW100 = EnginePort<Vcp_engine_w100, 100, 2, 3>;  // capacity not a power of two
using EngineW32U = EnginePort<Vcp_engine_w32u, 32, 2, 2, 200>;  // unreduced u up to 200

}  // namespace cpstep::sim

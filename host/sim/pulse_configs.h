// SPDX-License-Identifier: MIT
// The Verilated cp_pulse configurations built by rtl/CMakeLists.txt.
#pragma once

#include "Vcp_pulse.h"
#include "Vcp_pulse_small.h"
#include "sim/pulse_port.h"

namespace cpstep::sim {

using PulseDefault = PulsePort<Vcp_pulse, 16, 32>;  // TW = 16, PW = 32, reset polarities 1
// TW = 4, PW = 8: counters saturate at 15 and the position wraps after 128 steps;
// the reset polarities are the other way round (active-low STEP, DIR low = positive).
using PulseSmall = PulsePort<Vcp_pulse_small, 4, 8, false, false>;

}  // namespace cpstep::sim

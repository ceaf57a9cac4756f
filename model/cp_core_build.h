// SPDX-License-Identifier: MIT
// The golden model's parameters for a build of rtl/builds.json: the same table
// the Verilated cores and the synthesized boards are made from (docs/BUILDS.md).
#pragma once

#include "cpstep/builds.h"
#include "model/cp_core_ports.h"

namespace cpstep::model {

constexpr CpCoreParams core_params(const builds::Build& b) {
  CpCoreParams p;
  p.n = b.n;
  p.w = b.w;
  p.umax = b.umax;
  p.kmax = b.kmax;
  p.caw = b.caw;
  p.saw = b.saw;
  p.tw = b.tw;
  p.pw = 32;  // cp_card's position counters
  p.step_pol_reset = b.step_pol_reset != 0;
  p.dir_pol_reset = b.dir_pol_reset != 0;
  p.cbuf_aw = b.cbuf_aw;
  p.clock_hz = b.clock_hz;
  p.build_id = b.build_id;
  p.conic = b.conic != 0;  // the walker at the RTL's default width, CIW = 40
  p.inputs = b.inputs != 0;
  p.feed = b.feed != 0;
  p.ptimer = b.ptimer != 0;
  return p;
}

}  // namespace cpstep::model

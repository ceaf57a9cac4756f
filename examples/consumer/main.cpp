// SPDX-License-Identifier: MIT
// An example bench that links the installed cpstep package (CMakeLists.txt here;
// docs/VALIDATING.md, "Linking cpstep into your bench"). In your own bench the
// device under test is your step generator; here it is cpstep's golden model.
//
//   consumer [JOB.ngc MACHINE.toml]     (default: job.ngc and machine.toml here)
//
// 1. The oracle: the seed paper's line (51, 11) from the string algorithm equals
//    the closed form (SPEC §1).
// 2. The job is planned for the default board's card (cpstep::job); its command
//    words drive the golden model of the motion core (cpstep::model) cycle by
//    cycle; its STEP/DIR pins are written as a VCD, and the VCD is checked against
//    the plan (cpstep::check): it conforms.
// 3. The same trace with one x STEP pulse removed does not conform.
// Exit 0 when all three hold, 1 otherwise, 2 when the job or machine is refused.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "check/check.h"
#include "check/pin_map.h"
#include "check/vcd.h"
#include "cpstep/builds.h"
#include "model/cp_core.h"
#include "model/cp_core_build.h"
#include "model/oracle.h"
#include "run/card_job.h"

namespace {

using namespace cpstep;

constexpr const char* kAxisNames = "xyza";

// One pin change of the model: the cycle, the VCD code and the new level.
struct Change {
  uint64_t cycle;
  char code;
  bool level;
};

// Runs the command words on the golden model of the board's motion core and
// returns its STEP/DIR pin changes (codes '0'+axis for STEP, 'a'+axis for DIR).
std::vector<Change> run_model(const builds::Build& board, const std::vector<uint32_t>& words, bool& fault) {
  fault = false;
  model::CpCore core(model::core_params(board));
  std::vector<Change> changes;
  uint32_t step = 0, dir = 0;
  const unsigned axes = core.params().n;
  size_t next = 0;
  bool started = false;
  uint64_t stop_at = UINT64_MAX;
  for (uint64_t cycle = 0; cycle < 100'000'000; ++cycle) {
    core.in = {};
    core.in.rst = cycle < 2;
    core.in.rsp_ready = true;
    if (!core.in.rst && next < words.size()) {
      core.in.cmd_valid = true;
      core.in.cmd_data = words[next];
    }
    const model::CpCoreOut out = core.outputs();  // the pins before this rising edge
    if (cycle >= 2) {  // the levels after reset at time 0, then every change
      for (unsigned a = 0; a < axes; ++a) {
        const bool s = (out.step >> a) & 1, d = (out.dir >> a) & 1;
        if (cycle == 2 || s != bool((step >> a) & 1)) changes.push_back({cycle == 2 ? 0 : cycle, char('0' + a), s});
        if (cycle == 2 || d != bool((dir >> a) & 1)) changes.push_back({cycle == 2 ? 0 : cycle, char('a' + a), d});
      }
    }
    step = out.step;
    dir = out.dir;
    if (core.in.cmd_valid && out.cmd_ready) ++next;
    started = started || out.running;
    fault = fault || out.fault;
    // Done: a while after the run ends, so that the last pulse is in the trace.
    if (stop_at == UINT64_MAX && (fault || (started && !out.running && next == words.size())))
      stop_at = cycle + 2000;
    if (cycle == stop_at) break;
    core.tick();
  }
  return changes;
}

// The changes as a VCD whose time unit is one card cycle (no $timescale: the
// pin map gives the unit), with cpstep's pin names step_<axis> and dir_<axis>.
std::string to_vcd(const std::vector<Change>& changes, unsigned axes) {
  std::string v = "$scope module dut $end\n";
  for (unsigned a = 0; a < axes; ++a) {
    v += "$var wire 1 " + std::string(1, char('0' + a)) + " step_" + kAxisNames[a] + " $end\n";
    v += "$var wire 1 " + std::string(1, char('a' + a)) + " dir_" + kAxisNames[a] + " $end\n";
  }
  v += "$upscope $end\n$enddefinitions $end\n";
  uint64_t time = UINT64_MAX;
  for (const Change& c : changes) {
    if (c.cycle != time) v += "#" + std::to_string(time = c.cycle) + "\n";
    v += std::string(1, c.level ? '1' : '0') + c.code + "\n";
  }
  return v;
}

// Parses the VCD, finds the pins and checks them against the plan.
check::Verdict check_vcd(const std::string& vcd_text, const run::CardJob& job, const char* name) {
  const auto vcd = check::parse_vcd(vcd_text, name);
  if (!vcd.ok()) {
    std::fprintf(stderr, "%s\n", plan::join(vcd.errors).c_str());
    return {};
  }
  check::PinMap map = check::default_pin_map();
  map.unit_s = 1.0 / job.clock_hz();  // one time unit is one card cycle
  const auto pins = check::read_pins(*vcd, map, job);
  if (!pins.ok()) {
    std::fprintf(stderr, "%s\n", plan::join(pins.errors).c_str());
    return {};
  }
  return check::check_trace(job, *pins);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = CONSUMER_DIR;
  const std::string job_file = argc > 2 ? argv[1] : dir + "/job.ngc";
  const std::string machine_file = argc > 2 ? argv[2] : dir + "/machine.toml";

  // 1. The oracle.
  const bool oracle_ok = oracle::castle_pitteway(51, 11) == oracle::closed_form(51, 11);
  std::printf("oracle     (51, 11): %s %s\n", oracle::closed_form(51, 11).c_str(),
              oracle_ok ? "(string algorithm = closed form)" : "MISMATCH");

  // 2. Plan the job for the default board's card and run it on the golden model.
  const builds::Build& board = *builds::find(builds::kDefaultBoard);
  const auto job = run::prepare_job(job_file, machine_file);
  if (!job.ok()) {
    std::fprintf(stderr, "%s\n", plan::join(job.errors).c_str());
    return 2;
  }
  bool fault = false;
  std::vector<Change> changes = run_model(board, job->words, fault);
  std::printf("model      %s core: %zu command words, %zu pin changes%s\n", std::string(board.name).c_str(),
              job->words.size(), changes.size(), fault ? ", FAULT" : "");
  const check::Verdict verdict = check_vcd(to_vcd(changes, model::core_params(board).n), *job, "model.vcd");
  std::printf("%s", check::verdict_summary(verdict).c_str());

  // 3. One x STEP pulse (the 10th) removed: the checker must notice.
  int rises = 0;
  for (size_t i = 0; i < changes.size(); ++i) {
    if (changes[i].code != '0' || !changes[i].level || ++rises != 10) continue;
    size_t j = i + 1;
    while (j < changes.size() && changes[j].code != '0') ++j;  // its trailing edge
    if (j < changes.size()) changes.erase(changes.begin() + j);
    changes.erase(changes.begin() + i);
    break;
  }
  const check::Verdict dropped = check_vcd(to_vcd(changes, model::core_params(board).n), *job, "dropped.vcd");
  std::printf("dropped    one x step: %s (%zu findings)\n", dropped.conforms() ? "conforms (WRONG)" : "does not conform",
              dropped.findings.size());

  const bool ok = oracle_ok && !fault && verdict.planned_moves > 0 && verdict.conforms() &&
                  dropped.planned_moves > 0 && !dropped.conforms();
  std::printf("consumer   %s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}

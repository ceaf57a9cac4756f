// SPDX-License-Identifier: MIT
// A small, strict reader of VCD (IEEE 1364 value change dump) files: what
// simulators (`cpstep run --vcd`, Verilator, GHDL) and logic analyzers
// (`sigrok-cli -O vcd`) write. It keeps every variable's declaration and its
// value changes in time order; it does not interpret them.
//
// Accepted: $comment/$date/$version (skipped), $timescale ("1ps", "1 ps",
// "10 ns", ...; any whole number of s/ms/us/ns/ps/fs), nested $scope/$upscope,
// $var (a bit select such as "[3]" after the reference is kept with the name),
// $enddefinitions, #time (never decreasing), $dumpvars/$dumpall/$dumpon/$dumpoff
// blocks, scalar changes (0!, 1!, x!, z!), vector changes (b0101 !, widths up
// to 64; no more bits than the variable's width, leading zeros aside) and real
// changes (r1.5 !, skipped). Several tokens may share a line (sigrok writes
// "#12 1! 0\""). Anything else is an error naming file, line and column.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "plan/common.h"

namespace cpstep::check {

// One value of a variable from `time` on. `bits` holds the value's 0/1 bits
// (bit 0 last in the file); `known` is false when any bit is x or z.
struct VcdChange {
  uint64_t time = 0;
  uint64_t bits = 0;
  bool known = true;
};

struct VcdVar {
  std::string path;     // scopes and name joined by '.', e.g. "top.cpstep.step_x"
  std::string name;     // the last component, e.g. "step_x" (with its bit select: "d[0]")
  unsigned width = 1;
  size_t code = 0;      // index of its identifier code in VcdTrace::changes
  plan::SourceLoc loc;  // where it is declared
};

struct VcdTrace {
  std::string file;
  std::optional<double> unit_s;  // one time unit, from $timescale (none without one)
  std::vector<VcdVar> vars;
  // Per identifier code, in file order: the changes of the variables that
  // share that code (several $var lines may name one code).
  std::vector<std::vector<VcdChange>> changes;
  uint64_t end_time = 0;  // the last #time

  // The variables whose path or last component equals `name`.
  [[nodiscard]] std::vector<const VcdVar*> find(std::string_view name) const;
};

// Parses VCD text; `file` names it in errors. The first error refuses it.
plan::Result<VcdTrace> parse_vcd(std::string_view text, std::string_view file);
// Reads and parses a VCD file.
plan::Result<VcdTrace> read_vcd(const std::filesystem::path& path);

// The whole file as text; nullopt when it cannot be read.
std::optional<std::string> read_text(const std::filesystem::path& path);

// parse(text, file name) on the file's text, or "cannot read the file".
template <class T, class Parse>
plan::Result<T> parse_file(const std::filesystem::path& path, Parse parse) {
  if (const auto text = read_text(path)) return parse(*text, path.string());
  plan::Result<T> refused;
  refused.errors.push_back({path.string(), {}, "cannot read the file"});
  return refused;
}

// "1ps", "1 ps", "41.667ns", "2.5 us": a positive number and a unit (s, ms,
// us, ns, ps, fs), in seconds; nullopt when it is not one.
std::optional<double> parse_duration(std::string_view text);

}  // namespace cpstep::check

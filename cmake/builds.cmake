# SPDX-License-Identifier: MIT
# cmake/builds.cmake — reads rtl/builds.json, the one table of cpstep's build
# configurations (docs/BUILDS.md), for CMake and for scripts.
#
# include()d from CMakeLists.txt: cpstep_read_builds() sets
#   CPSTEP_BUILDS                 the build names, in table order
#   CPSTEP_BOARDS                 those of kind "board"
#   CPSTEP_DEFAULT_BOARD
#   CPSTEP_BUILD_<name>_<FIELD>   KIND DESCRIPTION TOP DEVICE PACKAGE SYNTH_OPTS CLOCK_HZ BUILD_ID
#                                 PINS (the board: rtl/boards/<pins>/, constraints/<pins>.pcf;
#                                 the key "pins", else the build's name)
#   CPSTEP_BUILD_<name>_<PARAM>   every parameter of CPSTEP_BUILD_PARAM_NAMES
#   CPSTEP_BUILD_<name>_PARAMS    NAME=VALUE for every parameter, CLK_HZ and BUILD_ID included:
#                                 what cp_card / cp_core / the board tops are built with
# and cpstep_write_builds_header(<file>) writes the C++ header cpstep/builds.h.
#
# Script mode, for shell scripts (scripts/synth):
#   cmake -DQUERY=<name> -P cmake/builds.cmake   shell assignments for one build
#   cmake -DQUERY=list -P cmake/builds.cmake     one line per build: name kind clock_hz
#   cmake -DQUERY=default_board -P cmake/builds.cmake
cmake_minimum_required(VERSION 3.25)

set(CPSTEP_BUILDS_JSON "${CMAKE_CURRENT_LIST_DIR}/../rtl/builds.json")
# The parameters every build names, in the order the build id hashes them.
set(CPSTEP_BUILD_PARAM_NAMES N W UMAX KMAX CAW SAW TW CBUF_AW STEP_POL_RESET DIR_POL_RESET CONIC INPUTS FEED PTIMER)

function(cpstep_builds_fail msg)
  message(FATAL_ERROR "rtl/builds.json: ${msg}")
endfunction()

macro(cpstep_read_builds)
  file(READ "${CPSTEP_BUILDS_JSON}" _cb_json)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${CPSTEP_BUILDS_JSON}")
  string(JSON CPSTEP_DEFAULT_BOARD ERROR_VARIABLE _cb_err GET "${_cb_json}" default_board)
  if(_cb_err)
    cpstep_builds_fail("no default_board: ${_cb_err}")
  endif()
  string(JSON _cb_n LENGTH "${_cb_json}" builds)
  set(CPSTEP_BUILDS "")
  set(CPSTEP_BOARDS "")
  math(EXPR _cb_last "${_cb_n} - 1")
  foreach(_cb_i RANGE ${_cb_last})
    string(JSON _cb_name GET "${_cb_json}" builds ${_cb_i} name)
    if(NOT _cb_name MATCHES "^[a-z][a-z0-9_]*$")
      cpstep_builds_fail("build ${_cb_i}: name '${_cb_name}' is not [a-z][a-z0-9_]*")
    endif()
    if(_cb_name IN_LIST CPSTEP_BUILDS)
      cpstep_builds_fail("build '${_cb_name}' appears twice")
    endif()
    list(APPEND CPSTEP_BUILDS ${_cb_name})
    foreach(_cb_field kind description clock_hz)
      string(JSON _cb_v ERROR_VARIABLE _cb_err GET "${_cb_json}" builds ${_cb_i} ${_cb_field})
      if(_cb_err)
        cpstep_builds_fail("build '${_cb_name}' has no ${_cb_field}")
      endif()
      string(TOUPPER ${_cb_field} _cb_F)
      set(CPSTEP_BUILD_${_cb_name}_${_cb_F} "${_cb_v}")
    endforeach()
    if(NOT CPSTEP_BUILD_${_cb_name}_KIND MATCHES "^(board|test)$")
      cpstep_builds_fail("build '${_cb_name}': kind must be board or test")
    endif()
    if(NOT CPSTEP_BUILD_${_cb_name}_CLOCK_HZ MATCHES "^[1-9][0-9]*$")
      cpstep_builds_fail("build '${_cb_name}': clock_hz must be a positive integer")
    endif()
    foreach(_cb_field top device package synth_opts)
      string(JSON _cb_v ERROR_VARIABLE _cb_err GET "${_cb_json}" builds ${_cb_i} ${_cb_field})
      if(_cb_err)
        set(_cb_v "")
        if(CPSTEP_BUILD_${_cb_name}_KIND STREQUAL "board" AND NOT _cb_field STREQUAL "synth_opts")
          cpstep_builds_fail("board '${_cb_name}' has no ${_cb_field}")
        endif()
      endif()
      string(TOUPPER ${_cb_field} _cb_F)
      set(CPSTEP_BUILD_${_cb_name}_${_cb_F} "${_cb_v}")
    endforeach()
    if(CPSTEP_BUILD_${_cb_name}_KIND STREQUAL "board")
      list(APPEND CPSTEP_BOARDS ${_cb_name})
    endif()
    # The board whose top and pins the build uses (several builds may share one).
    string(JSON _cb_v ERROR_VARIABLE _cb_err GET "${_cb_json}" builds ${_cb_i} pins)
    if(_cb_err)
      set(_cb_v "${_cb_name}")
    elseif(NOT _cb_v MATCHES "^[a-z][a-z0-9_]*$")
      cpstep_builds_fail("build '${_cb_name}': pins '${_cb_v}' is not [a-z][a-z0-9_]*")
    endif()
    set(CPSTEP_BUILD_${_cb_name}_PINS "${_cb_v}")
    # Parameters: all of them, integers, in a fixed order; the build id hashes them.
    set(_cb_params "")
    set(_cb_canon "${_cb_name}")
    foreach(_cb_p ${CPSTEP_BUILD_PARAM_NAMES})
      string(JSON _cb_v ERROR_VARIABLE _cb_err GET "${_cb_json}" builds ${_cb_i} params ${_cb_p})
      if(_cb_err OR NOT _cb_v MATCHES "^[0-9]+$")
        cpstep_builds_fail("build '${_cb_name}': params.${_cb_p} must be a non-negative integer")
      endif()
      set(CPSTEP_BUILD_${_cb_name}_${_cb_p} ${_cb_v})
      if(_cb_p MATCHES "_POL_RESET$")
        # One-bit parameters ([0:0]) as one-bit Verilog literals.
        if(_cb_v GREATER 1)
          cpstep_builds_fail("build '${_cb_name}': params.${_cb_p} must be 0 or 1")
        endif()
        list(APPEND _cb_params "${_cb_p}=1'b${_cb_v}")
      else()
        list(APPEND _cb_params "${_cb_p}=${_cb_v}")
      endif()
      # CONIC, INPUTS, FEED and PTIMER (added later) join the line only when set, so that
      # the ids of the builds without them, and of the cards already flashed with them,
      # stay what they were.
      if(NOT (_cb_p MATCHES "^(CONIC|INPUTS|FEED|PTIMER)$" AND _cb_v EQUAL 0))
        string(APPEND _cb_canon " ${_cb_p}=${_cb_v}")
      endif()
    endforeach()
    string(JSON _cb_np LENGTH "${_cb_json}" builds ${_cb_i} params)
    list(LENGTH CPSTEP_BUILD_PARAM_NAMES _cb_known)
    if(NOT _cb_np EQUAL _cb_known)
      cpstep_builds_fail("build '${_cb_name}': params has keys other than ${CPSTEP_BUILD_PARAM_NAMES}")
    endif()
    string(APPEND _cb_canon " CLK_HZ=${CPSTEP_BUILD_${_cb_name}_CLOCK_HZ}")
    # The build id: the first 32 bits of the SHA-256 of the canonical line.
    string(SHA256 _cb_hash "${_cb_canon}")
    string(SUBSTRING "${_cb_hash}" 0 8 _cb_hex)
    math(EXPR CPSTEP_BUILD_${_cb_name}_BUILD_ID "0x${_cb_hex}" OUTPUT_FORMAT DECIMAL)
    set(CPSTEP_BUILD_${_cb_name}_BUILD_ID_HEX "${_cb_hex}")
    list(APPEND _cb_params "CLK_HZ=${CPSTEP_BUILD_${_cb_name}_CLOCK_HZ}"
         "BUILD_ID=${CPSTEP_BUILD_${_cb_name}_BUILD_ID}")
    set(CPSTEP_BUILD_${_cb_name}_PARAMS "${_cb_params}")
  endforeach()
  if(NOT CPSTEP_DEFAULT_BOARD IN_LIST CPSTEP_BOARDS)
    cpstep_builds_fail("default_board '${CPSTEP_DEFAULT_BOARD}' is not a build of kind board")
  endif()
endmacro()

# The C++ view of the table: cpstep/builds.h under <dir>.
function(cpstep_write_builds_header dir)
  set(defs "")
  set(all "")
  set(boards "")
  foreach(b ${CPSTEP_BUILDS})
    set(fields "")
    foreach(p ${CPSTEP_BUILD_PARAM_NAMES})
      string(TOLOWER ${p} lp)
      string(APPEND fields "    .${lp} = ${CPSTEP_BUILD_${b}_${p}}u,\n")
    endforeach()
    set(isboard false)
    if(CPSTEP_BUILD_${b}_KIND STREQUAL "board")
      set(isboard true)
    endif()
    string(APPEND defs "// ${CPSTEP_BUILD_${b}_DESCRIPTION}\n"
      "inline constexpr Build ${b}{\n"
      "    .name = \"${b}\",\n"
      "    .board = ${isboard},\n"
      "    .top = \"${CPSTEP_BUILD_${b}_TOP}\",\n"
      "    .clock_hz = ${CPSTEP_BUILD_${b}_CLOCK_HZ}u,\n"
      "    .build_id = 0x${CPSTEP_BUILD_${b}_BUILD_ID_HEX}u,\n"
      "${fields}};\n\n")
    string(APPEND all "&${b}, ")
    if(CPSTEP_BUILD_${b}_KIND STREQUAL "board")
      string(APPEND boards " X(${b})")
    endif()
  endforeach()
  file(CONFIGURE OUTPUT "${dir}/cpstep/builds.h" @ONLY CONTENT
"// Generated by cmake/builds.cmake from rtl/builds.json: do not edit.
// cpstep's build configurations (docs/BUILDS.md): each board's parameter set and
// the test configurations, as the RTL, the model and the host see them.
#pragma once

#include <cstdint>
#include <string_view>

namespace cpstep::builds {

struct Build {
  std::string_view name;
  bool board = false;          // a shipped FPGA build (else a test configuration)
  std::string_view top;        // the board's top module (boards only)
  std::uint32_t clock_hz = 0;  // the card clock
  std::uint32_t build_id = 0;  // READ 0x25 (docs/CORE.md)
  unsigned n = 0, w = 0, umax = 0, kmax = 0, caw = 0, saw = 0, tw = 0, cbuf_aw = 0;
  unsigned step_pol_reset = 1, dir_pol_reset = 1;
  unsigned conic = 0;          // CONIC segments (docs/CORE.md), the walker of 40 bits
  unsigned inputs = 0;         // limit switches and the probe (docs/CORE.md \"Inputs\")
  unsigned feed = 0;           // feed hold and override (docs/CORE.md \"Feed hold and override\")
  unsigned ptimer = 0;         // moves timed by PHASE commands (docs/CORE.md \"Phase-timer builds\")
};

${defs}inline constexpr const Build* kAll[] = {${all}};
inline constexpr std::string_view kDefaultBoard = \"${CPSTEP_DEFAULT_BOARD}\";

// The build named `name`, or nullptr.
constexpr const Build* find(std::string_view name) {
  for (const Build* b : kAll)
    if (b->name == name) return b;
  return nullptr;
}

}  // namespace cpstep::builds

// X(name) for every build of kind board (each has a Verilated card Vcp_card_<name>).
#define CPSTEP_FOR_EACH_BOARD(X)${boards}
")
  set(incs "")
  foreach(b ${CPSTEP_BOARDS})
    string(APPEND incs "#include \"Vcp_core_${b}.h\"\n#include \"Vcp_card_${b}.h\"\n")
  endforeach()
  file(CONFIGURE OUTPUT "${dir}/cpstep/board_models.h" @ONLY CONTENT
"// Generated by cmake/builds.cmake from rtl/builds.json: do not edit.
// The Verilated core and card of every board (rtl/CMakeLists.txt).
#pragma once

${incs}")
endfunction()

# Script mode.
if(CMAKE_SCRIPT_MODE_FILE AND CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  cpstep_read_builds()
  if(NOT DEFINED QUERY)
    message(FATAL_ERROR "cmake/builds.cmake: give -DQUERY=<build>|list|default_board")
  endif()
  if(QUERY STREQUAL "list")
    foreach(b ${CPSTEP_BUILDS})
      execute_process(COMMAND ${CMAKE_COMMAND} -E echo
        "${b} ${CPSTEP_BUILD_${b}_KIND} ${CPSTEP_BUILD_${b}_CLOCK_HZ} ${CPSTEP_BUILD_${b}_DESCRIPTION}")
    endforeach()
  elseif(QUERY STREQUAL "default_board")
    execute_process(COMMAND ${CMAKE_COMMAND} -E echo "${CPSTEP_DEFAULT_BOARD}")
  elseif(QUERY IN_LIST CPSTEP_BUILDS)
    set(b ${QUERY})
    list(JOIN CPSTEP_BUILD_${b}_PARAMS " " params)
    execute_process(COMMAND ${CMAKE_COMMAND} -E echo
      "kind='${CPSTEP_BUILD_${b}_KIND}' top='${CPSTEP_BUILD_${b}_TOP}' pins='${CPSTEP_BUILD_${b}_PINS}' device='${CPSTEP_BUILD_${b}_DEVICE}' package='${CPSTEP_BUILD_${b}_PACKAGE}' synth_opts='${CPSTEP_BUILD_${b}_SYNTH_OPTS}' clock_hz='${CPSTEP_BUILD_${b}_CLOCK_HZ}' build_id='${CPSTEP_BUILD_${b}_BUILD_ID_HEX}' params=\"${params}\"")
  else()
    message(FATAL_ERROR "cmake/builds.cmake: no build '${QUERY}' in rtl/builds.json (builds: ${CPSTEP_BUILDS})")
  endif()
endif()

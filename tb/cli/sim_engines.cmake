# SPDX-License-Identifier: MIT
# Runs `cpstep sim SCRIPT` on both engines (--engine rtl, --engine model) with a
# VCD each and requires the same exit code, stdout, stderr and waveform, byte for
# byte (docs/SIM.md "Engines").
#   cmake -DCPSTEP=cpstep -DSCRIPT=file -DOUT=prefix [-DARGS="a|b"] -P sim_engines.cmake
string(REPLACE "|" ";" ARGS "${ARGS}")
foreach(engine rtl model)
  file(REMOVE "${OUT}.${engine}.vcd")
  execute_process(COMMAND ${CPSTEP} sim ${SCRIPT} --engine ${engine} --vcd ${OUT}.${engine}.vcd ${ARGS}
                  RESULT_VARIABLE rc_${engine} OUTPUT_VARIABLE out_${engine} ERROR_VARIABLE err_${engine})
  if(NOT EXISTS "${OUT}.${engine}.vcd")
    message(FATAL_ERROR "--engine ${engine} wrote no VCD (exit ${rc_${engine}}): ${err_${engine}}")
  endif()
endforeach()
foreach(what rc out err)
  if(NOT "${${what}_rtl}" STREQUAL "${${what}_model}")
    message(FATAL_ERROR "the engines differ in ${what}:\nrtl:   ${${what}_rtl}\nmodel: ${${what}_model}")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}.rtl.vcd ${OUT}.model.vcd RESULT_VARIABLE same)
if(NOT same EQUAL 0)
  message(FATAL_ERROR "the engines' waveforms differ: ${OUT}.rtl.vcd ${OUT}.model.vcd")
endif()
file(SIZE ${OUT}.rtl.vcd size)
if(size LESS 200)
  message(FATAL_ERROR "${OUT}.rtl.vcd is too small to prove anything (${size} bytes)")
endif()
message(STATUS "same exit code (${rc_rtl}), output and waveform (${size} bytes) on both engines")

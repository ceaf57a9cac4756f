# SPDX-License-Identifier: MIT
# cpstep's own trace through sigrok-cli and back, as a capture would come:
# read as a VCD, sampled at 50 MHz (more than twice the default board's 16.5 MHz card clock),
# saved as a sigrok session, exported with `sigrok-cli -O vcd` (time unit 10 ns: the first
# decade at or above 50 MHz), then checked with the sample rate in the map.
# Skipped (ctest SKIP_REGULAR_EXPRESSION) where sigrok-cli is not installed.
#   cmake -DCPSTEP=cpstep -DTRACE=t.vcd -DDATA=tb/check/data -DOUT=dir -P sigrok_roundtrip.cmake
find_program(SIGROK sigrok-cli)
if(NOT SIGROK)
  message("SKIPPED: sigrok-cli is not installed (Debian package sigrok-cli)")
  return()
endif()
file(MAKE_DIRECTORY "${OUT}")
file(REMOVE "${OUT}/capture.sr" "${OUT}/capture.vcd")
# The trace's time unit is 1 ps: 20000 of them are one 50 MHz sample.
execute_process(COMMAND ${SIGROK} -I vcd:downsample=20000 -i ${TRACE} -o ${OUT}/capture.sr
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "sigrok-cli could not read the trace: ${err}")
endif()
execute_process(COMMAND ${SIGROK} -i ${OUT}/capture.sr -O vcd -o ${OUT}/capture.vcd RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "sigrok-cli could not export the VCD: ${err}")
endif()
file(WRITE "${OUT}/sigrok.toml" "sample_hz = 50_000_000\n")
execute_process(COMMAND ${CPSTEP} check --vcd ${OUT}/capture.vcd --job ${DATA}/check.ngc --machine ${DATA}/check.toml
                --map ${OUT}/sigrok.toml RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "time unit 10 ns, resolution 20 ns" OR NOT out MATCHES "\nverdict +conforms\n")
  message(FATAL_ERROR "exit code ${rc}\nstdout: ${out}\nstderr: ${err}")
endif()

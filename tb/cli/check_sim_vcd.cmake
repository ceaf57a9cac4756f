# SPDX-License-Identifier: MIT
# Runs `cpstep sim SCRIPT --vcd VCD ...` and checks the waveform with vcd_count.
#   cmake -DCPSTEP=cpstep -DCOUNTER=vcd_count -DSCRIPT=file -DVCD=out.vcd -DRC=0
#         [-DARGS="a|b"] [-DEXPECT=regex] [-DNO_VCD=1] -P check_sim_vcd.cmake
# EXPECT is matched against vcd_count's summary; NO_VCD=1 requires that no file
# was written (a refused script sends nothing and writes nothing).
file(REMOVE "${VCD}")
string(REPLACE "|" ";" ARGS "${ARGS}")
execute_process(COMMAND ${CPSTEP} sim ${SCRIPT} --vcd ${VCD} ${ARGS}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL RC)
  message(FATAL_ERROR "cpstep exit code ${rc}, expected ${RC}\nstdout: ${out}\nstderr: ${err}")
endif()
if(NO_VCD)
  if(EXISTS "${VCD}")
    message(FATAL_ERROR "${VCD} was written although the script was refused")
  endif()
  return()
endif()
execute_process(COMMAND ${COUNTER} ${VCD} RESULT_VARIABLE rc OUTPUT_VARIABLE summary ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "vcd_count failed: ${err}")
endif()
if(NOT summary MATCHES "${EXPECT}")
  message(FATAL_ERROR "VCD summary does not match '${EXPECT}':\n${summary}")
endif()

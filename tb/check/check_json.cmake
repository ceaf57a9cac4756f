# SPDX-License-Identifier: MIT
# `cpstep check --json` on cpstep's own trace: the verdict file read back.
#   cmake -DCPSTEP=cpstep -DTRACE=t.vcd -DDATA=tb/check/data -DJSON=out.json -P check_json.cmake
file(REMOVE "${JSON}")
execute_process(COMMAND ${CPSTEP} check --vcd ${TRACE} --job ${DATA}/check.ngc --machine ${DATA}/check.toml
                --json ${JSON} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "exit code ${rc}\nstdout: ${out}\nstderr: ${err}")
endif()
file(READ "${JSON}" json)
string(JSON conforms GET "${json}" conforms)
string(JSON findings LENGTH "${json}" findings)
string(JSON planned GET "${json}" planned_moves)
string(JSON events GET "${json}" move_events)
string(JSON exact GET "${json}" segments_bit_exact)
string(JSON segments GET "${json}" segments)
string(JSON x_final GET "${json}" axes x final_position)
string(JSON x_planned GET "${json}" axes x planned_final)
string(JSON x_high GET "${json}" axes x required_ns step_high)
if(NOT conforms OR NOT findings EQUAL 0 OR NOT planned EQUAL events OR NOT exact EQUAL segments
   OR NOT x_final EQUAL x_planned)
  message(FATAL_ERROR "verdict: conforms=${conforms} findings=${findings} moves ${events}/${planned} "
                      "bit-exact ${exact}/${segments} x ${x_final}/${x_planned}\n${json}")
endif()
# data/check.toml: step_high_ns = 2000 on x.
if(NOT x_high EQUAL 2000)
  message(FATAL_ERROR "axes.x.required_ns.step_high is ${x_high}, the machine says 2000")
endif()

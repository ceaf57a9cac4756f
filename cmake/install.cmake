# SPDX-License-Identifier: MIT
# `cmake --install`: cpstep as a CMake package for other teams' benches
# (docs/VALIDATING.md, "Linking cpstep into your bench").
#
#   find_package(cpstep REQUIRED)
#   target_link_libraries(my_bench PRIVATE cpstep::model cpstep::oracle cpstep::check)
#
# Layout under the prefix:
#   lib/libcpstep_*.a                      the static libraries
#   include/cpstep/{model,plan,card,run,check,cpstep}/*.h
#                                          headers; the targets put include/cpstep on the
#                                          include path, so code includes "model/cp_core.h",
#                                          "model/oracle.h", "check/check.h" as cpstep's own does
#   lib/cmake/cpstep/cpstepConfig.cmake, cpstepConfigVersion.cmake, cpstepTargets*.cmake
#   bin/cpstep                             the program (component cli)
# Components: dev (libraries, headers, package files) and cli.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CPSTEP_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/cpstep)
set(CPSTEP_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/cpstep)

# Exported as cpstep::<name>: model, oracle, check and what they need.
set(_cpstep_exported
  cpstep_options:options   # C++20
  cpstep_builds:builds     # cpstep/builds.h (rtl/builds.json)
  cpstep_model:model       # the golden model (model/cp_*.h)
  cpstep_oracle:oracle     # the untimed oracle (model/oracle.h)
  cpstep_plan:plan         # the planner (plan/*.h)
  cpstep_card:card         # command words and capabilities (card/protocol.h, caps.h, frame.h)
  cpstep_card_job:card_job # a planned job as command words (card/job.h)
  cpstep_job:job           # a job made ready for a card (run/card_job.h)
  cpstep_check:check)      # the trace checker (check/*.h)
set(_cpstep_targets "")
foreach(pair ${_cpstep_exported})
  string(REPLACE ":" ";" pair ${pair})
  list(GET pair 0 target)
  list(GET pair 1 name)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  list(APPEND _cpstep_targets ${target})
endforeach()

install(TARGETS ${_cpstep_targets} EXPORT cpstepTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  INCLUDES DESTINATION ${CPSTEP_INSTALL_INCLUDEDIR})

# Headers: every header of model/, host/plan/ and host/check/; of host/card/ and
# host/run/ the ones of the installed libraries; the generated cpstep/builds.h.
set(_inc ${CPSTEP_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/model/ DESTINATION ${_inc}/model COMPONENT dev
  FILES_MATCHING PATTERN "*.h")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/host/plan/ DESTINATION ${_inc}/plan COMPONENT dev
  FILES_MATCHING PATTERN "*.h")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/host/check/ DESTINATION ${_inc}/check COMPONENT dev
  FILES_MATCHING PATTERN "*.h")
install(FILES ${PROJECT_SOURCE_DIR}/host/card/protocol.h ${PROJECT_SOURCE_DIR}/host/card/caps.h
  ${PROJECT_SOURCE_DIR}/host/card/frame.h ${PROJECT_SOURCE_DIR}/host/card/job.h
  DESTINATION ${_inc}/card COMPONENT dev)
install(FILES ${PROJECT_SOURCE_DIR}/host/run/card_job.h DESTINATION ${_inc}/run COMPONENT dev)
install(FILES ${CMAKE_BINARY_DIR}/generated/cpstep/builds.h DESTINATION ${_inc}/cpstep COMPONENT dev)

install(EXPORT cpstepTargets NAMESPACE cpstep:: DESTINATION ${CPSTEP_INSTALL_CMAKEDIR} COMPONENT dev)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/cpstepConfig.cmake.in
  ${CMAKE_BINARY_DIR}/cpstepConfig.cmake INSTALL_DESTINATION ${CPSTEP_INSTALL_CMAKEDIR})
# 0.x: a new minor version may change the interfaces.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cpstepConfigVersion.cmake
  VERSION ${cpstep_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cpstepConfig.cmake ${CMAKE_BINARY_DIR}/cpstepConfigVersion.cmake
  DESTINATION ${CPSTEP_INSTALL_CMAKEDIR} COMPONENT dev)

install(TARGETS cpstep RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT cli)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/cpstep COMPONENT dev)

# Script mode (cmake -P), run by the install_consumer test. Everything it writes is under WORK_DIR,
# inside the build tree: <WORK_DIR>/prefix (the installed package), /build (the consumer), /run (the
# programs' working directory).
foreach(var BUILD_DIR WORK_DIR CONSUMER_DIR GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "run_consumer.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install_consumer: ${what} failed (${rc}):\n${out}")
  endif()
  message(STATUS "install_consumer: ${what}: ok")
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/run")

run_step("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
run_step("configure consumer" ${CMAKE_COMMAND} -S "${CONSUMER_DIR}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
         "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
         "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix" "-DMRTILE_EXPECTED_PREFIX=${WORK_DIR}/prefix"
         "-DEXTRA_SOURCES=${EXTRA_SOURCES}" "-DCONSUMER_WERROR=${WERROR}"
         "-DCMAKE_CXX_FLAGS=${EXTRA_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${EXTRA_FLAGS}"
         # Only the scratch prefix and the system: no user package registry, no stale cache.
         -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
run_step("build consumer" ${CMAKE_COMMAND} --build "${WORK_DIR}/build" -j 2)

string(REPLACE "|" ";" extra_sources "${EXTRA_SOURCES}")
set(programs app)
foreach(source IN LISTS extra_sources)
  get_filename_component(name "${source}" NAME_WE)
  list(APPEND programs ${name})
endforeach()
foreach(program IN LISTS programs)
  execute_process(COMMAND "${WORK_DIR}/build/${program}" WORKING_DIRECTORY "${WORK_DIR}/run"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install_consumer: ${program} exited with ${rc}")
  endif()
endforeach()
message(STATUS "install_consumer: all consumer programs passed")

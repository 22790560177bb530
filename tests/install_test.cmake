# Installs the build tree BUILD into WORK/prefix, then configures, builds and
# runs the outside project SRC (C++ only) against it, and runs an installed
# program from that prefix: it must find its libraries (a relative RUNPATH)
# and the installed material file.
file(REMOVE_RECURSE "${WORK}")
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()
run(${CMAKE_COMMAND} --install "${BUILD}" --prefix "${WORK}/prefix")
run(${CMAKE_COMMAND} -S "${SRC}" -B "${WORK}/build" -DCMAKE_PREFIX_PATH=${WORK}/prefix
    -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build "${WORK}/build")
run("${WORK}/build/consumer")
execute_process(COMMAND "${WORK}/prefix/bin/dem_sample" --test tension --mean-radius 0.006
                        --summary "${WORK}/dem_sample.json"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed dem_sample failed (${rc}):\n${out}\n${err}")
endif()
if(NOT out MATCHES "--material = ${WORK}/prefix/share/dembridge/materials/default.json")
  message(FATAL_ERROR "the installed dem_sample does not use the installed material file:\n${out}")
endif()
message(STATUS "installed dem_sample ran from ${WORK}/prefix")

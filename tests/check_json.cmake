# Runs CMD with ARGS ('|'-separated) writing the JSON summary SUMMARY, then
# checks |KEY| < BOUND for each "KEY<BOUND" and |KEY| > BOUND for each
# "KEY>BOUND" in CHECKS ('|'-separated); a dotted KEY (energy.friction_j)
# names a member of an object.
string(REPLACE "|" ";" args "${ARGS}")
execute_process(COMMAND ${CMD} ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "exit ${rc}:\n${out}\n${err}")
endif()
file(READ "${SUMMARY}" json)
string(REPLACE "|" ";" checks "${CHECKS}")
foreach(c ${checks})
  string(REGEX MATCH "^([a-z_0-9.]+)([<>])(.+)$" m "${c}")
  set(key "${CMAKE_MATCH_1}")
  set(op "${CMAKE_MATCH_2}")
  set(bound "${CMAKE_MATCH_3}")
  string(REPLACE "." ";" path "${key}")
  string(JSON value GET "${json}" ${path})
  # |value| < bound, compared as numbers by a tiny expression in math(EXPR)-free form
  execute_process(COMMAND /usr/bin/python3 -c "import sys; sys.exit(0 if abs(float('${value}')) ${op} float('${bound}') else 1)"
                  RESULT_VARIABLE ok)
  if(NOT ok EQUAL 0)
    message(FATAL_ERROR "${key} = ${value}: |value| must be ${op} ${bound}")
  endif()
  message(STATUS "${key} = ${value} (${op} ${bound})")
endforeach()

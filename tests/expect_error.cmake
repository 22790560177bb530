# Runs CMD with ARGS ('|'-separated); passes if it exits non-zero and its
# stderr matches the regular expression EXPECT.
string(REPLACE "|" ";" args "${ARGS}")
execute_process(COMMAND ${CMD} ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "expected a failure, but '${CMD} ${args}' exited 0:\n${out}")
endif()
if(NOT err MATCHES "${EXPECT}")
  message(FATAL_ERROR "exit ${rc}, but stderr does not match '${EXPECT}':\n${err}")
endif()
message(STATUS "exit ${rc}: ${err}")

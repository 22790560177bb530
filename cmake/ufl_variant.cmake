# Copies the UFL file IN to OUT, setting its cell type to CELL (if given) on
# the line marked `# dembridge:cell`. Run by dembridge_compile_ufl.
file(READ "${IN}" text)
if(CELL)
  string(REGEX MATCH "CELL = \"[a-z]+\"[ ]*# dembridge:cell" marker "${text}")
  if(NOT marker)
    message(FATAL_ERROR "${IN}: no line 'CELL = \"...\"  # dembridge:cell' to set the cell type")
  endif()
  string(REGEX REPLACE "CELL = \"[a-z]+\"([ ]*# dembridge:cell)" "CELL = \"${CELL}\"\\1" text "${text}")
endif()
file(WRITE "${OUT}.tmp" "${text}")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUT}.tmp" "${OUT}")

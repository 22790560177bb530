# dembridge_compile_ufl(TARGET tgt SOURCE file.py NAME out_name [CELL cell])
#
# Compiles a UFL file with FFCx at build time and adds the generated C source
# to TARGET. With CELL, the file's line `CELL = "..."  # dembridge:cell` is
# rewritten first, so one UFL file serves several cell types; the generated
# symbols are named after NAME (form_<NAME>_<form>), which must be a valid C
# identifier. FFCx runs under DEMBRIDGE_FFCX_PYTHON (Debian's /usr/bin/python3).
set(DEMBRIDGE_FFCX_PYTHON "/usr/bin/python3" CACHE FILEPATH
    "Python interpreter that has FFCx (Debian: /usr/bin/python3)")
set(_DEMBRIDGE_UFL_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/ufl_variant.cmake")

execute_process(COMMAND ${DEMBRIDGE_FFCX_PYTHON} -c "import ffcx"
                RESULT_VARIABLE _ffcx_rc OUTPUT_QUIET ERROR_QUIET)
if(NOT _ffcx_rc EQUAL 0)
  message(FATAL_ERROR "FFCx is not importable by ${DEMBRIDGE_FFCX_PYTHON}. "
          "Install python3-ffcx (scripts/install-deps.sh does it) or set "
          "-DDEMBRIDGE_FFCX_PYTHON=<python with ffcx>.")
endif()

function(dembridge_compile_ufl)
  cmake_parse_arguments(ARG "" "TARGET;SOURCE;NAME;CELL" "" ${ARGN})
  if(NOT ARG_TARGET OR NOT ARG_SOURCE OR NOT ARG_NAME)
    message(FATAL_ERROR "dembridge_compile_ufl needs TARGET, SOURCE and NAME")
  endif()
  if(NOT ARG_NAME MATCHES "^[A-Za-z_][A-Za-z0-9_]*$")
    message(FATAL_ERROR "dembridge_compile_ufl: NAME '${ARG_NAME}' is not a C identifier")
  endif()
  get_filename_component(src "${ARG_SOURCE}" ABSOLUTE)
  set(outdir "${CMAKE_CURRENT_BINARY_DIR}/ufl")
  set(py "${outdir}/${ARG_NAME}.py")
  if(NOT ARG_CELL)
    set(ARG_CELL "")
  endif()
  add_custom_command(
    OUTPUT "${outdir}/${ARG_NAME}.c" "${outdir}/${ARG_NAME}.h"
    COMMAND ${CMAKE_COMMAND} -DIN=${src} -DOUT=${py} -DCELL=${ARG_CELL}
            -P ${_DEMBRIDGE_UFL_SCRIPT}
    COMMAND ${DEMBRIDGE_FFCX_PYTHON} -m ffcx -o ${outdir} ${py}
    DEPENDS "${src}" "${_DEMBRIDGE_UFL_SCRIPT}"
    COMMENT "FFCx: ${ARG_NAME} from ${ARG_SOURCE}"
    VERBATIM)
  target_sources(${ARG_TARGET} PRIVATE "${outdir}/${ARG_NAME}.c")
  target_include_directories(${ARG_TARGET} PRIVATE "${outdir}")
endfunction()

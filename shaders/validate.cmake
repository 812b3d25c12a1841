# Validates one shader with glslangValidator. This glslang (12) resolves
# #include only when preprocessing (-E) or compiling to SPIR-V, so the file
# is preprocessed first and the expanded text is validated as OpenGL GLSL.
get_filename_component(ext ${SRC} EXT)
get_filename_component(dir ${SRC} DIRECTORY)
get_filename_component(root ${CMAKE_CURRENT_LIST_DIR} ABSOLUTE)
execute_process(COMMAND ${VALIDATOR} -E -I${root} ${SRC} WORKING_DIRECTORY ${dir}
  OUTPUT_VARIABLE expanded ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${SRC}: preprocessing failed\n${expanded}${err}")
endif()
file(WRITE ${TMP}${ext} "${expanded}")
execute_process(COMMAND ${VALIDATOR} --quiet ${TMP}${ext} OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${SRC}: invalid GLSL\n${out}${err}")
endif()
file(TOUCH ${STAMP})

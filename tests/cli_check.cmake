# Run a command and check its exit code and that its stderr contains a text.
# -DCOMMAND="a;b;c" -DEXPECT_CODE=2 -DEXPECT_TEXT="..."
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code STREQUAL "${EXPECT_CODE}")
  message(FATAL_ERROR "exit code ${code}, expected ${EXPECT_CODE}\nstdout: ${out}\nstderr: ${err}")
endif()
if(DEFINED EXPECT_TEXT AND NOT "${out}${err}" MATCHES "${EXPECT_TEXT}")
  message(FATAL_ERROR "output does not contain '${EXPECT_TEXT}'\nstdout: ${out}\nstderr: ${err}")
endif()

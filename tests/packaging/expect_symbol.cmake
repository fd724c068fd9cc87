# cmake -DNM= -DELF= -DSYMBOL= -DTYPE= -P expect_symbol.cmake
# Passes if the image defines SYMBOL with nm type TYPE (T: a strong definition, W: a weak one),
# i.e. shows which definition of a hook the linker took.
execute_process(COMMAND "${NM}" "${ELF}" RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NM} ${ELF} failed (${rc})")
endif()
if(NOT out MATCHES "(^|\n)[0-9a-f]+ ([A-Za-z]) ${SYMBOL}\n")
  message(FATAL_ERROR "${ELF} does not define ${SYMBOL}")
endif()
if(NOT CMAKE_MATCH_2 STREQUAL TYPE)
  message(FATAL_ERROR "${ELF}: ${SYMBOL} has nm type ${CMAKE_MATCH_2}, expected ${TYPE}")
endif()
message(STATUS "${ELF}: ${SYMBOL} ${CMAKE_MATCH_2}")

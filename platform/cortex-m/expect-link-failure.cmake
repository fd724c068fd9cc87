# cmake -DBUILD_DIR=<build tree> -DTARGET=<target> -DEXPECT=<symbol> -P expect-link-failure.cmake
# Builds TARGET and succeeds only if the build FAILS with an undefined reference to EXPECT, i.e. the
# no-heap link check rejected it (and not, say, a compile error).
foreach(v BUILD_DIR TARGET EXPECT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "expect-link-failure.cmake: -D${v}=... is required")
  endif()
endforeach()
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${BUILD_DIR}" --target "${TARGET}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
message("${out}")
if(rc EQUAL 0)
  message(FATAL_ERROR "${TARGET} linked, but it uses the heap: the no-heap link check is not working")
endif()
string(FIND "${out}" "undefined reference to `${EXPECT}'" pos)
if(pos LESS 0)
  message(FATAL_ERROR "${TARGET} failed to build, but not with \"undefined reference to `${EXPECT}'\": see above")
endif()
message(STATUS "${TARGET} was rejected at link time as expected (undefined reference to ${EXPECT})")

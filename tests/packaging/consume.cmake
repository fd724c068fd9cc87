cmake_minimum_required(VERSION 3.25)  # script mode: IN_LIST, string(JSON)
# cmake -DBUILD_DIR= -DPREFIX= -DCONSUMERS=<src dir>[;<src dir>...] -DCONSUMER_BIN= [-DTOOLCHAIN=<file name>]
#       [-DCLI=ON] [-DGENERATOR=] -P consume.cmake
# Installs BUILD_DIR into PREFIX, then for each consumer project (consumer_c/, consumer_cxx/):
# configures and builds it against the installed package with find_package(kestrel); checks that
# none of Kestrel's own compile flags reached the consumer's compile commands and that its legacy
# file, which its own flags accept, fails under Kestrel's (so that check can fail); and runs the
# consumer's ctests (on the host: the hover values; on bare metal: which assertion hook the image
# links). With TOOLCHAIN, the consumers are cross-compiled with <PREFIX>/share/kestrel/cmake/
# <TOOLCHAIN>: the installed copy, so the test proves the toolchain files work from outside the
# source tree. With CLI, <PREFIX>/bin/kestrel must run and list the task registry.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    list(JOIN ARGN " " cmd)
    message(FATAL_ERROR "packaging: failed (${rc}): ${cmd}")
  endif()
endfunction()

# Kestrel's own policy (cmake/KestrelFlags.cmake): none of it may reach a consumer. The bare-metal
# toolchain file sets -ffp-contract=off itself (CMAKE_<LANG>_FLAGS_INIT) for whoever uses it, so
# that one is checked on the host only.
set(forbidden -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wdouble-promotion -fno-math-errno
    -DEIGEN_NO_MALLOC -DEIGEN_MPL2_ONLY -DEIGEN_NO_DEBUG -fno-exceptions -fno-rtti -fno-threadsafe-statics)
if(NOT TOOLCHAIN)
  list(APPEND forbidden -ffp-contract=off)
endif()

file(REMOVE_RECURSE "${PREFIX}" "${CONSUMER_BIN}")
run("${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}")

if(CLI)
  # The harness's command is installed on PATH (<prefix>/bin) and works from there.
  execute_process(COMMAND "${PREFIX}/bin/kestrel" list RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "position_setpoint_task")
    message(FATAL_ERROR "packaging: ${PREFIX}/bin/kestrel list failed (${rc}) or lists no position_setpoint_task:\n${out}${err}")
  endif()
  message(STATUS "packaging: ${PREFIX}/bin/kestrel list runs and lists position_setpoint_task")
endif()

foreach(src IN LISTS CONSUMERS)
  get_filename_component(name "${src}" NAME)
  set(bin "${CONSUMER_BIN}/${name}")
  set(args -S "${src}" -B "${bin}" "-DCMAKE_PREFIX_PATH=${PREFIX}" -DCMAKE_BUILD_TYPE=Release)
  if(GENERATOR)
    list(APPEND args -G "${GENERATOR}")
  endif()
  if(TOOLCHAIN)
    set(tc "${PREFIX}/share/kestrel/cmake/${TOOLCHAIN}")
    if(NOT EXISTS "${tc}")
      message(FATAL_ERROR "packaging: the installed package has no ${tc}")
    endif()
    list(APPEND args "-DCMAKE_TOOLCHAIN_FILE=${tc}")
  endif()
  run("${CMAKE_COMMAND}" ${args})
  run("${CMAKE_COMMAND}" --build "${bin}" -j 2)

  # Every compile command of the consumer's own build: its flags, none of Kestrel's.
  file(READ "${bin}/compile_commands.json" db)
  string(JSON n LENGTH "${db}")
  math(EXPR last "${n} - 1")
  set(checked 0)
  foreach(i RANGE ${last})
    string(JSON cmd GET "${db}" ${i} command)
    if(cmd MATCHES "kestrel_flags_canary")  # its object path; compiled only by the check below
      continue()
    endif()
    if(NOT cmd MATCHES " -Werror( |$)")
      message(FATAL_ERROR "packaging: ${name}: the consumer's own -Werror is missing from: ${cmd}")
    endif()
    separate_arguments(words UNIX_COMMAND "${cmd}")
    foreach(flag IN LISTS forbidden)
      if(flag IN_LIST words)
        message(FATAL_ERROR "packaging: ${name}: Kestrel's ${flag} reached the consumer: ${cmd}")
      endif()
    endforeach()
    math(EXPR checked "${checked} + 1")
  endforeach()
  if(checked LESS 3)
    message(FATAL_ERROR "packaging: ${name}: only ${checked} compile commands checked")
  endif()

  # The legacy file under Kestrel's warning policy must fail, or the check above proves nothing.
  execute_process(COMMAND "${CMAKE_COMMAND}" --build "${bin}" --target kestrel_flags_canary
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "-Werror=(shadow|pedantic|old-style-cast)")
    message(FATAL_ERROR "packaging: ${name}: its legacy file compiles under Kestrel's flags (${rc}); "
      "it no longer shows that they stay out of the consumer:\n${out}${err}")
  endif()

  run("${CMAKE_CTEST_COMMAND}" --test-dir "${bin}" --output-on-failure --no-tests=error)
  message(STATUS "packaging: ${name}: ${checked} compile commands without Kestrel's flags, built and checked against ${PREFIX}")
endforeach()

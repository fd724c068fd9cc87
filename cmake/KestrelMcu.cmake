# MCU images under QEMU: Cortex-M (Arm MPS2 boards, STM32F405/netduinoplus2; platform/cortex-m) and
# 32-bit RISC-V (QEMU virt, rv32imac / rv32imafc; platform/riscv): firmware executables and ktest
# images. Included by the port's CMakeLists.txt in MCU builds (KESTREL_BOARD != host). The port
# follows from the toolchain file (CMAKE_SYSTEM_PROCESSOR arm or riscv32); both share the code in
# platform/mcu (semihosting, console, runtime hooks) and the scripts in platform/cortex-m
# (run-qemu.sh, check-image.sh, heap-symbols.txt).
#
#   kestrel_add_mcu_executable(<name> SOURCES <src>... [LIBS <lib>...] [STACK_SIZE <bytes>]
#                              [EXCLUDE_FROM_ALL] [NO_IMAGE_CHECK] [RUN] [TIMEOUT <s>]
#                              [LINKER_SCRIPT <file>])
#     <name>.elf for KESTREL_BOARD: startup code, vector table / trap handler, fault handlers,
#     semihosting console (kestrel::platform), linker script <port>/ld/<board>.ld, no heap. Also <name>.elf.map.
#     Registers the ctest <name>.image (check-image.sh: no heap symbols, flash/RAM use) unless
#     NO_IMAGE_CHECK or EXCLUDE_FROM_ALL, and with RUN the ctest <name> that runs it under QEMU
#     and passes if it exits 0 (main's return value).
#
#   kestrel_add_mcu_test(<name> SOURCES <src>... [LIBS <lib>...] [STACK_SIZE <bytes>] [TIMEOUT <s>])
#     The same plus the ktest runner (tests/support/ktest_runner.cpp) and semihosting file access
#     (tests/support/test_io_semihost.cpp), linked with ld/<board>-tests.ld where the board has
#     one, include dirs tests/support and tests/, and the ctest
#     <name>: run-qemu.sh runs the image with the golden directory ($KESTREL_GOLDEN_DIR at test
#     time, else KESTREL_GOLDEN_DIR_DEFAULT) as a semihosting argument and passes if QEMU exits 0
#     and prints "<N> passed, 0 failed".
#
#   kestrel_add_qemu_test(<test> <image target> <argv0> <timeout s> [run-qemu.sh options...])
#     Any other QEMU run of an image, e.g. `--expect-status 3 --expect-output "BusFault"`.
#
# No heap, enforced at link time: every link gets -Wl,--wrap=<sym> for each symbol in
# platform/cortex-m/heap-symbols.txt (malloc, free, _sbrk, _malloc_r, operator new/delete, ...)
# and no __wrap_<sym> exists, so a reference that survives --gc-sections is an
# "undefined reference to `__wrap_malloc'" error. Code that never reaches the heap links as before.
include_guard(GLOBAL)

# The functions run in their callers' directory scopes (tests/, platform/, ...): everything they
# need is kept in the cache (INTERNAL: recomputed at every configure).
get_filename_component(_dir "${CMAKE_CURRENT_LIST_DIR}/../platform/cortex-m" ABSOLUTE)
set(KESTREL_CORTEX_M_DIR "${_dir}" CACHE INTERNAL "")
get_filename_component(_dir "${CMAKE_CURRENT_LIST_DIR}/../tests" ABSOLUTE)
set(KESTREL_TESTS_DIR "${_dir}" CACHE INTERNAL "")
set(KESTREL_TEST_SUPPORT_DIR "${_dir}/support" CACHE INTERNAL "")

if(CMAKE_SYSTEM_PROCESSOR STREQUAL "riscv32")
  set(_port riscv)
  set(_boards virt)
  set(_hint "--preset rv32imac|rv32imafc or -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-rv32imac.cmake")
elseif(CMAKE_SYSTEM_PROCESSOR STREQUAL "arm")
  set(_port cortex-m)
  set(_boards mps2-an385 mps2-an386 mps2-an500 netduinoplus2)
  set(_hint "--preset cortex-m4f|cortex-m7|cortex-m3|netduinoplus2 or -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-<cpu>.cmake")
else()
  message(FATAL_ERROR "KESTREL_BOARD=${KESTREL_BOARD} needs a cross toolchain (arm-none-eabi or riscv64-unknown-elf): "
                      "configure with --preset cortex-m4f|cortex-m7|cortex-m3|netduinoplus2|rv32imac|rv32imafc")
endif()
if(NOT CMAKE_SYSTEM_NAME STREQUAL "Generic" OR NOT KESTREL_BOARD IN_LIST _boards)
  message(FATAL_ERROR "KESTREL_BOARD=${KESTREL_BOARD} with the ${CMAKE_SYSTEM_PROCESSOR} toolchain: the ${_port} port "
                      "supports ${_boards}; configure with ${_hint}")
endif()
get_filename_component(_dir "${CMAKE_CURRENT_LIST_DIR}/../platform/${_port}" ABSOLUTE)
set(KESTREL_MCU_PORT_DIR "${_dir}" CACHE INTERNAL "")
get_filename_component(_dir "${CMAKE_CURRENT_LIST_DIR}/../platform/mcu" ABSOLUTE)
set(KESTREL_MCU_COMMON_DIR "${_dir}" CACHE INTERNAL "")
# Section layout the board scripts INCLUDE (a link dependency of every image).
file(GLOB _sections "${KESTREL_MCU_PORT_DIR}/ld/*-sections.ld")
set(KESTREL_MCU_SECTIONS_LD "${_sections}" CACHE INTERNAL "")

if(DEFINED KESTREL_QEMU_MACHINE AND NOT KESTREL_QEMU_MACHINE STREQUAL KESTREL_BOARD)
  message(FATAL_ERROR "KESTREL_BOARD=${KESTREL_BOARD}, but the toolchain file compiles for ${KESTREL_QEMU_MACHINE}: "
                      "pick the toolchain file of that board instead of setting KESTREL_BOARD")
endif()

set(KESTREL_MCU_LINKER_SCRIPT "${KESTREL_MCU_PORT_DIR}/ld/${KESTREL_BOARD}.ld" CACHE INTERNAL "")
# A board whose real RAM is smaller than what QEMU maps may give the ktest images their own script
# (netduinoplus2: 128 KiB on the chip, 192 KiB in QEMU; see ld/netduinoplus2-tests.ld).
if(EXISTS "${KESTREL_MCU_PORT_DIR}/ld/${KESTREL_BOARD}-tests.ld")
  set(KESTREL_MCU_TEST_LINKER_SCRIPT "${KESTREL_MCU_PORT_DIR}/ld/${KESTREL_BOARD}-tests.ld" CACHE INTERNAL "")
else()
  set(KESTREL_MCU_TEST_LINKER_SCRIPT "${KESTREL_MCU_LINKER_SCRIPT}" CACHE INTERNAL "")
endif()
set(KESTREL_MCU_QEMU_MACHINE "${KESTREL_BOARD}" CACHE INTERNAL "")  # QEMU's machine names are the board names

file(STRINGS "${KESTREL_CORTEX_M_DIR}/heap-symbols.txt" _lines)
set(_syms "")
foreach(_line IN LISTS _lines)
  string(REGEX REPLACE "#.*" "" _line "${_line}")
  string(STRIP "${_line}" _line)
  if(_line)
    list(APPEND _syms "${_line}")
  endif()
endforeach()
list(TRANSFORM _syms PREPEND "-Wl,--wrap=")
set(KESTREL_MCU_NO_HEAP_LINK_OPTIONS "${_syms}" CACHE INTERNAL "")

# The QEMU and size programs of the port; KESTREL_MCU_QEMU_OPTIONS: run-qemu.sh options every run
# of an image needs (RISC-V virt: no firmware, the image is loaded at the start of DRAM).
if(_port STREQUAL "riscv")
  find_program(KESTREL_QEMU_SYSTEM_RISCV32 qemu-system-riscv32)
  set(KESTREL_MCU_QEMU "${KESTREL_QEMU_SYSTEM_RISCV32}" CACHE INTERNAL "")
  set(_qemu_name qemu-system-riscv32)
  set(_qemu_pkg qemu-system-misc)
  set(KESTREL_MCU_QEMU_OPTIONS --bios none CACHE INTERNAL "")
  find_program(KESTREL_RISCV_SIZE riscv64-unknown-elf-size)
  set(KESTREL_MCU_SIZE "${KESTREL_RISCV_SIZE}" CACHE INTERNAL "")
else()
  find_program(KESTREL_QEMU_SYSTEM_ARM qemu-system-arm)
  set(KESTREL_MCU_QEMU "${KESTREL_QEMU_SYSTEM_ARM}" CACHE INTERNAL "")
  set(_qemu_name qemu-system-arm)
  set(_qemu_pkg qemu-system-arm)
  set(KESTREL_MCU_QEMU_OPTIONS "" CACHE INTERNAL "")
  if(NOT KESTREL_ARM_SIZE)
    find_program(KESTREL_ARM_SIZE arm-none-eabi-size)
  endif()
  set(KESTREL_MCU_SIZE "${KESTREL_ARM_SIZE}" CACHE INTERNAL "")
endif()
if(NOT KESTREL_MCU_QEMU)
  set(KESTREL_MCU_QEMU "${_qemu_name}" CACHE INTERNAL "")
  message(WARNING "${_qemu_name} not found: the MCU images build, but their ctests will fail. "
                  "Install it (Debian: apt-get install ${_qemu_pkg}).")
endif()
set(KESTREL_MCU_TEST_TIMEOUT 900 CACHE STRING "Seconds a QEMU run of an MCU test image may take")

# ctest <test> running image target <image> under QEMU through run-qemu.sh, which reports a missing
# QEMU with the package to install. ARGN: more run-qemu.sh options (--ktest, --expect-status ...).
function(kestrel_add_qemu_test test image argv0 timeout)
  add_test(NAME ${test}
    COMMAND sh "${KESTREL_CORTEX_M_DIR}/run-qemu.sh" --qemu "${KESTREL_MCU_QEMU}" --machine "${KESTREL_MCU_QEMU_MACHINE}" ${KESTREL_MCU_QEMU_OPTIONS}
            --elf "$<TARGET_FILE:${image}>" --name "${argv0}" --golden-default "${KESTREL_GOLDEN_DIR_DEFAULT}"
            --timeout ${timeout} ${ARGN})
  math(EXPR ctest_timeout "${timeout} + 30")
  set_tests_properties(${test} PROPERTIES LABELS "mcu;${KESTREL_BOARD}" TIMEOUT ${ctest_timeout})
endfunction()

function(kestrel_add_mcu_executable name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "EXCLUDE_FROM_ALL;NO_IMAGE_CHECK;RUN" "STACK_SIZE;TIMEOUT;LINKER_SCRIPT" "SOURCES;LIBS")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "kestrel_add_mcu_executable(${name}): unknown arguments ${arg_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT arg_LINKER_SCRIPT)
    set(arg_LINKER_SCRIPT "${KESTREL_MCU_LINKER_SCRIPT}")
  endif()
  set(exclude "")
  if(arg_EXCLUDE_FROM_ALL)
    set(exclude EXCLUDE_FROM_ALL)
  endif()
  add_executable(${name} ${exclude} ${arg_SOURCES})
  set_target_properties(${name} PROPERTIES SUFFIX ".elf")
  # Objects of kestrel_mcu_runtime (startup, vector table / trap entry, fault handlers, C/C++
  # runtime hooks) go straight onto the link line; kestrel_platform after the caller's libraries.
  target_link_libraries(${name} PRIVATE ${arg_LIBS} kestrel_platform kestrel_mcu_runtime)
  target_link_options(${name} PRIVATE
    -nostartfiles
    "-L${KESTREL_MCU_PORT_DIR}/ld" "-T${arg_LINKER_SCRIPT}"
    "-Wl,-Map=$<TARGET_FILE:${name}>.map"
    ${KESTREL_MCU_NO_HEAP_LINK_OPTIONS})
  if(arg_STACK_SIZE)
    target_link_options(${name} PRIVATE "-Wl,--defsym=__stack_size=${arg_STACK_SIZE}")
  endif()
  set_property(TARGET ${name} APPEND PROPERTY LINK_DEPENDS
    "${arg_LINKER_SCRIPT}" ${KESTREL_MCU_SECTIONS_LD}
    "${KESTREL_CORTEX_M_DIR}/heap-symbols.txt")

  if(NOT arg_NO_IMAGE_CHECK AND NOT arg_EXCLUDE_FROM_ALL)
    add_test(NAME ${name}.image
      COMMAND sh "${KESTREL_CORTEX_M_DIR}/check-image.sh" "${CMAKE_NM}" "${KESTREL_MCU_SIZE}"
              "$<TARGET_FILE:${name}>" "${KESTREL_CORTEX_M_DIR}/heap-symbols.txt")
    set_tests_properties(${name}.image PROPERTIES LABELS "mcu;${KESTREL_BOARD};image")
  endif()
  if(arg_RUN)
    if(NOT arg_TIMEOUT)
      set(arg_TIMEOUT ${KESTREL_MCU_TEST_TIMEOUT})
    endif()
    kestrel_add_qemu_test(${name} ${name} ${name} ${arg_TIMEOUT})
  endif()
endfunction()

function(kestrel_add_mcu_test name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "STACK_SIZE;TIMEOUT" "SOURCES;LIBS")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "kestrel_add_mcu_test(${name}): unknown arguments ${arg_UNPARSED_ARGUMENTS}")
  endif()
  set(stack "")
  if(arg_STACK_SIZE)
    set(stack STACK_SIZE ${arg_STACK_SIZE})
  endif()
  if(NOT arg_TIMEOUT)
    set(arg_TIMEOUT ${KESTREL_MCU_TEST_TIMEOUT})
  endif()
  kestrel_add_mcu_executable(${name} ${stack} LINKER_SCRIPT "${KESTREL_MCU_TEST_LINKER_SCRIPT}"
    SOURCES ${arg_SOURCES} "${KESTREL_TEST_SUPPORT_DIR}/ktest_runner.cpp" "${KESTREL_TEST_SUPPORT_DIR}/test_io_semihost.cpp"
    LIBS ${arg_LIBS})
  # Without KESTREL_TEST_GTEST, ktest.hpp selects its own runner's macros.
  target_include_directories(${name} PRIVATE "${KESTREL_TEST_SUPPORT_DIR}" "${KESTREL_TESTS_DIR}")
  target_compile_definitions(${name} PRIVATE KESTREL_GOLDEN_DIR_DEFAULT="${KESTREL_GOLDEN_DIR_DEFAULT}")
  kestrel_add_qemu_test(${name} ${name} ${name} ${arg_TIMEOUT} --ktest)
endfunction()

# ctests mcu.heap_canary_{malloc,new}_link_fails (both ports): the no-heap link check must reject an
# image that allocates. Each canary (platform/cortex-m/tests/heap_canary.cpp) is built on demand by
# its ctest (never by the normal build), which passes only if the link fails on the heap symbol.
function(kestrel_add_heap_canary_tests)
  foreach(kind malloc new)
    string(TOUPPER "${kind}" kind_upper)
    kestrel_add_mcu_executable(kestrel_heap_canary_${kind} EXCLUDE_FROM_ALL SOURCES "${KESTREL_CORTEX_M_DIR}/tests/heap_canary.cpp")
    target_compile_definitions(kestrel_heap_canary_${kind} PRIVATE KESTREL_CANARY_${kind_upper}=1)
  endforeach()
  set(canary_expect_malloc __wrap_malloc)
  set(canary_expect_new __wrap__Znwj)  # operator new(unsigned int): size_t is 32 bits on both
  foreach(kind malloc new)
    add_test(NAME mcu.heap_canary_${kind}_link_fails
      COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${CMAKE_BINARY_DIR} -DTARGET=kestrel_heap_canary_${kind}
              -DEXPECT=${canary_expect_${kind}} -P "${KESTREL_CORTEX_M_DIR}/expect-link-failure.cmake")
    # Both run a build in the same tree: never at the same time.
    set_tests_properties(mcu.heap_canary_${kind}_link_fails PROPERTIES
      LABELS "mcu;${KESTREL_BOARD};heap" RESOURCE_LOCK kestrel_build_tree TIMEOUT 300)
  endforeach()
endfunction()

# kestrel_add_board_tests(<mode|exit status|output regex>...): the board tests of both ports
# (platform/cortex-m/tests/test_board.cpp: the tick counter against a known instruction count,
# timer callbacks, semihosting reads, console, stack measurement), the failure-path probe image
# (board_probe.cpp) with one ctest mcu.probe_<mode> per argument, which must end QEMU with that
# status and print a line matching the regex, and the heap canaries.
function(kestrel_add_board_tests)
  set(dir "${KESTREL_CORTEX_M_DIR}/tests")
  kestrel_add_mcu_test(kestrel_platform_tests_mcu SOURCES "${dir}/test_board.cpp")
  target_compile_definitions(kestrel_platform_tests_mcu PRIVATE KESTREL_BOARD_TEST_SOURCE="${dir}/test_board.cpp")
  kestrel_add_mcu_executable(kestrel_board_probe SOURCES "${dir}/board_probe.cpp" LIBS kestrel_kernel STACK_SIZE 8192)
  foreach(probe IN LISTS ARGN)
    string(REPLACE "|" ";" probe "${probe}")
    list(GET probe 0 mode)
    list(GET probe 1 status)
    list(GET probe 2 regex)
    kestrel_add_qemu_test(mcu.probe_${mode} kestrel_board_probe ${mode} 60 --expect-status ${status} --expect-output "${regex}")
  endforeach()
  kestrel_add_heap_canary_tests()
endfunction()

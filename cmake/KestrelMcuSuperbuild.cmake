# From a host build (KESTREL_MCU_TESTS=ON): also configure and build this same source tree for the
# Cortex-M4F (Arm MPS2 AN386) in ${CMAKE_BINARY_DIR}/mcu-cortex-m4f, and register one host ctest,
# mcu.cortex-m4f, that runs that tree's ctests (core tests under QEMU, image checks, board tests,
# heap canaries). So `ctest --preset host` covers the host and the emulated MCU.
#
# Without the cross toolchain or QEMU this prints which Debian packages are missing and registers
# mcu.cortex-m4f as a disabled test (listed as "Not Run (Disabled)" at the end of ctest's output)
# instead of failing the host build.
include_guard(GLOBAL)

set(_kestrel_m4f_flags -mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb --specs=nano.specs)
find_program(KESTREL_ARM_GXX arm-none-eabi-g++)
find_program(KESTREL_QEMU_SYSTEM_ARM qemu-system-arm)

set(_kestrel_missing "")
if(NOT KESTREL_ARM_GXX)
  list(APPEND _kestrel_missing "arm-none-eabi-g++ (gcc-arm-none-eabi)")
else()
  # The compiler alone is not enough: newlib-nano (nano.specs, libc_nano.a) and its libstdc++.
  foreach(_lib_pkg "libc_nano.a|libnewlib-arm-none-eabi" "libstdc++_nano.a|libstdc++-arm-none-eabi-newlib")
    string(REPLACE "|" ";" _lib_pkg "${_lib_pkg}")
    list(GET _lib_pkg 0 _lib)
    list(GET _lib_pkg 1 _pkg)
    execute_process(COMMAND "${KESTREL_ARM_GXX}" ${_kestrel_m4f_flags} -print-file-name=${_lib}
      RESULT_VARIABLE _rc OUTPUT_VARIABLE _path ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(NOT _rc EQUAL 0 OR NOT IS_ABSOLUTE "${_path}" OR NOT EXISTS "${_path}")
      list(APPEND _kestrel_missing "${_lib} (${_pkg})")
    endif()
  endforeach()
endif()
if(NOT KESTREL_QEMU_SYSTEM_ARM)
  list(APPEND _kestrel_missing "qemu-system-arm (qemu-system-arm)")
endif()

if(_kestrel_missing)
  list(JOIN _kestrel_missing ", " _kestrel_missing_text)
  message(WARNING
    "KESTREL_MCU_TESTS=ON, but the Cortex-M4F tests cannot be built and run here: missing "
    "${_kestrel_missing_text}. On Debian/Ubuntu install them with\n"
    "  sudo apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib qemu-system-arm\n"
    "or configure with -DKESTREL_MCU_TESTS=OFF. The host build and tests go on without them.")
  add_test(NAME mcu.cortex-m4f COMMAND "${CMAKE_COMMAND}" -E echo "MCU tests unavailable: missing ${_kestrel_missing_text}")
  set_tests_properties(mcu.cortex-m4f PROPERTIES DISABLED TRUE LABELS "mcu")
  return()
endif()

include(ExternalProject)
set(KESTREL_MCU_M4F_BINARY_DIR "${CMAKE_BINARY_DIR}/mcu-cortex-m4f")
ExternalProject_Add(kestrel_mcu_cortex_m4f
  SOURCE_DIR "${PROJECT_SOURCE_DIR}"
  BINARY_DIR "${KESTREL_MCU_M4F_BINARY_DIR}"
  CMAKE_ARGS
    "-DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/cmake/toolchain-cortex-m4f.cmake"
    -DCMAKE_BUILD_TYPE=Release
    -DKESTREL_BUILD_TESTS=ON
    "-DKESTREL_GOLDEN_DIR_DEFAULT=${KESTREL_GOLDEN_DIR_DEFAULT}"
    "-DKESTREL_QEMU_SYSTEM_ARM=${KESTREL_QEMU_SYSTEM_ARM}"
    # The host build of the policy firmware example: the MCU tree's ctest
    # kestrel_firmware_policy.host_parity compares its trajectory hashes with the QEMU run's.
    "-DKESTREL_HOST_FIRMWARE_POLICY=$<TARGET_FILE:kestrel_firmware_policy_host>"
    # kestrel_firmware.host_parity: the Lee example's flight report, the same on host and MCU.
    "-DKESTREL_HOST_FIRMWARE=$<TARGET_FILE:kestrel_firmware_host>"
  BUILD_ALWAYS ON  # the sub-build's own ninja decides what is out of date
  INSTALL_COMMAND ""
  TEST_COMMAND "")

add_test(NAME mcu.cortex-m4f
  COMMAND "${CMAKE_CTEST_COMMAND}" --test-dir "${KESTREL_MCU_M4F_BINARY_DIR}" --output-on-failure)
set_tests_properties(mcu.cortex-m4f PROPERTIES LABELS "mcu;mps2-an386" TIMEOUT 3600)

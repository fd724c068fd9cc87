# From a host build (KESTREL_RISCV_TESTS=ON, the default; also needs KESTREL_MCU_TESTS): configure
# and build this same source tree for 32-bit RISC-V on QEMU's virt board, once per variant,
#   ${CMAKE_BINARY_DIR}/mcu-rv32imac    rv32imac/ilp32, soft float
#   ${CMAKE_BINARY_DIR}/mcu-rv32imafc   rv32imafc/ilp32f, single-precision FPU
# and register the host ctests mcu.rv32imac and mcu.rv32imafc, which run a subset of that tree's
# ctests under qemu-system-riscv32: the core tests image, the firmware examples (the policy
# example's trajectory hash and the Lee example's flight report compared with the host build's),
# the C API test, the board tests, the failure-path probes, the heap canaries (an image that
# allocates must fail to link), and the image checks of those images
# (no heap or undefined symbols; flash and RAM use). Only the images those tests need are built
# (not the benchmark images: bench/control/run-mcu-bench.sh builds them in the tree), which keeps
# the added build time to the core libraries and one test image per variant. The Cortex-M4F tree
# (KestrelMcuSuperbuild.cmake) stays the one that runs everything.
#
# Without the toolchain, picolibc, the borrowed libstdc++ headers or QEMU this prints which Debian
# packages are missing and registers the two tests as disabled instead of failing the host build.
include_guard(GLOBAL)

# What the RISC-V trees need, as "<what>|<Debian package>": programs by name, files by path
# (picolibc's specs file sits in GCC's library folder; the libstdc++ headers are the Arm toolchain's).
find_program(KESTREL_QEMU_SYSTEM_RISCV32 qemu-system-riscv32)
find_program(KESTREL_RISCV_GXX riscv64-unknown-elf-g++)
set(_kestrel_rv_specs "")
if(KESTREL_RISCV_GXX)
  execute_process(COMMAND "${KESTREL_RISCV_GXX}" -print-file-name=picolibc.specs
    OUTPUT_VARIABLE _kestrel_rv_specs ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
endif()
set(_kestrel_rv_missing "")
foreach(_need
    "${KESTREL_RISCV_GXX}|riscv64-unknown-elf-g++ (gcc-riscv64-unknown-elf)"
    "${_kestrel_rv_specs}|picolibc.specs (picolibc-riscv64-unknown-elf)"
    "/usr/include/newlib/c++/12.2.1/arm-none-eabi/thumb/v7e-m+fp/hard/bits/c++config.h|libstdc++ 12 headers (libstdc++-arm-none-eabi-dev)"
    "${KESTREL_QEMU_SYSTEM_RISCV32}|qemu-system-riscv32 (qemu-system-misc)")
  string(REPLACE "|" ";" _need "${_need}")
  list(LENGTH _need _n)
  list(GET _need -1 _what)
  if(_n LESS 2)
    list(APPEND _kestrel_rv_missing "${_what}")
  else()
    list(GET _need 0 _path)
    if(NOT IS_ABSOLUTE "${_path}" OR NOT EXISTS "${_path}")
      list(APPEND _kestrel_rv_missing "${_what}")
    endif()
  endif()
endforeach()

# The ctests of a RISC-V tree that the host ctest runs, and the targets they need.
set(_kestrel_rv_tests
  "^((kestrel_core_tests_mcu|kestrel_firmware|kestrel_firmware_policy|kestrel_firmware_hexa|kestrel_capi_test|kestrel_platform_tests_mcu|kestrel_board_probe)(\\.image)?|kestrel_firmware(_policy)?\\.host_parity|mcu\\.probe_.*|mcu\\.heap_canary_.*)$")
set(_kestrel_rv_targets kestrel_core_tests_mcu kestrel_firmware kestrel_firmware_policy kestrel_firmware_hexa
  kestrel_capi_test kestrel_board_probe kestrel_platform_tests_mcu)

include(ExternalProject)
foreach(_variant rv32imac rv32imafc)
  if(_kestrel_rv_missing)
    list(JOIN _kestrel_rv_missing ", " _text)
    if(_variant STREQUAL "rv32imac")
      message(WARNING
        "KESTREL_RISCV_TESTS=ON, but the RISC-V tests cannot be built and run here: missing ${_text}. "
        "On Debian/Ubuntu install them with\n"
        "  sudo apt-get install gcc-riscv64-unknown-elf picolibc-riscv64-unknown-elf libstdc++-arm-none-eabi-newlib qemu-system-misc\n"
        "or configure with -DKESTREL_RISCV_TESTS=OFF. The host build and tests go on without them.")
    endif()
    add_test(NAME mcu.${_variant} COMMAND "${CMAKE_COMMAND}" -E echo "RISC-V tests unavailable: missing ${_text}")
    set_tests_properties(mcu.${_variant} PROPERTIES DISABLED TRUE LABELS "mcu;riscv")
    continue()
  endif()
  set(_dir "${CMAKE_BINARY_DIR}/mcu-${_variant}")
  set(_build_targets "")
  foreach(_t IN LISTS _kestrel_rv_targets)
    list(APPEND _build_targets --target ${_t})
  endforeach()
  ExternalProject_Add(kestrel_mcu_${_variant}
    SOURCE_DIR "${PROJECT_SOURCE_DIR}"
    BINARY_DIR "${_dir}"
    CMAKE_ARGS
      "-DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/cmake/toolchain-${_variant}.cmake"
      -DCMAKE_BUILD_TYPE=Release
      -DKESTREL_BUILD_TESTS=ON
      "-DKESTREL_GOLDEN_DIR_DEFAULT=${KESTREL_GOLDEN_DIR_DEFAULT}"
      "-DKESTREL_QEMU_SYSTEM_RISCV32=${KESTREL_QEMU_SYSTEM_RISCV32}"
      "-DKESTREL_HOST_FIRMWARE_POLICY=$<TARGET_FILE:kestrel_firmware_policy_host>"
      "-DKESTREL_HOST_FIRMWARE=$<TARGET_FILE:kestrel_firmware_host>"
    BUILD_COMMAND "${CMAKE_COMMAND}" --build "${_dir}" ${_build_targets}
    BUILD_ALWAYS ON  # the sub-build's own ninja decides what is out of date
    INSTALL_COMMAND ""
    TEST_COMMAND "")
  add_test(NAME mcu.${_variant}
    COMMAND "${CMAKE_CTEST_COMMAND}" --test-dir "${_dir}" --output-on-failure -R "${_kestrel_rv_tests}")
  set_tests_properties(mcu.${_variant} PROPERTIES LABELS "mcu;riscv;virt" TIMEOUT 1800)
endforeach()

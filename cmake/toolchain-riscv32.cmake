# 32-bit RISC-V bare metal with Debian 12's packages: riscv64-unknown-elf-gcc 12 (its rv32 multilibs),
# picolibc (picolibc-riscv64-unknown-elf) as the C library, and the C++ library *headers* of the
# Arm toolchain's libstdc++ 12 (libstdc++-arm-none-eabi-dev): Debian ships no libstdc++ for
# riscv64-unknown-elf, and Kestrel needs none of its binary (-fno-exceptions -fno-rtti, no heap:
# the core's archives reference only libgcc, libm/libc and the platform's hooks). Only the
# target-specific bits/ directory of one Arm multilib is borrowed (thumb/v7e-m+fp/hard: atomics on,
# no __int128, no TLS, no threads, newlib's libc feature macros, which picolibc shares; the file by
# file review is in cmake/riscv32-core/README.md).
#
# Not used on its own by the board builds: toolchain-rv32imac.cmake (rv32imac/ilp32, soft float)
# and toolchain-rv32imafc.cmake (rv32imafc/ilp32f, single-precision FPU) set RISCV_MARCH,
# RISCV_MABI and the board, then include this file. Used directly (cmake/riscv32-core), it builds
# rv32imac/ilp32 unless RISCV_MARCH/RISCV_MABI are given.
#
# Executables: -nostartfiles and the linker script come from kestrel_add_mcu_executable
# (cmake/KestrelMcu.cmake, platform/riscv). The g++ driver always adds -lstdc++, which does not
# exist for riscv, and GCC 12 has no -nostdlib++: links use -nodefaultlibs and name picolibc and
# libgcc themselves (CMAKE_<LANG>_STANDARD_LIBRARIES).
# CSR instructions need Zicsr, which the sources enable with `.option arch, +zicsr`: a -march with
# _zicsr would match no multilib (-print-multi-directory gives ".", rv64) and the link would
# silently take the rv64 libgcc and picolibc.
if(NOT DEFINED RISCV_MARCH)
  set(RISCV_MARCH rv32imac)
endif()
if(NOT DEFINED RISCV_MABI)
  set(RISCV_MABI ilp32)
endif()
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR riscv32)
# try_compile() cannot link a bare-metal executable without startup code and a linker script.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RISCV_MARCH RISCV_MABI)
set(CMAKE_C_COMPILER riscv64-unknown-elf-gcc)
set(CMAKE_CXX_COMPILER riscv64-unknown-elf-g++)
set(CMAKE_ASM_COMPILER riscv64-unknown-elf-gcc)

# The borrowed libstdc++ headers (libstdc++-arm-none-eabi-dev).
set(KESTREL_RISCV_LIBSTDCXX_INCLUDE "/usr/include/newlib/c++/12.2.1" CACHE PATH
  "libstdc++ headers used for riscv (Debian 12: libstdc++-arm-none-eabi-dev)")
set(_kestrel_rv_bits "${KESTREL_RISCV_LIBSTDCXX_INCLUDE}/arm-none-eabi/thumb/v7e-m+fp/hard")
if(NOT EXISTS "${_kestrel_rv_bits}/bits/c++config.h")
  message(FATAL_ERROR "toolchain-riscv32.cmake: no ${_kestrel_rv_bits}/bits/c++config.h; "
                      "install libstdc++-arm-none-eabi-dev (Debian: apt-get install libstdc++-arm-none-eabi-newlib)")
endif()

# picolibc's specs: its headers, the rv32 multilib of its libraries, -ftls-model=local-exec.
# -ffunction-sections/-fdata-sections + --gc-sections as on Cortex-M. -ffp-contract=off: no fused
# multiply-add unless written (determinism contract, docs/design.md; rv32imafc has fmadd.s).
set(_kestrel_rv "-march=${RISCV_MARCH} -mabi=${RISCV_MABI} -mcmodel=medany --specs=picolibc.specs -ffunction-sections -fdata-sections -ffp-contract=off")
set(CMAKE_C_FLAGS_INIT "${_kestrel_rv}")
set(CMAKE_CXX_FLAGS_INIT "${_kestrel_rv} -isystem ${KESTREL_RISCV_LIBSTDCXX_INCLUDE} -isystem ${_kestrel_rv_bits}")
set(CMAKE_ASM_FLAGS_INIT "-march=${RISCV_MARCH} -mabi=${RISCV_MABI}")
# --no-warn-rwx-segments: QEMU loads the ELF into DRAM as linked; there is no flash to protect.
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nodefaultlibs -Wl,--gc-sections -Wl,--no-warn-rwx-segments")
foreach(_lang C CXX)
  set(CMAKE_${_lang}_STANDARD_LIBRARIES "-Wl,--start-group -lc -lgcc -Wl,--end-group")
endforeach()

# Release without -g, RelWithDebInfo with it: toolchain-arm-none-eabi.cmake says why.
foreach(_lang C CXX ASM)
  set(CMAKE_${_lang}_FLAGS_DEBUG "-Og -g" CACHE STRING "Flags used by the ${_lang} compiler during DEBUG builds.")
  set(CMAKE_${_lang}_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during RELEASE builds.")
  set(CMAKE_${_lang}_FLAGS_RELWITHDEBINFO "-O2 -g -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during RELWITHDEBINFO builds.")
  set(CMAKE_${_lang}_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during MINSIZEREL builds.")
endforeach()
if(NOT DEFINED CMAKE_BUILD_TYPE_INIT)
  set(CMAKE_BUILD_TYPE_INIT Release)
endif()
# Eigen is header-only: take the host's headers.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)

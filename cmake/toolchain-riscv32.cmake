# RV32IMAC (ilp32, soft float) bare metal with riscv64-unknown-elf-gcc and picolibc. Compiles the
# core libraries only (cmake/riscv32-core is the project that uses it; the Cortex-M board ports,
# firmware images and QEMU runs do not exist for RISC-V yet).
# Status: configures, but does not compile with Debian 12's packages: riscv64-unknown-elf-gcc +
# picolibc ship no libstdc++ headers (<cstdint> is missing) and Debian has no bare-metal RISC-V
# libstdc++; the evidence (package file lists, include search path) is in riscv32-core/README.md.
# A riscv toolchain with its C++ library (e.g. a picolibc-built libstdc++) is needed.
# Usage: cmake -S cmake/riscv32-core -B build/riscv32 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-riscv32.cmake
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR riscv32)
# try_compile() cannot link a bare-metal executable without startup code and a linker script.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(CMAKE_C_COMPILER riscv64-unknown-elf-gcc)
set(CMAKE_CXX_COMPILER riscv64-unknown-elf-g++)
set(CMAKE_ASM_COMPILER riscv64-unknown-elf-gcc)
# picolibc (not the toolchain's newlib): its specs select the rv32imac/ilp32 multilib.
# -ffp-contract=off: the determinism contract (docs/design.md); rv32imac has no FPU anyway.
set(_kestrel_rv "-march=rv32imac -mabi=ilp32 -mcmodel=medany --specs=picolibc.specs -ffunction-sections -fdata-sections -ffp-contract=off")
set(CMAKE_C_FLAGS_INIT "${_kestrel_rv}")
set(CMAKE_CXX_FLAGS_INIT "${_kestrel_rv}")
set(CMAKE_ASM_FLAGS_INIT "-march=rv32imac -mabi=ilp32")
foreach(_lang C CXX)
  set(CMAKE_${_lang}_FLAGS_RELEASE "-O2 -g -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during RELEASE builds.")
endforeach()
if(NOT CMAKE_BUILD_TYPE)
  set(CMAKE_BUILD_TYPE Release CACHE STRING "Build type")
endif()
# Eigen is header-only: take the host's headers.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)

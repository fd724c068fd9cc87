# Common toolchain file for bare-metal Arm Cortex-M with the GNU Arm Embedded toolchain
# (arm-none-eabi-gcc + newlib-nano). Not used on its own: a board file sets
# KESTREL_MCU_ARCH_FLAGS (and KESTREL_BOARD) and then includes this one, e.g.
#
#   cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-cortex-m4f.cmake ...
#
# It is self-contained (it reads no project variable), so any CMake project can use it to build
# libraries or code that links into a Kestrel image. It deliberately does not add startup files,
# linker scripts or the no-heap link options: those belong to the executables
# (kestrel_add_mcu_executable in cmake/KestrelMcu.cmake).
#
# ARM_TOOLCHAIN_DIR (cache or environment): bin/ folder of another arm-none-eabi install, e.g. an
# unpacked Arm GNU Toolchain release; default: whatever arm-none-eabi-gcc is on PATH.
if(NOT DEFINED KESTREL_MCU_ARCH_FLAGS)
  message(FATAL_ERROR "toolchain-arm-none-eabi.cmake is included by a board toolchain file "
                      "(toolchain-cortex-m4f.cmake, toolchain-cortex-m7.cmake, toolchain-cortex-m3.cmake)")
endif()

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
# try_compile() cannot link a bare-metal executable without startup code and a linker script.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

if(NOT DEFINED ARM_TOOLCHAIN_DIR AND DEFINED ENV{ARM_TOOLCHAIN_DIR})
  set(ARM_TOOLCHAIN_DIR "$ENV{ARM_TOOLCHAIN_DIR}")
endif()
set(_kestrel_tc_prefix "arm-none-eabi-")
if(ARM_TOOLCHAIN_DIR)
  set(_kestrel_tc_prefix "${ARM_TOOLCHAIN_DIR}/arm-none-eabi-")
endif()
set(CMAKE_C_COMPILER "${_kestrel_tc_prefix}gcc")
set(CMAKE_CXX_COMPILER "${_kestrel_tc_prefix}g++")
set(CMAKE_ASM_COMPILER "${_kestrel_tc_prefix}gcc")
# Carried into try_compile() projects, which re-read this file.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES ARM_TOOLCHAIN_DIR)

# arm-none-eabi-size is not one of the binutils CMake looks up itself.
find_program(KESTREL_ARM_SIZE NAMES arm-none-eabi-size HINTS "${ARM_TOOLCHAIN_DIR}" NO_CMAKE_FIND_ROOT_PATH)

# -ffunction-sections/-fdata-sections + --gc-sections: one section per function/object so the
# linker drops everything an image does not reach. -ffp-contract=off: no fused multiply-add unless
# written (determinism contract, docs/design.md). --specs=nano.specs: newlib-nano headers and
# libraries (smaller; the images use no stdio anyway).
set(_kestrel_common "${KESTREL_MCU_ARCH_FLAGS} -ffunction-sections -fdata-sections -ffp-contract=off --specs=nano.specs")
set(CMAKE_C_FLAGS_INIT "${_kestrel_common}")
set(CMAKE_CXX_FLAGS_INIT "${_kestrel_common}")
set(CMAKE_ASM_FLAGS_INIT "${KESTREL_MCU_ARCH_FLAGS}")
# CMake links through the compiler driver with CMAKE_<LANG>_FLAGS, so the architecture flags and
# the nano specs are already on the link line (the specs file cannot be given twice).
# -z noexecstack: newlib's assembly objects carry no .note.GNU-stack, which binutils >= 2.39
# would otherwise warn about at every link (there is no executable-stack notion on Cortex-M).
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections -Wl,-z,noexecstack")

# Per-configuration flags go straight into the cache: CMake's GNU compiler module appends its own
# "-O3 -DNDEBUG" to CMAKE_<LANG>_FLAGS_RELEASE_INIT, and the last -O wins. -O2, not -Os, in
# Release: the benchmarks compare the core at -O2 on every target. Release has no -g: debug
# sections never reach flash or RAM and GCC's code is the same with or without them (the objdump
# of the control bench compared equal, 2026-12-03), but they doubled the MCU test images' compile
# time, the largest part of the test command's build. RelWithDebInfo (-O2 -g) is the build for
# addr2line on a fault address.
foreach(_lang C CXX ASM)
  set(CMAKE_${_lang}_FLAGS_DEBUG "-Og -g" CACHE STRING "Flags used by the ${_lang} compiler during DEBUG builds.")
  set(CMAKE_${_lang}_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during RELEASE builds.")
  set(CMAKE_${_lang}_FLAGS_RELWITHDEBINFO "-O2 -g -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during RELWITHDEBINFO builds.")
  set(CMAKE_${_lang}_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "Flags used by the ${_lang} compiler during MINSIZEREL builds.")
endforeach()
if(NOT DEFINED CMAKE_BUILD_TYPE_INIT)
  set(CMAKE_BUILD_TYPE_INIT Release)
endif()

# Programs (qemu, scripts) come from the build machine; headers and packages may come from either
# (Eigen is header-only and the same for every target), so those modes stay at CMake's default.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)

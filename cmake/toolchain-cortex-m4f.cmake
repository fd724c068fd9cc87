# Cortex-M4F, single-precision FPU, hard-float ABI — Arm MPS2 board mps2-an386 (QEMU: -M mps2-an386).
# Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-cortex-m4f.cmake ...
set(KESTREL_MCU_ARCH_FLAGS "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb")
set(KESTREL_BOARD "mps2-an386" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "mps2-an386")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake")

# Cortex-M7, double-precision FPU (FPv5-D16), hard-float ABI — Arm MPS2 board mps2-an500 (QEMU: -M mps2-an500).
# Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-cortex-m7.cmake ...
set(KESTREL_MCU_ARCH_FLAGS "-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard -mthumb")
set(KESTREL_BOARD "mps2-an500" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "mps2-an500")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake")

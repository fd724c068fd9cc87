# Cortex-M3, no FPU, soft-float ABI — Arm MPS2 board mps2-an385 (QEMU: -M mps2-an385).
# Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-cortex-m3.cmake ...
set(KESTREL_MCU_ARCH_FLAGS "-mcpu=cortex-m3 -mfloat-abi=soft -mthumb")
set(KESTREL_BOARD "mps2-an385" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "mps2-an385")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake")

# STM32F405 (Cortex-M4F, single-precision FPU, hard-float ABI), the MCU of the Crazyflie 2.x —
# QEMU board netduinoplus2 (-M netduinoplus2: STM32F405RG, 168 MHz core clock).
# Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-stm32f405.cmake ...
# Same code generation as toolchain-cortex-m4f.cmake; the board differs (memory map, clock).
set(KESTREL_MCU_ARCH_FLAGS "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb")
set(KESTREL_BOARD "netduinoplus2" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "netduinoplus2")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake")

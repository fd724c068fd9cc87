# RV32IMAFC, ilp32f (single-precision FPU, hard-float ABI) — QEMU riscv32 virt board
# (qemu-system-riscv32 -M virt -bios none). Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-rv32imafc.cmake ...
set(RISCV_MARCH rv32imafc)
set(RISCV_MABI ilp32f)
set(KESTREL_RISCV_CPU_NAME "RV32IMAFC")
set(KESTREL_BOARD "virt" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "virt")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-riscv32.cmake")

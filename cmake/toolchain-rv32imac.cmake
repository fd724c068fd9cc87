# RV32IMAC, ilp32 (soft float) — QEMU riscv32 virt board (qemu-system-riscv32 -M virt -bios none).
# Usage: cmake -DCMAKE_TOOLCHAIN_FILE=<kestrel>/cmake/toolchain-rv32imac.cmake ...  (or --preset rv32imac)
set(RISCV_MARCH rv32imac)
set(RISCV_MABI ilp32)
set(KESTREL_RISCV_CPU_NAME "RV32IMAC")
set(KESTREL_BOARD "virt" CACHE STRING "Target board")
set(KESTREL_QEMU_MACHINE "virt")
include("${CMAKE_CURRENT_LIST_DIR}/toolchain-riscv32.cmake")

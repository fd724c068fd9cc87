// CSR access for the RISC-V port (M-mode). Zicsr is enabled per instruction with .option arch, not
// with -march (see start.S: -march=rv32imac_zicsr matches no multilib of Debian's GCC 12).
#pragma once

#include <cstdint>

#define KESTREL_CSR_READ(csr, out) \
  asm volatile(".option push\n .option arch, +zicsr\n csrr %0, " #csr "\n .option pop" : "=r"(out))
#define KESTREL_CSR_SET(csr, bits) \
  asm volatile(".option push\n .option arch, +zicsr\n csrs " #csr ", %0\n .option pop" : : "r"(bits) : "memory")
#define KESTREL_CSR_CLEAR(csr, bits) \
  asm volatile(".option push\n .option arch, +zicsr\n csrc " #csr ", %0\n .option pop" : : "r"(bits) : "memory")

namespace kestrel::platform::riscv {

/// mcycle as a 64-bit count (the high half re-read until it did not change across the low read).
/// Under `qemu -icount shift=0` it advances exactly once per instruction (and through WFI sleep as
/// virtual time passes), the same as minstret.
inline std::uint64_t cycles() {
  std::uint32_t hi;
  std::uint32_t lo;
  std::uint32_t hi2;
  do {
    KESTREL_CSR_READ(mcycleh, hi);
    KESTREL_CSR_READ(mcycle, lo);
    KESTREL_CSR_READ(mcycleh, hi2);
  } while (hi != hi2);
  return (static_cast<std::uint64_t>(hi) << 32) | lo;
}

constexpr std::uint32_t kMstatusMie = 1u << 3;
constexpr std::uint32_t kMieMtie = 1u << 7;
constexpr std::uint32_t kMcauseInterrupt = 1u << 31;
constexpr std::uint32_t kMcauseMachineTimer = 7u;

/// Machine timer interrupt (board.cpp): the next deadline, and a tick callback.
void timer_interrupt();

}  // namespace kestrel::platform::riscv

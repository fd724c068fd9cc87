// Core-specific primitives the shared MCU sources (platform/mcu/src) need, for both ports.
#pragma once

#include <cstdint>

namespace kestrel::platform::arch {

/// Masks interrupts and returns the previous state for irq_restore. Cortex-M: PRIMASK. RISC-V
/// (M-mode): mstatus.MIE; Zicsr is enabled per instruction with .option arch, not with -march
/// (platform/riscv/src/start.S says why).
inline std::uint32_t irq_save() {
  std::uint32_t state;
#if defined(__riscv)
  asm volatile(".option push\n .option arch, +zicsr\n csrrci %0, mstatus, 8\n .option pop" : "=r"(state) : : "memory");
#else
  asm volatile("mrs %0, primask\n cpsid i" : "=r"(state) : : "memory");
#endif
  return state;
}
inline void irq_restore(std::uint32_t state) {
#if defined(__riscv)
  asm volatile(".option push\n .option arch, +zicsr\n csrs mstatus, %0\n .option pop" : : "r"(state & 8u) : "memory");
#else
  asm volatile("msr primask, %0" : : "r"(state) : "memory");
#endif
}

}  // namespace kestrel::platform::arch

// Core-specific primitives the shared MCU sources (platform/mcu/src) need: RISC-V, M-mode.
#pragma once

#include <cstdint>

namespace kestrel::platform::arch {

/// Masks interrupts (mstatus.MIE) and returns the previous mstatus for irq_restore. Zicsr is
/// enabled per instruction (.option arch), not with -march: see start.S.
inline std::uint32_t irq_save() {
  std::uint32_t mstatus;
  asm volatile(".option push\n .option arch, +zicsr\n csrrci %0, mstatus, 8\n .option pop" : "=r"(mstatus) : : "memory");
  return mstatus;
}
inline void irq_restore(std::uint32_t mstatus) {
  asm volatile(".option push\n .option arch, +zicsr\n csrs mstatus, %0\n .option pop" : : "r"(mstatus & 8u) : "memory");
}

}  // namespace kestrel::platform::arch

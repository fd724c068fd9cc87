// Core-specific primitives the shared MCU sources (platform/mcu/src) need: Cortex-M.
#pragma once

#include <cstdint>

namespace kestrel::platform::arch {

/// Masks interrupts (PRIMASK) and returns the previous mask for irq_restore.
inline std::uint32_t irq_save() {
  std::uint32_t primask;
  asm volatile("mrs %0, primask\n cpsid i" : "=r"(primask) : : "memory");
  return primask;
}
inline void irq_restore(std::uint32_t primask) { asm volatile("msr primask, %0" : : "r"(primask) : "memory"); }

}  // namespace kestrel::platform::arch

// Clocks and tick pacing shared by the firmware examples' mains.
// Host: the steady clock in nanoseconds (costs are reported, never asserted: the host is shared).
// Cortex-M: SysTick interrupts pace the loop (the core sleeps in WFI between ticks) and SysTick
// ticks time it; under QEMU -icount shift=0 one tick is exactly 40 instructions. RISC-V: the
// CLINT timer paces it and mcycle times it (one tick = one instruction; board.hpp).
#pragma once

#include <cstdint>

#if defined(KESTREL_PLATFORM_CORTEX_M) || defined(KESTREL_PLATFORM_RISCV)
#include <cstddef>

#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"

namespace kestrel::firmware::loop_clock {
namespace detail {
inline volatile std::uint32_t g_ticks_pending = 0;
inline void on_tick() { g_ticks_pending = g_ticks_pending + 1u; }
}  // namespace detail

/// Starts SysTick so that wait_for_tick() returns at `rate_hz`.
inline void start_ticks(float rate_hz) {
  namespace board = kestrel::platform::board;
  const std::uint32_t reload = static_cast<std::uint32_t>(static_cast<float>(board::kCoreClockHz) / rate_hz + 0.5f) - 1u;
  board::systick_start(reload, &detail::on_tick);
}

/// Sleeps until the next tick (a tick that already passed returns at once: no tick is lost).
inline void wait_for_tick() {
  while (detail::g_ticks_pending == 0u) {
    __asm volatile("wfi");
  }
  detail::g_ticks_pending = detail::g_ticks_pending - 1u;
}

inline std::uint64_t now_ticks() { return kestrel::platform::board::systick_now(); }

/// "<cpu>, QEMU <board>, -icount shift=0" into out, without snprintf (newlib's pulls in malloc).
template <std::size_t N>
void describe_target(char (&out)[N]) {
  namespace board = kestrel::platform::board;
  const char* parts[] = {board::kCpuName, ", QEMU ", board::kBoardName, ", -icount shift=0"};
  std::size_t n = 0;
  for (const char* p : parts)
    for (; *p != '\0' && n + 1 < N; ++p) out[n++] = *p;
  out[n] = '\0';
}

/// Prints the painted-stack high-water mark.
inline void print_stack_use() {
  namespace board = kestrel::platform::board;
  kestrel::platform::print("  stack used: ");
  kestrel::platform::print_uint(board::stack_used_bytes());
  kestrel::platform::print(" of ");
  kestrel::platform::print_uint(board::stack_size_bytes());
  kestrel::platform::println(" bytes");
}
}  // namespace kestrel::firmware::loop_clock

#else
#include <chrono>

namespace kestrel::firmware::loop_clock {
inline std::uint64_t now_ns() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
}
}  // namespace kestrel::firmware::loop_clock
#endif

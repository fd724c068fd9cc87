// SysTick timing for the Cortex-M boards (kestrel/platform/board.hpp; stack use and exit:
// platform/mcu/src/runtime_common.cpp).
#include "kestrel/platform/board.hpp"

#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"
#include "runtime.h"

extern "C" {
void SysTick_Handler();
}

namespace kestrel::platform::board {
namespace {

// SysTick (Armv7-M ARM B3.3) and the SCB's interrupt control register.
struct SysTickRegs {
  volatile std::uint32_t csr;  // control and status
  volatile std::uint32_t rvr;  // reload value
  volatile std::uint32_t cvr;  // current value
  volatile std::uint32_t calib;
};
SysTickRegs& systick() { return *reinterpret_cast<SysTickRegs*>(0xE000E010u); }
volatile std::uint32_t& icsr() { return *reinterpret_cast<volatile std::uint32_t*>(0xE000ED04u); }

constexpr std::uint32_t kCsrEnable = 1u << 0;
constexpr std::uint32_t kCsrTickInt = 1u << 1;
constexpr std::uint32_t kCsrClkSourceCore = 1u << 2;
constexpr std::uint32_t kIcsrPendStSet = 1u << 26;

volatile std::uint32_t g_wraps = 0;
std::uint32_t g_period = 0;  // reload + 1
TickCallback g_callback = nullptr;

}  // namespace

void systick_start(std::uint32_t reload_ticks, TickCallback on_wrap) {
  if (reload_ticks == 0) reload_ticks = 1;
  if (reload_ticks > kSysTickMaxReload) reload_ticks = kSysTickMaxReload;
  systick().csr = 0;
  g_wraps = 0;
  g_period = reload_ticks + 1;
  g_callback = on_wrap;
  systick().rvr = reload_ticks;
  systick().cvr = 0;  // any write clears it; the first tick after enabling loads RVR
  systick().csr = kCsrEnable | kCsrTickInt | kCsrClkSourceCore;
}

void systick_stop() { systick().csr = 0; }

std::uint32_t systick_current() { return systick().cvr; }

std::uint32_t systick_wraps() { return g_wraps; }

std::uint64_t systick_now() {
  std::uint32_t primask;
  asm volatile("mrs %0, primask\n cpsid i" : "=r"(primask) : : "memory");
  // With interrupts masked a wrap can still happen; it shows as the SysTick exception pending.
  // CVR read before the pending check belongs to g_wraps as it stands; if the exception is pending
  // the wrap happened before the check, and CVR read after it belongs to g_wraps + 1.
  std::uint32_t wraps = g_wraps;
  std::uint32_t cvr = systick().cvr;
  if ((icsr() & kIcsrPendStSet) != 0) {
    cvr = systick().cvr;
    ++wraps;
  }
  asm volatile("msr primask, %0" : : "r"(primask) : "memory");
  // From a start at CVR = 0 the counter reads 0, R, R-1, ..., 1, 0 (interrupt), R, ...: tick t has
  // wraps = t / P and CVR = (t % P == 0) ? 0 : P - t % P, with P = R + 1.
  const std::uint64_t base = static_cast<std::uint64_t>(wraps) * g_period;
  return cvr == 0 ? base : base + (g_period - cvr);
}

}  // namespace kestrel::platform::board

extern "C" void SysTick_Handler() {
  using namespace kestrel::platform::board;
  g_wraps = g_wraps + 1;
  if (g_callback != nullptr) g_callback();
}

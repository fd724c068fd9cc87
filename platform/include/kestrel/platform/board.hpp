// Board API of the Cortex-M ports (Arm MPS2 AN385 / AN386 / AN500 under QEMU): core clock,
// SysTick timing, console flush, stack use, exit. MCU builds only (KESTREL_PLATFORM_CORTEX_M).
//
// Timing under QEMU: run with `-icount shift=0,sleep=off` (run-qemu.sh does) and every guest
// instruction advances virtual time by exactly 1 ns (sleep=off: an idle core, WFI, jumps to the
// next timer deadline instead of waiting in host time, which would make results vary). SysTick counts the 25 MHz core clock, i.e. one tick per
// 40 ns = 40 instructions, so tick counts are deterministic instruction counts with a resolution
// of 40 instructions (ticks_to_instructions). Measured, not assumed: see
// platform/cortex-m/tests/test_systick_calibration.cpp. Without -icount the ticks follow host
// wall-clock time and mean nothing.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kestrel::platform::board {

/// The board and CPU this image is built for ("mps2-an386", "Cortex-M4F"; from the build).
inline constexpr const char* kBoardName = KESTREL_BOARD_NAME;
inline constexpr const char* kCpuName = KESTREL_BOARD_CPU;
/// Floating-point hardware: single precision (M4F, M7), double precision too (M7). Without an FPU
/// (M3) float arithmetic is emulated in software and costs several times more instructions.
#if defined(__ARM_FP)
inline constexpr bool kHasFpu = (__ARM_FP & 0x4) != 0;
inline constexpr bool kHasDoubleFpu = (__ARM_FP & 0x8) != 0;
#else
inline constexpr bool kHasFpu = false;
inline constexpr bool kHasDoubleFpu = false;
#endif

/// MPS2 FPGA images clock the core (and SysTick with CLKSOURCE = processor clock) at 25 MHz.
inline constexpr std::uint32_t kCoreClockHz = 25'000'000;
/// SysTick's reload register is 24 bits wide.
inline constexpr std::uint32_t kSysTickMaxReload = 0x00FF'FFFF;
/// Guest instructions per SysTick tick under `qemu -icount shift=0` (1 instruction = 1 ns).
inline constexpr std::uint32_t kIcountInstructionsPerTick = 1'000'000'000u / kCoreClockHz;

using TickCallback = void (*)();

/// Starts SysTick on the core clock with its interrupt on: the counter runs down from
/// reload_ticks (written to SYST_RVR, 1..kSysTickMaxReload) and wraps every reload_ticks + 1
/// ticks, calling on_wrap (if not null) from the SysTick interrupt each time. Resets the
/// systick_now() count to 0. For pure timing use the default, kSysTickMaxReload (one interrupt
/// per 0.67 s of core time).
void systick_start(std::uint32_t reload_ticks = kSysTickMaxReload, TickCallback on_wrap = nullptr);
void systick_stop();
/// Raw down-counter SYST_CVR (reload_ticks .. 0).
std::uint32_t systick_current();
/// Number of wraps (SysTick interrupts) since systick_start.
std::uint32_t systick_wraps();
/// Ticks since systick_start as a monotonic 64-bit count (wraps folded in; safe against a wrap
/// racing the read). Costs a few dozen instructions; measure an empty region to subtract it.
std::uint64_t systick_now();

/// Elapsed ticks across a region: `TickRegion r; work(); const auto t = r.elapsed();`
class TickRegion {
 public:
  TickRegion() : start_(systick_now()) {}
  std::uint64_t elapsed() const { return systick_now() - start_; }
  void restart() { start_ = systick_now(); }

 private:
  std::uint64_t start_;
};

/// Ticks spent in f() (call overhead of systick_now() included).
template <typename F>
std::uint64_t measure_ticks(F&& f) {
  const std::uint64_t t0 = systick_now();
  f();
  return systick_now() - t0;
}

/// Guest instructions for an elapsed tick count under `-icount shift=0`.
constexpr std::uint64_t ticks_to_instructions(std::uint64_t ticks) { return ticks * kIcountInstructionsPerTick; }
/// Nanoseconds of core time for an elapsed tick count.
constexpr std::uint64_t ticks_to_ns(std::uint64_t ticks) { return ticks * (1'000'000'000u / kCoreClockHz); }

/// Flushes the buffered semihosting console (console_write flushes at each newline by itself).
void console_flush();

/// Main stack: size reserved by the linker script, and the most of it used so far (high-water
/// mark of the paint pattern written at reset).
std::size_t stack_size_bytes();
std::size_t stack_used_bytes();

/// Flushes the console and ends the program; QEMU exits with `code` (0 = success; see
/// semihosting.hpp for how other codes map to QEMU's exit status).
[[noreturn]] void semihost_exit(int code);

}  // namespace kestrel::platform::board

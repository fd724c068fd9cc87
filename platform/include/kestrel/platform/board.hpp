// Board API of the Cortex-M ports (Arm MPS2 AN385 / AN386 / AN500 and the STM32F405 of QEMU's
// netduinoplus2) and of the 32-bit RISC-V port (QEMU virt, platform/riscv): core clock, SysTick
// timing, console flush, stack use, exit. MCU builds only
// (KESTREL_PLATFORM_CORTEX_M or KESTREL_PLATFORM_RISCV).
//
// RISC-V has no SysTick: there the "SysTick" functions read the mcycle counter, which under
// `-icount shift=0` advances once per instruction, with kCoreClockHz = 1 GHz (1 tick = 1
// instruction = 1 ns); a callback given to systick_start is paced by the CLINT machine timer
// (10 MHz, 100 instructions per mtime tick), exact when the period is a multiple of 100 ticks.
//
// Timing under QEMU: run with `-icount shift=0,sleep=off` (run-qemu.sh does) and every guest
// instruction advances virtual time by exactly 1 ns (sleep=off: an idle core, WFI, jumps to the
// next timer deadline instead of waiting in host time, which would make results vary). SysTick
// counts the core clock (kCoreClockHz, set per board by the build), so a tick count is an
// instruction count: ticks * 1e9 / kCoreClockHz (ticks_to_instructions). MPS2 boards: 25 MHz, one
// tick = exactly 40 instructions. netduinoplus2 (STM32F405): 168 MHz, one tick = 125/21 = 5.95
// instructions, so 21 ticks are exactly 125 instructions and a region is exact to +-1 tick (6
// instructions). Measured, not assumed: platform/cortex-m/tests/test_board.cpp. Without -icount
// the ticks follow host wall-clock time and mean nothing.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kestrel::platform::board {

/// The board and CPU this image is built for ("mps2-an386", "Cortex-M4F"; from the build,
/// platform/cortex-m/CMakeLists.txt).
inline constexpr const char* kBoardName = KESTREL_BOARD_NAME;
inline constexpr const char* kCpuName = KESTREL_BOARD_CPU;
/// Floating-point hardware: single precision (M4F, M7), double precision too (M7). Without an FPU
/// (M3) float arithmetic is emulated in software and costs several times more instructions.
#if defined(__ARM_FP)
inline constexpr bool kHasFpu = (__ARM_FP & 0x4) != 0;
inline constexpr bool kHasDoubleFpu = (__ARM_FP & 0x8) != 0;
#elif defined(__riscv_flen)
inline constexpr bool kHasFpu = true;  // F (rv32imafc); D if FLEN is 64
inline constexpr bool kHasDoubleFpu = __riscv_flen >= 64;
#else
inline constexpr bool kHasFpu = false;
inline constexpr bool kHasDoubleFpu = false;
#endif

/// Core clock (and SysTick's, with CLKSOURCE = processor clock) as QEMU models the board: the
/// MPS2 FPGA images run at 25 MHz, the netduinoplus2's STM32F405 at 168 MHz.
#if defined(KESTREL_BOARD_CORE_CLOCK_HZ)
inline constexpr std::uint32_t kCoreClockHz = KESTREL_BOARD_CORE_CLOCK_HZ;
#else
inline constexpr std::uint32_t kCoreClockHz = 25'000'000;
#endif
/// SysTick's reload register is 24 bits wide.
inline constexpr std::uint32_t kSysTickMaxReload = 0x00FF'FFFF;
/// Guest instructions (= ns of virtual time) per second under `qemu -icount shift=0`.
inline constexpr std::uint64_t kIcountInstructionsPerSecond = 1'000'000'000u;
/// Guest instructions per SysTick tick under `qemu -icount shift=0`: 40 on the MPS2 boards,
/// 5.952... on the netduinoplus2 (not an integer: use ticks_to_instructions for exact counts).
inline constexpr double kIcountInstructionsPerTick =
    static_cast<double>(kIcountInstructionsPerSecond) / static_cast<double>(kCoreClockHz);

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

/// Guest instructions for an elapsed tick count under `-icount shift=0`, rounded to the nearest
/// (exact on the MPS2 boards: ticks * 40; netduinoplus2: ticks * 125 / 21). `scale` multiplies
/// the result before rounding (e.g. 10 for tenths of an instruction per call).
constexpr std::uint64_t ticks_to_instructions(std::uint64_t ticks, std::uint64_t scale = 1) {
  return (ticks * kIcountInstructionsPerSecond * scale + kCoreClockHz / 2u) / kCoreClockHz;
}
/// SysTick ticks that `instructions` guest instructions take under `-icount shift=0` (rounded down).
constexpr std::uint64_t instructions_to_ticks(std::uint64_t instructions) {
  return instructions * kCoreClockHz / kIcountInstructionsPerSecond;
}
/// Nanoseconds of core time for an elapsed tick count (rounded to the nearest).
constexpr std::uint64_t ticks_to_ns(std::uint64_t ticks) { return ticks_to_instructions(ticks); }

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

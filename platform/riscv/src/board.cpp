// Timing for the RISC-V virt port (kestrel/platform/board.hpp): the board API's "SysTick" is the
// mcycle counter, 1 tick = 1 instruction under -icount shift=0 (KESTREL_BOARD_CORE_CLOCK_HZ =
// 1e9: one instruction per ns of virtual time). The pacing interrupt (systick_start with a
// callback) comes from the CLINT machine timer, mtime at 10 MHz = 1 mtime tick per 100
// instructions. Stack use and exit: platform/mcu/src/runtime_common.cpp.
#include "kestrel/platform/board.hpp"

#include "csr.hpp"

namespace kestrel::platform::board {
namespace {

// CLINT of QEMU's virt board (hw/riscv/virt.c: VIRT_CLINT at 0x02000000; SiFive layout).
volatile std::uint64_t& mtime() { return *reinterpret_cast<volatile std::uint64_t*>(0x0200BFF8u); }
volatile std::uint32_t* mtimecmp_hart0() { return reinterpret_cast<volatile std::uint32_t*>(0x02004000u); }
constexpr std::uint64_t kInstructionsPerMtimeTick = 100;  // 1e9 / 10 MHz

std::uint64_t g_base = 0;    // mcycle at systick_start
std::uint64_t g_period = 1;  // reload + 1 ticks (instructions)
std::uint64_t g_deadline = 0;
std::uint64_t g_deadline_step = 0;  // mtime ticks per period
TickCallback g_callback = nullptr;

std::uint64_t read_mtime() {
  // Two 32-bit halves on RV32: re-read until the high half is stable.
  const volatile std::uint32_t* p = reinterpret_cast<const volatile std::uint32_t*>(&mtime());
  std::uint32_t hi;
  std::uint32_t lo;
  do {
    hi = p[1];
    lo = p[0];
  } while (hi != p[1]);
  return (static_cast<std::uint64_t>(hi) << 32) | lo;
}

void write_mtimecmp(std::uint64_t v) {
  // No spurious interrupt in between: high half to all ones first.
  volatile std::uint32_t* cmp = mtimecmp_hart0();
  cmp[1] = 0xFFFFFFFFu;
  cmp[0] = static_cast<std::uint32_t>(v);
  cmp[1] = static_cast<std::uint32_t>(v >> 32);
}

}  // namespace

void systick_start(std::uint32_t reload_ticks, TickCallback on_wrap) {
  if (reload_ticks == 0) reload_ticks = 1;
  if (reload_ticks > kSysTickMaxReload) reload_ticks = kSysTickMaxReload;
  systick_stop();
  g_period = static_cast<std::uint64_t>(reload_ticks) + 1u;
  g_callback = on_wrap;
  g_base = riscv::cycles();
  if (on_wrap != nullptr) {
    // Exact when the period is a multiple of 100 instructions (the firmware's 500 Hz: 2e6).
    g_deadline_step = (g_period + kInstructionsPerMtimeTick / 2u) / kInstructionsPerMtimeTick;
    if (g_deadline_step == 0) g_deadline_step = 1;
    g_deadline = read_mtime() + g_deadline_step;
    write_mtimecmp(g_deadline);
    KESTREL_CSR_SET(mie, riscv::kMieMtie);
    KESTREL_CSR_SET(mstatus, riscv::kMstatusMie);
  }
}

void systick_stop() {
  KESTREL_CSR_CLEAR(mie, riscv::kMieMtie);
  g_callback = nullptr;
}

std::uint64_t systick_now() { return riscv::cycles() - g_base; }

std::uint32_t systick_wraps() { return static_cast<std::uint32_t>(systick_now() / g_period); }

std::uint32_t systick_current() {
  // SysTick's down-counter, as the same arithmetic on the cycle count (board.cpp of the Cortex-M
  // port: tick t reads 0 when t % P == 0, else P - t % P).
  const std::uint64_t r = systick_now() % g_period;
  return static_cast<std::uint32_t>(r == 0 ? 0 : g_period - r);
}

}  // namespace kestrel::platform::board

namespace kestrel::platform::riscv {

void timer_interrupt() {
  using namespace kestrel::platform::board;
  g_deadline += g_deadline_step;
  write_mtimecmp(g_deadline);
  if (g_callback != nullptr) g_callback();
}

}  // namespace kestrel::platform::riscv

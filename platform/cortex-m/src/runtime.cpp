// Cortex-M runtime for the Kestrel images: early hardware set-up (vector table, fault handlers,
// MPU stack guard) and the fault reports over the semihosting console. Exit, fatal errors, the
// default assertion handler and libstdc++'s error paths are shared with the RISC-V port
// (platform/mcu/src/runtime_common.cpp).
#include <cstdint>

#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"
#include "runtime.h"

extern "C" {
extern std::uint32_t __isr_vector[];  // NOLINT: linker-script / startup.S symbols
extern std::uint32_t __stack_guard[];
extern std::uint32_t __stack_limit[];
extern std::uint32_t __stack_top[];
extern std::uint32_t __ram_start[];
extern std::uint32_t __ram_end[];
}

namespace {

using kestrel::platform::print;
using kestrel::platform::print_uint;
using kestrel::platform::println;

template <typename T>
T& reg(std::uintptr_t addr) {
  return *reinterpret_cast<T*>(addr);
}
volatile std::uint32_t& reg32(std::uintptr_t addr) { return reg<volatile std::uint32_t>(addr); }

// System control block and MPU (Armv7-M ARM B3.2, B3.5).
constexpr std::uintptr_t kVtor = 0xE000ED08u;
constexpr std::uintptr_t kCcr = 0xE000ED14u;
constexpr std::uintptr_t kShcsr = 0xE000ED24u;
constexpr std::uintptr_t kCfsr = 0xE000ED28u;
constexpr std::uintptr_t kHfsr = 0xE000ED2Cu;
constexpr std::uintptr_t kMmfar = 0xE000ED34u;
constexpr std::uintptr_t kBfar = 0xE000ED38u;
constexpr std::uintptr_t kMpuType = 0xE000ED90u;
constexpr std::uintptr_t kMpuCtrl = 0xE000ED94u;
constexpr std::uintptr_t kMpuRnr = 0xE000ED98u;
constexpr std::uintptr_t kMpuRbar = 0xE000ED9Cu;
constexpr std::uintptr_t kMpuRasr = 0xE000EDA0u;

std::uintptr_t addr(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

void print_reg(const char* name, std::uint32_t v) {
  print(name);
  kestrel::platform::print_hex32(v);
}

}  // namespace

extern "C" void kestrel_cortex_m_early_init(void) {
  reg32(kVtor) = static_cast<std::uint32_t>(addr(__isr_vector));
  // MemManage, BusFault and UsageFault get their own handlers (and names in the report) instead
  // of escalating to HardFault; integer division by zero traps as it does on the host.
  reg32(kShcsr) = reg32(kShcsr) | (1u << 16) | (1u << 17) | (1u << 18);
  reg32(kCcr) = reg32(kCcr) | (1u << 4);  // DIV_0_TRP
  // Stack guard: a 1 KiB no-access region just below the main stack, the rest of the map as the
  // default (PRIVDEFENA). An overflow is a MemManage fault, reported as such.
  if (((reg32(kMpuType) >> 8) & 0xFFu) != 0) {  // DREGION: the MPU exists
    reg32(kMpuRnr) = 0;
    reg32(kMpuRbar) = static_cast<std::uint32_t>(addr(__stack_guard));
    reg32(kMpuRasr) = (1u << 28)    // XN
                      | (0u << 24)  // AP: no access
                      | (9u << 1)   // SIZE: 2^(9+1) = 1 KiB (linker script: __stack_guard)
                      | 1u;         // ENABLE
    reg32(kMpuCtrl) = (1u << 2) | 1u;  // PRIVDEFENA | ENABLE
    asm volatile("dsb\n isb" : : : "memory");
  }
}

extern "C" void kestrel_fault_report(const std::uint32_t* frame, std::uint32_t exc_return, std::uint32_t kind) {
  static const char* const kNames[] = {"HardFault", "MemManage fault", "BusFault", "UsageFault"};
  const std::uint32_t cfsr = reg32(kCfsr);
  const std::uint32_t mmfar = reg32(kMmfar);
  println();
  print("kestrel: ");
  print(kind >= 3 && kind <= 6 ? kNames[kind - 3] : "fault");
  print_reg(" CFSR=", cfsr);
  print_reg(" HFSR=", reg32(kHfsr));
  if ((cfsr & (1u << 7)) != 0) print_reg(" MMFAR=", mmfar);
  if ((cfsr & (1u << 15)) != 0) print_reg(" BFAR=", reg32(kBfar));
  print_reg(" EXC_RETURN=", exc_return);
  println();
  // The stacked frame (r0-r3, r12, lr, pc, xPSR) is only readable if it lies in RAM above the guard.
  const std::uintptr_t f = addr(frame);
  if (f >= addr(__stack_limit) && f + 32 <= addr(__ram_end)) {
    print_reg("kestrel: at pc=", frame[6]);
    print_reg(" lr=", frame[5]);
    print_reg(" xpsr=", frame[7]);
    println(" (arm-none-eabi-addr2line -e <elf> <pc>)");
  }
  const bool mm_stacking = (cfsr & (1u << 4)) != 0;  // MSTKERR
  const bool guard_hit = (cfsr & (1u << 7)) != 0 && mmfar >= addr(__stack_guard) && mmfar < addr(__stack_limit);
  if (mm_stacking || guard_hit || (f < addr(__stack_limit) && f >= addr(__ram_start))) {
    print("kestrel: main stack overflow (");
    print_uint(kestrel::platform::board::stack_size_bytes());
    println(" bytes reserved; raise it with kestrel_add_mcu_executable(... STACK_SIZE n))");
  }
  kestrel::platform::semihost::exit(KESTREL_EXIT_FAULT);
}

extern "C" void kestrel_unexpected_exception(std::uint32_t ipsr) {
  println();
  print("kestrel: unexpected exception ");
  print_uint(ipsr & 0x1FFu);
  if ((ipsr & 0x1FFu) >= 16) {
    print(" (IRQ ");
    print_uint((ipsr & 0x1FFu) - 16);
    print(")");
  }
  println(" without a handler");
  kestrel::platform::semihost::exit(KESTREL_EXIT_UNEXPECTED_IRQ);
}

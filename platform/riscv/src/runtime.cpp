// RISC-V runtime for the Kestrel images: the trap entry (mtvec, direct mode; start.S installs it)
// and the trap report over the semihosting console. Exit, fatal errors, the default assertion
// handler and libstdc++'s error paths are shared with the Cortex-M port
// (platform/mcu/src/runtime_common.cpp).
#include <cstdint>

#include "csr.hpp"
#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"
#include "runtime.h"

extern "C" {
extern std::uint32_t __stack_limit[];  // NOLINT: linker-script symbols
extern std::uint32_t __stack_top[];
}

namespace {

using kestrel::platform::print;
using kestrel::platform::println;

void print_reg(const char* name, std::uint32_t v) {
  print(name);
  kestrel::platform::print_hex32(v);
}

// Synchronous exception causes (RISC-V privileged spec 1.12, table 3.6).
const char* cause_name(std::uint32_t cause) {
  static const char* const kNames[] = {"instruction address misaligned",
                                       "instruction access fault",
                                       "illegal instruction",
                                       "breakpoint",
                                       "load address misaligned",
                                       "load access fault",
                                       "store/AMO address misaligned",
                                       "store/AMO access fault",
                                       "environment call from U-mode",
                                       "environment call from S-mode",
                                       "reserved",
                                       "environment call from M-mode"};
  return cause < sizeof(kNames) / sizeof(kNames[0]) ? kNames[cause] : "exception";
}

[[noreturn]] void trap_report(std::uint32_t mcause, std::uint32_t mepc, std::uint32_t mtval, std::uint32_t sp) {
  println();
  if ((mcause & kestrel::platform::riscv::kMcauseInterrupt) != 0) {
    print("kestrel: unexpected interrupt ");
    kestrel::platform::print_uint(mcause & ~kestrel::platform::riscv::kMcauseInterrupt);
    println(" without a handler");
    kestrel::platform::semihost::exit(KESTREL_EXIT_UNEXPECTED_IRQ);
  }
  print("kestrel: trap: ");
  print(cause_name(mcause));
  print_reg(" mcause=", mcause);
  print_reg(" mepc=", mepc);
  print_reg(" mtval=", mtval);
  println(" (riscv64-unknown-elf-addr2line -e <elf> <mepc>)");
  // No MPU-style guard: a stack pointer below the reserved stack at the trap is an overflow.
  if (sp < reinterpret_cast<std::uintptr_t>(__stack_limit) || sp > reinterpret_cast<std::uintptr_t>(__stack_top)) {
    print("kestrel: main stack overflow (");
    kestrel::platform::print_uint(kestrel::platform::board::stack_size_bytes());
    println(" bytes reserved; raise it with kestrel_add_mcu_executable(... STACK_SIZE n))");
  }
  kestrel::platform::semihost::exit(KESTREL_EXIT_FAULT);
}

}  // namespace

// Every trap of the images: the machine timer interrupt (board.cpp) returns with mret; anything
// else is reported and ends the program. GCC saves the registers the handler and its callees may
// clobber (integer and, with the F extension, FP) and returns with mret. 4-byte aligned: mtvec
// direct mode.
extern "C" __attribute__((interrupt("machine"), aligned(4))) void kestrel_trap_entry() {
  std::uint32_t mcause;
  KESTREL_CSR_READ(mcause, mcause);
  if (mcause == (kestrel::platform::riscv::kMcauseInterrupt | kestrel::platform::riscv::kMcauseMachineTimer)) {
    kestrel::platform::riscv::timer_interrupt();
    return;
  }
  std::uint32_t mepc;
  std::uint32_t mtval;
  std::uint32_t sp;
  KESTREL_CSR_READ(mepc, mepc);
  KESTREL_CSR_READ(mtval, mtval);
  asm volatile("mv %0, sp" : "=r"(sp));
  trap_report(mcause, mepc, mtval, sp);
}

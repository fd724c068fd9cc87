// Probe image for the runtime's failure paths, run by ctests that expect a given QEMU exit status
// and message (platform/cortex-m/CMakeLists.txt). The semihosting command line's first word
// (run-qemu.sh --name) selects what it does:
//   exit42     main returns 42                      -> QEMU exit status 42
//   assert     KESTREL_ASSERT fails                 -> 2, "assertion failed"
//   overflow   unbounded recursion into the guard   -> 3, "main stack overflow"
//   badaddr    load from an unmapped address        -> 3, "BusFault"
//   div0       integer division by zero             -> 3, "UsageFault"
#include <cstdint>
#include <cstring>

#include "kestrel/kernel/assert.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"

// An address nothing answers at: on the MPS2 boards 0x30000000; the RISC-V port passes its own
// (on QEMU's virt board 0x30000000 is PCIe ECAM space, which reads fine).
#ifndef KESTREL_PROBE_BAD_ADDRESS
#define KESTREL_PROBE_BAD_ADDRESS 0x30000000u
#endif

namespace {

volatile std::uint32_t g_sink;

__attribute__((noinline)) std::uint32_t recurse(std::uint32_t depth) {
  volatile std::uint32_t frame[16];  // < the 1 KiB guard, so some store lands in it
  frame[depth % 16] = depth;
  if (g_sink == 0xDEADBEEFu) return 0;  // never: keeps -Winfinite-recursion quiet
  return recurse(depth + 1) + frame[depth % 16];  // not a tail call
}

bool is(const char* cmd, const char* word) {
  const std::size_t n = std::strlen(word);
  return std::strncmp(cmd, word, n) == 0 && (cmd[n] == '\0' || cmd[n] == ' ');
}

}  // namespace

int main() {
  static char cmd[256];
  kestrel::platform::semihost::get_cmdline(cmd, sizeof(cmd));
  kestrel::platform::print("probe: ");
  kestrel::platform::println(cmd);
  if (is(cmd, "exit42")) return 42;
  if (is(cmd, "assert")) {
    KESTREL_ASSERT(g_sink == 12345u);
    return 0;
  }
  if (is(cmd, "overflow")) return static_cast<int>(recurse(0));
  if (is(cmd, "badaddr")) return static_cast<int>(*reinterpret_cast<volatile std::uint32_t*>(KESTREL_PROBE_BAD_ADDRESS));
  if (is(cmd, "div0")) {
    volatile std::uint32_t zero = 0;
    return static_cast<int>(100u / zero);
  }
  kestrel::platform::println("probe: unknown mode");
  return 1;
}

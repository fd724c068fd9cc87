// The RISC-V semihosting trap (kestrel/platform/semihosting.hpp): a0 = op, a1 = arg, result in a0.
// The sequence `slli x0, x0, 0x1f; ebreak; srai x0, x0, 7` must be uncompressed (norvc) and within
// one page (16-byte aligned), as the RISC-V semihosting spec asks; QEMU 7.2 implements it with
// -semihosting-config enable=on,target=native. The parameter blocks are the AArch32 ones (RV32).
#include "kestrel/platform/semihosting.hpp"

namespace kestrel::platform::semihost {

std::int32_t call(std::uint32_t op, const void* arg) {
  // The host reads and writes memory through arg (parameter blocks, buffers): "memory" clobber.
  register std::uint32_t a0 asm("a0") = op;
  register const void* a1 asm("a1") = arg;
  asm volatile(
      ".option push\n"
      ".balign 16\n"
      ".option norvc\n"
      "slli zero, zero, 0x1f\n"
      "ebreak\n"
      "srai zero, zero, 7\n"
      ".option pop"
      : "+r"(a0)
      : "r"(a1)
      : "memory");
  return static_cast<std::int32_t>(a0);
}

}  // namespace kestrel::platform::semihost

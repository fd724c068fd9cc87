// The AArch32 semihosting trap (kestrel/platform/semihosting.hpp): r0 = op, r1 = arg, bkpt 0xAB.
#include "kestrel/platform/semihosting.hpp"

namespace kestrel::platform::semihost {

std::int32_t call(std::uint32_t op, const void* arg) {
  // The host reads and writes memory through arg (parameter blocks, buffers): "memory" clobber.
  std::uint32_t result;
  asm volatile(
      "mov r0, %1\n"
      "mov r1, %2\n"
      "bkpt 0xAB\n"
      "mov %0, r0"
      : "=r"(result)
      : "r"(op), "r"(arg)
      : "r0", "r1", "memory");
  return static_cast<std::int32_t>(result);
}

}  // namespace kestrel::platform::semihost

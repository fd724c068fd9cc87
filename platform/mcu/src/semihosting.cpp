// Semihosting operations (see kestrel/platform/semihosting.hpp), shared by the Cortex-M and RISC-V
// ports: the parameter blocks are the same on AArch32 and RV32; only the trap sequence differs
// (semihost::call, in each port's semihost_call.cpp).
#include "kestrel/platform/semihosting.hpp"

#include <cstring>

#include "kestrel/platform/board.hpp"

namespace kestrel::platform::semihost {

int open(const char* path, Mode mode) {
  const std::uint32_t block[3] = {reinterpret_cast<std::uintptr_t>(path), mode,
                                  static_cast<std::uint32_t>(std::strlen(path))};
  return call(kSysOpen, block);
}

int close(int handle) {
  const std::uint32_t block[1] = {static_cast<std::uint32_t>(handle)};
  return call(kSysClose, block);
}

std::size_t write(int handle, const void* buf, std::size_t n) {
  const std::uint32_t block[3] = {static_cast<std::uint32_t>(handle), reinterpret_cast<std::uintptr_t>(buf),
                                  static_cast<std::uint32_t>(n)};
  return static_cast<std::size_t>(call(kSysWrite, block));
}

long read(int handle, void* buf, std::size_t n) {
  const std::uint32_t block[3] = {static_cast<std::uint32_t>(handle), reinterpret_cast<std::uintptr_t>(buf),
                                  static_cast<std::uint32_t>(n)};
  // SYS_READ returns the number of bytes NOT read: 0 = buffer filled, n = end of file.
  const std::int32_t left = call(kSysRead, block);
  if (left < 0 || static_cast<std::size_t>(left) > n) return -1;
  return static_cast<long>(n - static_cast<std::size_t>(left));
}

void write0(const char* s) { call(kSysWrite0, s); }

int get_cmdline(char* buf, std::size_t cap) {
  if (cap == 0) return -1;
  std::uint32_t block[2] = {reinterpret_cast<std::uintptr_t>(buf), static_cast<std::uint32_t>(cap)};
  if (call(kSysGetCmdline, block) != 0) {
    buf[0] = '\0';
    return -1;
  }
  const std::size_t len = block[1] < cap ? block[1] : cap - 1;
  buf[len] = '\0';
  return static_cast<int>(len);
}

void exit(int code) {
  board::console_flush();
  if (code == 0) {
    // AArch32 SYS_EXIT takes the reason code itself in r1, not a parameter block.
    call(kSysExit, reinterpret_cast<const void*>(static_cast<std::uintptr_t>(kAdpStoppedApplicationExit)));
  } else {
    // The host sees only the low 8 bits of an exit status: keep a failure a failure.
    const std::uint32_t status = (static_cast<std::uint32_t>(code) & 0xFFu) != 0 ? static_cast<std::uint32_t>(code) : 1u;
    const std::uint32_t block[2] = {kAdpStoppedApplicationExit, status};
    call(kSysExitExtended, block);
    call(kSysExit, reinterpret_cast<const void*>(static_cast<std::uintptr_t>(kAdpStoppedRunTimeErrorUnknown)));
  }
  for (;;) {
  }
}

}  // namespace kestrel::platform::semihost

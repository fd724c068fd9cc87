// Console over semihosting: console_write() buffers and hands the host one SYS_WRITE per line
// (or per full buffer), not one trap per character. Output goes to QEMU's stdout (":tt" opened
// for writing); if that cannot be opened, to the semihosting debug console (SYS_WRITE0).
#include <cstring>

#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#include "kestrel/platform/semihosting.hpp"
#include "mcu_arch.hpp"

namespace kestrel::platform {
namespace {

constexpr std::size_t kBufferSize = 256;
char g_buf[kBufferSize + 1];  // + 1 for the NUL SYS_WRITE0 needs
std::size_t g_len = 0;
int g_stdout = -2;  // -2: not opened yet; -1: ":tt" unavailable

// Console output may come from the main program and from interrupts (timer callback, faults):
// interrupts are masked while the buffer changes (arch::irq_save, mcu_arch.hpp of each port).

void flush_locked() {
  if (g_len == 0) return;
  if (g_stdout == -2) g_stdout = semihost::open(":tt", semihost::kModeW);
  if (g_stdout >= 0) {
    semihost::write(g_stdout, g_buf, g_len);
  } else {
    g_buf[g_len] = '\0';
    semihost::write0(g_buf);
  }
  g_len = 0;
}

}  // namespace

void console_write(const char* s, std::size_t n) {
  const std::uint32_t primask = arch::irq_save();
  bool newline = false;
  while (n > 0) {
    if (g_len == kBufferSize) flush_locked();
    std::size_t chunk = kBufferSize - g_len;
    if (chunk > n) chunk = n;
    std::memcpy(g_buf + g_len, s, chunk);
    newline = newline || std::memchr(s, '\n', chunk) != nullptr;
    g_len += chunk;
    s += chunk;
    n -= chunk;
  }
  if (newline) flush_locked();
  arch::irq_restore(primask);
}

namespace board {
void console_flush() {
  const std::uint32_t primask = arch::irq_save();
  flush_locked();
  arch::irq_restore(primask);
}
}  // namespace board

}  // namespace kestrel::platform

// Host port: console on stdout, assertion failures abort with a message.
#include <cstdio>
#include <cstdlib>

#include "kestrel/platform/console.hpp"

namespace kestrel::platform {
void console_write(const char* s, std::size_t n) {
  std::fwrite(s, 1, n, stdout);
  std::fflush(stdout);
}
}  // namespace kestrel::platform

extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  std::fprintf(stderr, "kestrel: assertion failed: %s (%s:%d)\n", expr, file, line);
  std::abort();
}

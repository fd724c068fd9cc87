#include "kestrel/kernel/assert.hpp"

// The platform layer provides the default handler (host: print + abort; MCU: console + halt).
extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line);

namespace kestrel {
namespace {
AssertHandler g_handler = nullptr;
}

AssertHandler set_assert_handler(AssertHandler handler) {
  AssertHandler prev = g_handler;
  g_handler = handler;
  return prev;
}

void assert_failed(const char* expr, const char* file, int line) {
  if (g_handler != nullptr) {
    g_handler(expr, file, line);
    return;
  }
  kestrel_platform_assert_default(expr, file, line);
}

}  // namespace kestrel

// What this firmware provides on bare metal: its own assertion hook (replacing the package's weak
// default, which traps) and newlib crt0's _exit (an empty main needs it too; a real firmware's
// startup code replaces crt0, or --specs=nosys.specs provides a stub). Kestrel needs nothing else.
extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line);
extern "C" void _exit(int status);

namespace {
volatile int g_failsafe = 0;
}

extern "C" void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  g_failsafe = line;  // a real flight stack logs and enters its failsafe here
  for (;;) {
  }
}

extern "C" void _exit(int status) {
  for (;;) {
  }
}

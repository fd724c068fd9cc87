/* The kernel's assertion hook for firmware that uses the installed package (kestrel::assert_default,
 * linked by kestrel::kernel on bare-metal targets; cmake/KestrelInstall.cmake). Kestrel-built
 * images never link it: they have the Cortex-M runtime's handler (runtime.cpp: report, exit).
 *
 * Weak, so a firmware replaces it by defining kestrel_platform_assert_default itself (to log and
 * enter its failsafe) with no link order to respect. The default traps (UDF -> HardFault): the
 * firmware's fault handler sees a broken invariant of the control stack as a fault, instead of the
 * stack going on with a state it no longer trusts. It reads no console and allocates nothing. */
void kestrel_platform_assert_default(const char* expr, const char* file, int line);

__attribute__((weak)) void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  (void)expr;
  (void)file;
  (void)line;
  __builtin_trap();
}

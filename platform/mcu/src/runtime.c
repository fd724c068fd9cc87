/* The C library and C++ ABI hooks a bare-metal image needs when linked with -nostartfiles and
 * without libnosys: each one either does nothing (static destructors are never run: the program
 * ends through semihosting) or reports and exits non-zero. None of them allocates. Kept in C so
 * they can carry the C library's own names and signatures. */
#include "runtime.h"

/* __libc_init_array() calls _init() (normally crti.o) before the .init_array constructors. */
void _init(void) {}
void _fini(void) {}

/* Static objects with destructors register them here; nothing runs them, so nothing is stored
 * (newlib's __register_exitproc could otherwise reach for malloc past its first 32 entries). */
int __cxa_atexit(void (*fn)(void*), void* arg, void* dso) {
  (void)fn;
  (void)arg;
  (void)dso;
  return 0;
}
int __aeabi_atexit(void* arg, void (*fn)(void*), void* dso) {
  (void)fn;
  (void)arg;
  (void)dso;
  return 0;
}
int atexit(void (*fn)(void)) {
  (void)fn;
  return 0;
}

__attribute__((noreturn)) void _exit(int code) { kestrel_mcu_exit(code); }
__attribute__((noreturn)) void exit(int code) { kestrel_mcu_exit(code); }
__attribute__((noreturn)) void abort(void) { kestrel_mcu_fatal("abort()", 0); }

/* newlib's assert() (when NDEBUG is not defined) would fiprintf to stderr: stdio and malloc. */
__attribute__((noreturn)) void __assert_func(const char* file, int line, const char* func, const char* expr) {
  (void)func;
  kestrel_platform_assert_default(expr, file, line);
  for (;;) {
  }
}

__attribute__((noreturn)) void __cxa_pure_virtual(void) { kestrel_mcu_fatal("pure virtual function called", 0); }
__attribute__((noreturn)) void __cxa_deleted_virtual(void) { kestrel_mcu_fatal("deleted virtual function called", 0); }

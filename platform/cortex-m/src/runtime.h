/* Shared between the C and C++ parts of the Cortex-M runtime (runtime.c, runtime.cpp). */
#ifndef KESTREL_CORTEX_M_RUNTIME_H
#define KESTREL_CORTEX_M_RUNTIME_H

/* Exit codes of the MCU images (QEMU's exit status). 1 is left to main(): the ktest runner
 * returns 1 when a test failed. */
#define KESTREL_EXIT_FATAL 2           /* assertion, abort(), pure virtual call, std::__throw_* */
#define KESTREL_EXIT_FAULT 3           /* HardFault, MemManage (incl. stack overflow), BusFault, UsageFault */
#define KESTREL_EXIT_UNEXPECTED_IRQ 4  /* an exception or interrupt without a handler */

#ifdef __cplusplus
extern "C" {
#endif
/* Prints "kestrel: fatal: what: detail" and exits with KESTREL_EXIT_FATAL. */
__attribute__((noreturn)) void kestrel_cortex_m_fatal(const char* what, const char* detail);
__attribute__((noreturn)) void kestrel_cortex_m_exit(int code);
/* The platform's default KESTREL_ASSERT handler: prints and exits with KESTREL_EXIT_FATAL. */
void kestrel_platform_assert_default(const char* expr, const char* file, int line);
#ifdef __cplusplus
}
#endif

#endif

/* Shared between the C and C++ parts of the MCU runtimes (platform/mcu/src: runtime.c,
 * runtime_common.cpp; the ports' runtime.cpp and board.cpp). */
#ifndef KESTREL_MCU_RUNTIME_H
#define KESTREL_MCU_RUNTIME_H

/* Exit codes of the MCU images (QEMU's exit status). 1 is left to main(): the ktest runner
 * returns 1 when a test failed. */
#define KESTREL_EXIT_FATAL 2           /* assertion, abort(), pure virtual call, std::__throw_* */
#define KESTREL_EXIT_FAULT 3           /* Cortex-M: HardFault, MemManage (incl. stack overflow), BusFault, UsageFault; RISC-V: a trap */
#define KESTREL_EXIT_UNEXPECTED_IRQ 4  /* an exception or interrupt without a handler */

#ifdef __cplusplus
extern "C" {
#endif
/* Prints "kestrel: fatal: what: detail" and exits with KESTREL_EXIT_FATAL. */
__attribute__((noreturn)) void kestrel_mcu_fatal(const char* what, const char* detail);
__attribute__((noreturn)) void kestrel_mcu_exit(int code);
/* The platform's default KESTREL_ASSERT handler: prints and exits with KESTREL_EXIT_FATAL. */
void kestrel_platform_assert_default(const char* expr, const char* file, int line);
#ifdef __cplusplus
}
#endif

#endif

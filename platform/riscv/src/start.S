/* RV32 (rv32imac / rv32imafc) start-up for QEMU's virt board, M-mode, -bios none: hart 0 starts
 * at 0x80000000 (_start, the first thing in .text: ld/virt.ld). Written in assembly so nothing
 * runs before gp, sp, tp and the FPU are set. The C++ side is in runtime.cpp (trap report) and
 * board.cpp (timer); exit and the stack measurement are shared with the Cortex-M port
 * (platform/mcu/src/runtime_common.cpp). Symbols from ld/virt.ld:
 *   __stack_top, __stack_limit            main stack (grows down towards __stack_limit)
 *   __data_start/__data_end/__data_load   .data (+ .sdata, .tdata) in RAM and its load image
 *   __bss_start/__bss_end                 zero-initialised data (.tbss, .sbss, .bss)
 *   __tls_base                            the static TLS block (picolibc's errno)
 * The CSR instructions need Zicsr; it is enabled here with .option arch, not with -march, because
 * -march=rv32imac_zicsr would match no multilib of Debian's GCC 12 and the link would silently take
 * the rv64 libgcc and picolibc.
 */
    .equ KESTREL_STACK_PAINT, 0x5AC3C35A   /* stack high-water mark (board::stack_used_bytes) */

    .section .text.start, "ax", @progbits
    .option arch, +zicsr
    .globl _start
    .type _start, @function
_start:
    .option push
    .option norelax
    la    gp, __global_pointer$
    .option pop
    la    sp, __stack_top
    la    tp, __tls_base
    csrw  mie, zero                 /* no interrupt source until board code enables one */
    la    t0, kestrel_trap_entry    /* runtime.cpp; direct mode (4-byte aligned) */
    csrw  mtvec, t0
#ifdef __riscv_flen
    li    t0, (1 << 13)             /* mstatus.FS = Initial: FP instructions trap until this is set */
    csrs  mstatus, t0
    csrwi fcsr, 0                   /* round to nearest, no flags */
#endif
    /* .data (with .sdata and .tdata): copy the initial values from the load image. */
    la    a0, __data_start
    la    a1, __data_end
    la    a2, __data_load
1:  bgeu  a0, a1, 2f
    lw    t0, 0(a2)
    sw    t0, 0(a0)
    addi  a0, a0, 4
    addi  a2, a2, 4
    j     1b
2:  /* .tbss, .sbss, .bss: zero. */
    la    a0, __bss_start
    la    a1, __bss_end
3:  bgeu  a0, a1, 4f
    sw    zero, 0(a0)
    addi  a0, a0, 4
    j     3b
4:  /* Paint the stack (nothing has been pushed yet) so its high-water mark can be measured. */
    la    a0, __stack_limit
    li    t0, KESTREL_STACK_PAINT
5:  bgeu  a0, sp, 6f
    sw    t0, 0(a0)
    addi  a0, a0, 4
    j     5b
6:  /* Static constructors. */
    la    s0, __init_array_start
    la    s1, __init_array_end
7:  bgeu  s0, s1, 8f
    lw    t0, 0(s0)
    jalr  t0
    addi  s0, s0, 4
    j     7b
8:  li    a0, 0
    li    a1, 0
    call  main
    call  kestrel_mcu_exit          /* noreturn: semihosting SYS_EXIT with main's result */
9:  j     9b
    .size _start, . - _start

/* The C++ ABI's handle for this "shared object" (static destructors register against it; they
 * never run here, see __cxa_atexit in platform/mcu/src/runtime.c). Normally from crtbegin.o. */
    .section .sdata.__dso_handle, "aw", @progbits
    .align 2
    .globl __dso_handle
    .hidden __dso_handle
__dso_handle:
    .word 0

/* Cortex-M3/M4/M7 startup for the Arm MPS2 boards and the STM32F405 (netduinoplus2): vector table,
 * reset handler, fault entry.
 *
 * Written in assembly so that nothing runs before the FPU is enabled (with -mfloat-abi=hard the
 * compiler may use FP registers in any C++ function, even a copy loop) and so the vector table is a
 * plain link-time constant. The C++ side is in runtime.cpp (fault report, exit) and board.cpp
 * (SysTick). Symbols from the linker script (ld/cortex-m-sections.ld):
 *   __stack_top, __stack_limit        main stack (grows down towards __stack_limit)
 *   __data_start/__data_end/__data_load   .data in RAM and its load image in flash
 *   __bss_start/__bss_end             zero-initialised data
 */
    .syntax unified
    .thumb

    .equ KESTREL_STACK_PAINT, 0x5AC3C35A   /* stack high-water mark (board::stack_used_bytes) */

/* ---------------------------------------------------------------------------------------------
 * Vector table: 16 system exceptions + 32 external interrupts (QEMU's MPS2 NVIC has num-irq 32;
 * the STM32F405 has more, none of which the images enable).
 */
    .section .isr_vector,"a",%progbits
    .align 2
    .global __isr_vector
__isr_vector:
    .word __stack_top
    .word Reset_Handler
    .word NMI_Handler
    .word HardFault_Handler
    .word MemManage_Handler
    .word BusFault_Handler
    .word UsageFault_Handler
    .word 0, 0, 0, 0
    .word SVC_Handler
    .word DebugMon_Handler
    .word 0
    .word PendSV_Handler
    .word SysTick_Handler
    .rept 32
    .word Default_Handler
    .endr
    .size __isr_vector, . - __isr_vector

/* ---------------------------------------------------------------------------------------------
 * Reset: FPU on, .data copied, .bss zeroed, stack painted, MPU stack guard, static constructors,
 * main(), then exit through semihosting with main's return code.
 */
    .section .text.Reset_Handler,"ax",%progbits
    .global Reset_Handler
    .type Reset_Handler, %function
    .thumb_func
Reset_Handler:
    ldr   r0, =__stack_top
    msr   msp, r0
#if defined(__ARM_FP)
    /* CPACR (0xE000ED88): full access to CP10 and CP11 before any FP instruction. */
    ldr   r0, =0xE000ED88
    ldr   r1, [r0]
    orr   r1, r1, #(0xF << 20)
    str   r1, [r0]
    dsb
    isb
#endif
    /* .data: copy its initial values from flash to RAM. */
    ldr   r0, =__data_start
    ldr   r1, =__data_end
    ldr   r2, =__data_load
1:  cmp   r0, r1
    bhs   2f
    ldr   r3, [r2], #4
    str   r3, [r0], #4
    b     1b
2:  /* .bss: zero. */
    ldr   r0, =__bss_start
    ldr   r1, =__bss_end
    movs  r3, #0
3:  cmp   r0, r1
    bhs   4f
    str   r3, [r0], #4
    b     3b
4:  /* Paint the stack (nothing has been pushed yet) so its high-water mark can be measured. */
    ldr   r0, =__stack_limit
    mov   r1, sp
    ldr   r3, =KESTREL_STACK_PAINT
5:  cmp   r0, r1
    bhs   6f
    str   r3, [r0], #4
    b     5b
6:  bl    kestrel_cortex_m_early_init
    bl    __libc_init_array
    bl    main
    bl    kestrel_mcu_exit      /* noreturn: semihosting SYS_EXIT with main's result */
7:  b     7b
    .pool
    .size Reset_Handler, . - Reset_Handler

/* ---------------------------------------------------------------------------------------------
 * Faults: switch to a private stack first (the main stack may be what overflowed into the MPU
 * guard), then report through semihosting and exit non-zero: kestrel_fault_report(frame,
 * exc_return, kind) in runtime.cpp. kind: 3 HardFault, 4 MemManage, 5 BusFault, 6 UsageFault
 * (the exception numbers).
 */
    .section .text.kestrel_fault_entry,"ax",%progbits
    .macro FAULT_ENTRY name, kind
    .global \name
    .type \name, %function
    .thumb_func
\name:
    movs  r2, #\kind
    b     kestrel_fault_common
    .size \name, . - \name
    .endm

    FAULT_ENTRY HardFault_Handler, 3
    FAULT_ENTRY MemManage_Handler, 4
    FAULT_ENTRY BusFault_Handler, 5
    FAULT_ENTRY UsageFault_Handler, 6

    .type kestrel_fault_common, %function
    .thumb_func
kestrel_fault_common:
    tst   lr, #4
    ite   eq
    mrseq r0, msp
    mrsne r0, psp
    mov   r1, lr
    ldr   r3, =kestrel_fault_stack_top
    mov   sp, r3
    bl    kestrel_fault_report
8:  b     8b
    .pool
    .size kestrel_fault_common, . - kestrel_fault_common

/* Any other exception or interrupt without a handler: reports its number (IPSR) and exits. */
    .section .text.Default_Handler,"ax",%progbits
    .global Default_Handler
    .type Default_Handler, %function
    .thumb_func
Default_Handler:
    mrs   r0, ipsr
    bl    kestrel_unexpected_exception
9:  b     9b
    .size Default_Handler, . - Default_Handler

    .macro WEAK_DEFAULT name
    .weak \name
    .thumb_set \name, Default_Handler
    .endm
    WEAK_DEFAULT NMI_Handler
    WEAK_DEFAULT SVC_Handler
    WEAK_DEFAULT DebugMon_Handler
    WEAK_DEFAULT PendSV_Handler
    WEAK_DEFAULT SysTick_Handler

    .section .bss.kestrel_fault_stack,"aw",%nobits
    .align 3
kestrel_fault_stack:
    .space 1024
kestrel_fault_stack_top:

/* The C++ ABI's handle for this "shared object" (static destructors register against it; they
 * never run here, see __cxa_atexit in runtime.cpp). Normally from crtbegin.o (-nostartfiles). */
    .section .rodata.__dso_handle,"a",%progbits
    .align 2
    .global __dso_handle
    .hidden __dso_handle
__dso_handle:
    .word 0

    .section .note.GNU-stack,"",%progbits

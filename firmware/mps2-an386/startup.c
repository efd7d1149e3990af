/* startup.c - vector table, reset handler, SysTick instruction counter and
 * semihosting calls of QEMU's mps2-an386 (Cortex-M4F), shared by every gearsim
 * target program (docs/firmware.md; services declared in board.h).
 *
 * Reset: enable the FPU (CP10/CP11 full access in CPACR, dsb/isb so that the
 * next instruction sees it), copy .data from its load address and clear .bss
 * (mps2_an386.ld), then either
 *  - newlib's _start (BOARD_NEWLIB_START: C runtime set-up, semihosting stdio;
 *    main's return value ends QEMU through exit), or
 *  - main directly, for programs that must not pull in a C runtime (the size
 *    probes, the M4 benchmark); its return value ends QEMU through board_exit.
 * A fault also ends QEMU through board_exit, with exit status 1. */
#include <stdint.h>

#include "board.h"

#define CPACR    (*(volatile uint32_t *)0xE000ED88U)
#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

/* Semihosting operations and SYS_EXIT reasons (ARM semihosting 2.0). */
#define SEMIHOST_SYS_WRITE0       0x04U
#define SEMIHOST_SYS_EXIT         0x18U
#define SEMIHOST_APPLICATION_EXIT 0x20026U /* ADP_Stopped_ApplicationExit: status 0 */
#define SEMIHOST_RUNTIME_ERROR    0x20023U /* ADP_Stopped_RunTimeErrorUnknown: status 1 */

/* mps2_an386.ld */
extern uint32_t __stack_top;
extern uint32_t __data_load__, __data_start__, __data_end__;
extern uint32_t __bss_start__, __bss_end__;

int main(void);
#ifdef BOARD_NEWLIB_START
void _start(void); /* newlib crt0 (rdimon-crt0.o with --specs=rdimon.specs) */
#endif

void Reset_Handler(void);
void Default_Handler(void);
void SysTick_Handler(void);

void Reset_Handler(void)
{
    CPACR |= (0xFU << 20); /* CP10, CP11: full access */
    __asm volatile("dsb\n\tisb" ::: "memory");
    const uint32_t *src = &__data_load__;
    for (uint32_t *dst = &__data_start__; dst < &__data_end__;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = &__bss_start__; dst < &__bss_end__;) {
        *dst++ = 0U;
    }
#ifdef BOARD_NEWLIB_START
    _start();
    for (;;) {}
#else
    board_exit(main());
#endif
}

/* Faults end the run with a failure status rather than hanging QEMU. */
void Default_Handler(void)
{
    board_exit(1);
}

static volatile uint32_t systick_wraps;

void SysTick_Handler(void)
{
    systick_wraps = systick_wraps + 1U;
}

typedef void (*board_vector)(void);

/* Cortex-M vector table: initial SP, then the 15 system exceptions. */
__attribute__((section(".vectors"), used)) const board_vector board_vector_table[16] = {
    (board_vector)(uintptr_t)&__stack_top,
    Reset_Handler,
    Default_Handler, /* NMI */
    Default_Handler, /* HardFault */
    Default_Handler, /* MemManage */
    Default_Handler, /* BusFault */
    Default_Handler, /* UsageFault */
    0,               /* reserved */
    0,               /* reserved */
    0,               /* reserved */
    0,               /* reserved */
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMonitor */
    0,               /* reserved */
    Default_Handler, /* PendSV */
    SysTick_Handler,
};

void board_counter_start(void)
{
    systick_wraps = 0U;
    SYST_RVR = 0x00FFFFFFU;
    SYST_CVR = 0U;
    SYST_CSR = 0x7U; /* core clock, interrupt on wrap, enable */
    /* The cleared counter reads 0 until it loads the reload value on the
     * first tick; board_instructions would take that 0 for a whole period. */
    while (SYST_CVR == 0U) {}
}

uint64_t board_instructions(void)
{
    uint32_t wraps;
    uint32_t value;
    do {
        wraps = systick_wraps;
        value = SYST_CVR;
    } while (wraps != systick_wraps);
    const uint64_t ticks = ((uint64_t)wraps << 24) + (uint64_t)(0x00FFFFFFU - value);
    return ticks * BOARD_INSN_PER_TICK;
}

uint64_t board_calibrate(uint32_t n)
{
    const uint64_t t0 = board_instructions();
    __asm volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
    return board_instructions() - t0;
}

void board_write0(const char *s)
{
    register uint32_t r0 __asm__("r0") = SEMIHOST_SYS_WRITE0;
    register const char *r1 __asm__("r1") = s;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
}

void board_exit(int code)
{
    register uint32_t r0 __asm__("r0") = SEMIHOST_SYS_EXIT;
    register uint32_t r1 __asm__("r1") = code == 0 ? SEMIHOST_APPLICATION_EXIT : SEMIHOST_RUNTIME_ERROR;
    __asm__ volatile("bkpt 0xab" : : "r"(r0), "r"(r1) : "memory");
    for (;;) {}
}

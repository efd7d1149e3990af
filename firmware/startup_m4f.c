/* startup_m4f.c - vector table, reset handler and SysTick for the Cortex-M4F
 * test programs (QEMU mps2-an386; docs in docs/firmware.md).
 *
 * Reset: enable the FPU (CP10/CP11 full access in CPACR), dsb/isb, then
 * either newlib's _start (FW_NEWLIB_START: C runtime set-up, semihosting
 * stdio, main's return value ends QEMU) or main directly (the size-probe
 * programs, which must not pull in any C runtime). */
#include <stdint.h>

#include "platform.h"

#define CPACR (*(volatile uint32_t *)0xE000ED88U)
#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

extern uint32_t __stack_top;  /* linker script: top of RAM */
int main(void);
#ifdef FW_NEWLIB_START
void _start(void);  /* newlib crt0 (rdimon-crt0.o with --specs=rdimon.specs) */
#endif

void Reset_Handler(void);
void Default_Handler(void);
void SysTick_Handler(void);

void Reset_Handler(void)
{
    CPACR |= (0xFU << 20);  /* CP10, CP11: full access */
    __asm volatile("dsb\n\tisb" ::: "memory");
#ifdef FW_NEWLIB_START
    _start();
#else
    (void)main();
#endif
    for (;;) {
    }
}

/* Faults end up here and hang: the test wraps QEMU in `timeout`. */
void Default_Handler(void)
{
    for (;;) {
    }
}

static volatile uint32_t systick_wraps;

void SysTick_Handler(void)
{
    systick_wraps = systick_wraps + 1U;
}

typedef void (*fw_vector)(void);

/* Cortex-M vector table: initial SP, then the 15 system exceptions. */
__attribute__((section(".vectors"), used)) const fw_vector fw_vector_table[16] = {
    (fw_vector)(uintptr_t)&__stack_top,
    Reset_Handler,
    Default_Handler, /* NMI */
    Default_Handler, /* HardFault */
    Default_Handler, /* MemManage */
    Default_Handler, /* BusFault */
    Default_Handler, /* UsageFault */
    0, 0, 0, 0,
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMonitor */
    0,
    Default_Handler, /* PendSV */
    SysTick_Handler,
};

void fw_platform_init(void)
{
    systick_wraps = 0U;
    SYST_RVR = 0x00FFFFFFU;
    SYST_CVR = 0U;
    SYST_CSR = 0x7U;  /* core clock, interrupt on wrap, enable */
}

uint64_t fw_instructions(void)
{
    uint32_t wraps;
    uint32_t value;
    do {
        wraps = systick_wraps;
        value = SYST_CVR;
    } while (wraps != systick_wraps);
    const uint64_t ticks = ((uint64_t)wraps << 24) + (uint64_t)(0x00FFFFFFU - value);
    return ticks * FW_INSN_PER_TICK;
}

uint64_t fw_calibrate(uint32_t n)
{
    const uint64_t t0 = fw_instructions();
    __asm volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
    return fw_instructions() - t0;
}

/* m4_bench.c - instructions per rig step on a Cortex-M4F (gearsim float
 * build), run under QEMU mps2-an386 with -icount shift=0.
 *
 * With -icount shift=0 QEMU's virtual clock advances exactly 1 ns per guest
 * instruction, so the SysTick counter (clocked from that virtual clock) counts
 * instructions in fixed units. The program calibrates the unit on a loop of
 * known length, then, for every configuration of bench_common.h, sets the rig
 * up and times BENCH_M4_STEPS calls of gs_rig_step (the same loop as the host
 * benchmark: input indexing plus one addition). It prints one line per
 * configuration through semihosting:
 *     <name> <steps> <instructions>
 * and exits. These are instructions, not cycles: QEMU does not model the
 * Cortex-M4 pipeline (a float divide is 14 cycles, a load 2, a taken branch
 * 2-4). bench/m4_bench.py builds, runs and reads this. */
#include <stdint.h>

#include "../bench_common.h"

#ifndef BENCH_M4_STEPS
#define BENCH_M4_STEPS 8000
#endif

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_MASK 0x00FFFFFFu

void bench_exit(int code);
void *memset(void *dst, int c, size_t n);
void *memcpy(void *dst, const void *src, size_t n);

volatile float g_sink;
static gs_rig_input g_inputs[BENCH_PERIOD];
static gs_rig_consts g_consts;
static gs_rig_state g_state;

/* The library's struct copies and clears; byte loops keep the image free of libc. */
void *memset(void *dst, int c, size_t n)
{
    unsigned char *d = dst;
    while (n--) {
        *d++ = (unsigned char)c;
    }
    return dst;
}

void *memcpy(void *dst, const void *src, size_t n)
{
    unsigned char *d = dst;
    const unsigned char *s = src;
    while (n--) {
        *d++ = *s++;
    }
    return dst;
}

/* Semihosting SYS_WRITE0: a NUL-terminated string to the host's stdout. */
static void put_string(const char *s)
{
    register uint32_t r0 __asm__("r0") = 0x04u;
    register const char *r1 __asm__("r1") = s;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
}

static char *append_u32(char *p, uint32_t v)
{
    char digits[10];
    int n = 0;
    do {
        digits[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    while (n > 0) {
        *p++ = digits[--n];
    }
    return p;
}

static char *append_string(char *p, const char *s)
{
    while (*s) {
        *p++ = *s++;
    }
    return p;
}

static void print_line(const char *name, uint32_t a, uint32_t b)
{
    char line[96];
    char *p = append_string(line, name);
    *p++ = ' ';
    p = append_u32(p, a);
    *p++ = ' ';
    p = append_u32(p, b);
    *p++ = '\n';
    *p = '\0';
    put_string(line);
}

static uint32_t ticks_since(uint32_t start)
{
    return (start - SYST_CVR) & SYST_MASK;
}

/* 2*n + a few instructions: subs + bne per iteration. */
static void known_loop(uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

int main(void)
{
    SYST_RVR = SYST_MASK;
    SYST_CVR = 0u;
    SYST_CSR = 0x5u; /* enable, processor clock, no interrupt */

    /* calibration: ticks of 2e6 more instructions */
    uint32_t t0 = SYST_CVR;
    known_loop(1000u);
    const uint32_t short_ticks = ticks_since(t0);
    t0 = SYST_CVR;
    known_loop(1001000u);
    const uint32_t long_ticks = ticks_since(t0);
    print_line("calibration_ticks_per_2000000_instructions", long_ticks - short_ticks, 0u);

    for (size_t c = 0; c < N_CONFIGS; ++c) {
        gs_error err;
        if (bench_setup(&CONFIGS[c], &g_consts, &g_state, g_inputs, &err) != GS_OK) {
            return 1;
        }
        gs_rig_output out;
        float acc = 0.0f;
        uint32_t k = 0;
        const uint32_t start = SYST_CVR;
        for (uint32_t i = 0; i < BENCH_M4_STEPS; ++i) {
            gs_rig_step(&g_consts, &g_state, &g_inputs[k], &out);
            acc += out.base_torque;
            if (++k == BENCH_PERIOD) {
                k = 0;
            }
        }
        const uint32_t ticks = ticks_since(start);
        g_sink = acc;
        print_line(CONFIGS[c].name, BENCH_M4_STEPS, ticks);
    }
    return 0;
}

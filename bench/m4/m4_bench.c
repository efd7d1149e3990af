/* m4_bench.c - instructions per rig step on a Cortex-M4F (gearsim float
 * build), run under QEMU mps2-an386 with -icount shift=0.
 *
 * With -icount shift=0 QEMU's virtual clock advances exactly 1 ns per guest
 * instruction, so the SysTick counter (clocked from that virtual clock) counts
 * instructions in fixed units (the board's counter, firmware/mps2-an386/
 * board.h). The program calibrates the unit on a loop of known length, then,
 * for every configuration of bench_common.h, sets the rig up and times
 * BENCH_M4_STEPS calls of gs_rig_step (the same loop as the host benchmark:
 * input indexing plus one addition). It prints one line per configuration
 * through semihosting:
 *     <name> <steps> <SysTick ticks>
 * and returns, which ends QEMU (the board's start-up). These are
 * instructions, not cycles: QEMU does not model the Cortex-M4 pipeline (a
 * float divide is 14 cycles, a load 2, a taken branch 2-4).
 * bench/m4_bench.py builds, runs and reads this. */
#include <stdint.h>

#include "../bench_common.h"
#include "board.h"

#ifndef BENCH_M4_STEPS
#define BENCH_M4_STEPS 8000
#endif

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
    board_write0(line);
}

/* The SysTick ticks of an instruction count of the board's counter (a whole
 * number of ticks; a run here is far below 2^32 instructions). */
static uint32_t ticks_of(uint64_t instructions)
{
    return (uint32_t)instructions / BOARD_INSN_PER_TICK;
}

/* Ticks of a loop of 2*n instructions (2*n a multiple of BOARD_INSN_PER_TICK):
 * the fewest of a few readings. A reading is one tick more when the loop
 * starts late enough in a tick for the counter read to cross a tick edge;
 * the start moves between readings, so the fewest does not depend on it, and
 * two loops measured so differ by exactly their difference in length. */
static uint32_t loop_ticks(uint32_t n)
{
    uint64_t fewest = board_calibrate(n);
    for (int i = 1; i < 8; ++i) {
        const uint64_t counted = board_calibrate(n);
        if (counted < fewest) {
            fewest = counted;
        }
    }
    return ticks_of(fewest);
}

int main(void)
{
    board_counter_start();

    /* calibration: ticks of 2e6 more instructions (subs + bne per iteration) */
    print_line("calibration_ticks_per_2000000_instructions", loop_ticks(1001000u) - loop_ticks(1000u), 0u);

    for (size_t c = 0; c < N_CONFIGS; ++c) {
        gs_error err;
        if (bench_setup(&CONFIGS[c], &g_consts, &g_state, g_inputs, &err) != GS_OK) {
            return 1;
        }
        gs_rig_output out;
        float acc = 0.0f;
        uint32_t k = 0;
        const uint64_t start = board_instructions();
        for (uint32_t i = 0; i < BENCH_M4_STEPS; ++i) {
            gs_rig_step(&g_consts, &g_state, &g_inputs[k], &out);
            acc += out.base_torque;
            if (++k == BENCH_PERIOD) {
                k = 0;
            }
        }
        const uint32_t ticks = ticks_of(board_instructions() - start);
        g_sink = acc;
        print_line(CONFIGS[c].name, BENCH_M4_STEPS, ticks);
    }
    return 0;
}

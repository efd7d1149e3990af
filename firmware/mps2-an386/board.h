/* board.h - the services QEMU's mps2-an386 (Cortex-M4F) gives the gearsim
 * target programs, implemented in startup.c: an instruction counter and the
 * two ARM semihosting calls a program without a C runtime needs.
 *
 * Instruction counts come from SysTick on the core clock: under QEMU with
 * -icount shift=0 one instruction advances virtual time by 1 ns, so ticks of
 * the 25 MHz core clock count 40 instructions each. Semihosting needs QEMU's
 * -semihosting (or -semihosting-config enable=on). */
#ifndef GEARSIM_BOARD_H
#define GEARSIM_BOARD_H

#include <stdint.h>

/* Starts SysTick (core clock, 24-bit reload, wrap interrupt). */
void board_counter_start(void);
/* Instructions executed since board_counter_start (QEMU -icount shift=0; a
 * resolution of BOARD_INSN_PER_TICK instructions). */
uint64_t board_instructions(void);
/* Counts a loop of exactly 2*n instructions (subs + bne) with board_instructions(). */
uint64_t board_calibrate(uint32_t n);

#define BOARD_INSN_PER_TICK 40U

/* Semihosting SYS_WRITE0: a NUL-terminated string to QEMU's console. */
void board_write0(const char *s);
/* Semihosting SYS_EXIT: ends QEMU, with exit status 0 when code is 0 and 1
 * otherwise. Does not return. */
__attribute__((noreturn)) void board_exit(int code);

#endif /* GEARSIM_BOARD_H */

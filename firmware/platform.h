/* platform.h - the few target services the Cortex-M4F test program uses
 * (startup_m4f.c). Instruction counts come from SysTick on the core clock:
 * under QEMU with -icount shift=0 one instruction advances virtual time by
 * 1 ns, so ticks of the 25 MHz core clock count 40 instructions each. */
#ifndef GEARSIM_FW_PLATFORM_H
#define GEARSIM_FW_PLATFORM_H

#include <stdint.h>

/* Starts SysTick (core clock, 24-bit reload, wrap interrupt). */
void fw_platform_init(void);
/* Instructions executed since fw_platform_init (QEMU -icount shift=0; a
 * resolution of FW_INSN_PER_TICK instructions). */
uint64_t fw_instructions(void);
/* Counts a loop of exactly 2*n instructions (subs + bne) with fw_instructions(). */
uint64_t fw_calibrate(uint32_t n);

#define FW_INSN_PER_TICK 40U

#endif /* GEARSIM_FW_PLATFORM_H */

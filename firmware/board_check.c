/* board_check.c - the board's start-up for programs without a C runtime
 * (firmware/mps2-an386/startup.c, as the M4 benchmark uses it), one variant
 * per program; scripts/firmware_check.sh runs each under QEMU:
 *   BOARD_CHECK_RETURN  .data holds its initial value (QEMU loads it behind
 *                       the code, the start-up copies it), .bss reads zero,
 *                       the counter read right after its start counts a loop
 *                       of 200 000 instructions to within a tick at each end;
 *                       prints "board: ok" and returns 0: QEMU exits 0;
 *   BOARD_CHECK_FAIL    main returns 3: QEMU exits 1;
 *   BOARD_CHECK_FAULT   an undefined instruction: the fault handler ends QEMU
 *                       with exit status 1 (not a hang until the timeout). */
#include <stdint.h>

#include "board.h"

int main(void);

#if defined(BOARD_CHECK_RETURN)
static volatile uint32_t data_word = 0x5EED1234U;
static volatile uint32_t bss_word;

int main(void)
{
    board_counter_start();
    const uint64_t counted = board_calibrate(100000U);
    int failures = 0;
    if (data_word != 0x5EED1234U) {
        board_write0("board: .data does not hold its initial value\n");
        ++failures;
    }
    if (bss_word != 0U) {
        board_write0("board: .bss is not zero\n");
        ++failures;
    }
    if (counted < 200000U - 2U * BOARD_INSN_PER_TICK || counted > 200000U + 2U * BOARD_INSN_PER_TICK) {
        board_write0("board: the counter is off for a loop of 200000 instructions\n");
        ++failures;
    }
    if (failures == 0) {
        board_write0("board: ok\n");
    }
    return failures;
}
#elif defined(BOARD_CHECK_FAIL)
int main(void)
{
    return 3;
}
#elif defined(BOARD_CHECK_FAULT)
int main(void)
{
    __asm volatile("udf #0");
    board_write0("board: still running after the fault\n");
    return 0;
}
#else
#error "define one BOARD_CHECK_*"
#endif

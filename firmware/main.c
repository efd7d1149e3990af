/* main.c - runs the scripted scenarios and prints every output of every step
 * as IEEE-754 bit patterns (hex), one line per step, plus a hash per scenario.
 *
 * The same file builds the Cortex-M4F program (FW_TARGET defined; run under
 * QEMU mps2-an386, output through semihosting) and the host program (host
 * float build); scripts/firmware_check.sh compares the two outputs. Lines
 * starting with '#' are informational (struct sizes, the column names, the
 * instruction counts on the target) and are not compared. */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "gearsim/gearsim.h"
#include "scenarios.h"

#ifdef FW_TARGET
#include "board.h" /* mps2-an386/: the instruction counter */
#endif

#ifdef GS_SINGLE_PRECISION
typedef uint32_t real_bits;
#define BITS_FMT  "%08" PRIx32
#define PRECISION "float"
#else
typedef uint64_t real_bits;
#define BITS_FMT  "%016" PRIx64
#define PRECISION "double"
#endif

static real_bits bits_of(gs_real x)
{
    real_bits b;
    memcpy(&b, &x, sizeof b);
    return b;
}

/* FNV-1a, 64 bit, over the bit patterns of every output. */
static uint64_t hash_real(uint64_t h, gs_real x)
{
    const real_bits b = bits_of(x);
    for (unsigned i = 0; i < sizeof b; ++i) {
        h ^= (uint64_t)((b >> (8U * i)) & 0xFFU);
        h *= UINT64_C(0x100000001b3);
    }
    return h;
}

/* The outputs of a step in the order of gearsim/fields.h (GS_RIG_OUTPUT_LIST),
 * which is the column order of the step lines. */
static void output_fields(const gs_rig_output *o, gs_real v[GS_RIG_OUTPUT_FIELDS])
{
    int i = 0;
#define FW_OUTPUT_VALUE_(type, name, gear_unit, rack_unit, doc) v[i++] = o->name;
    GS_RIG_OUTPUT_LIST(FW_OUTPUT_VALUE_)
#undef FW_OUTPUT_VALUE_
}

/* The column names of the step lines, from the same list. */
static void print_columns(void)
{
    printf("# columns step");
#define FW_OUTPUT_NAME_(type, name, gear_unit, rack_unit, doc) printf(" %s", #name);
    GS_RIG_OUTPUT_LIST(FW_OUTPUT_NAME_)
#undef FW_OUTPUT_NAME_
    printf("\n");
}

#ifdef FW_TARGET
/* Instructions per step: the scenario stepped once without printing, minus a
 * pass that only builds the inputs. */
static void report_cost(const fw_scenario *s, const gs_rig_consts *consts, gs_rig_state *state)
{
    gs_rig_input in;
    gs_rig_output out;
    gs_rig_info info;
    gs_rig_get_info(consts, &info);
    gs_rig_reset(consts, state);
    const uint64_t t0 = board_instructions();
    for (int k = 0; k < s->steps; ++k) {
        s->input(k, &in);
        gs_rig_step(consts, state, &in, &out);
    }
    const uint64_t t1 = board_instructions();
    for (int k = 0; k < s->steps; ++k) {
        s->input(k, &in);
        __asm volatile("" : : "r"(&in) : "memory");
    }
    const uint64_t t2 = board_instructions();
    const uint64_t step_total = (t1 - t0) - (t2 - t1);
    printf("# cost %s %" PRIu32 " instructions/step (QEMU -icount, %d steps, %d contact sub-steps)\n", s->name,
           (uint32_t)(step_total / (uint64_t)s->steps), s->steps,
           info.contact_h_omega_n > GS_R(0.0) ? info.contact_substeps : 0); /* h*omega_n > 0: backlash */
    gs_rig_reset(consts, state);
}
#endif

static int run(const fw_scenario *s)
{
    gs_rig_consts consts; /* filled by init, read-only afterwards */
    gs_rig_state state;   /* what a step updates */
    gs_error err;
    const gs_status st = s->init(&consts, &state, &err);
    if (st != GS_OK) {
        printf("scenario %s init failed: %s: %s\n", s->name, err.parameter, err.message);
        return 1;
    }
#ifdef FW_TARGET
    report_cost(s, &consts, &state);
#endif
    printf("scenario %s steps %d\n", s->name, s->steps);
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    for (int k = 0; k < s->steps; ++k) {
        gs_rig_input in;
        gs_rig_output out;
        gs_real v[GS_RIG_OUTPUT_FIELDS];
        s->input(k, &in);
        gs_rig_step(&consts, &state, &in, &out);
        output_fields(&out, v);
        printf("%04d", k);
        for (int i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
            printf(" " BITS_FMT, bits_of(v[i]));
            h = hash_real(h, v[i]);
        }
        printf("\n");
    }
    printf("hash %s %08" PRIx32 "%08" PRIx32 "\n", s->name, (uint32_t)(h >> 32), (uint32_t)h);
    return 0;
}

int main(void)
{
#ifdef FW_TARGET
    board_counter_start();
    printf("# target Cortex-M4F (QEMU mps2-an386), precision " PRECISION "\n");
    printf("# calibration %" PRIu32 " instructions counted for 200000 known\n", (uint32_t)board_calibrate(100000U));
#endif
    /* Layout: informational only. RAM per rig instance is gs_rig_state; the
     * constants (gs_rig_consts) are read-only after init and may live in
     * flash. arm-none-eabi uses the AAPCS bare-metal variable-size enums
     * (1 byte here), x86-64 int-sized ones, so the structs holding enums are
     * a few bytes smaller on the target. */
    printf("# layout sizeof gs_rig_consts %u gs_rig_state %u gs_simple_gear_consts %u "
           "gs_rack_pinion_consts %u gs_block_state %u gs_rig_params %u gs_simple_gear_params %u "
           "gs_rack_pinion_params %u gs_rig_input %u gs_rig_output %u precision %s\n",
           (unsigned)sizeof(gs_rig_consts), (unsigned)sizeof(gs_rig_state), (unsigned)sizeof(gs_simple_gear_consts),
           (unsigned)sizeof(gs_rack_pinion_consts), (unsigned)sizeof(gs_block_state), (unsigned)sizeof(gs_rig_params),
           (unsigned)sizeof(gs_simple_gear_params), (unsigned)sizeof(gs_rack_pinion_params),
           (unsigned)sizeof(gs_rig_input), (unsigned)sizeof(gs_rig_output), PRECISION);
    print_columns();
    int failures = 0;
    for (int i = 0; i < fw_scenario_count; ++i) {
        failures += run(&fw_scenarios[i]);
    }
    printf("done %d scenarios, %d failed\n", fw_scenario_count, failures);
    return failures == 0 ? 0 : 1;
}

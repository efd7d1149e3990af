/* size_probe.c - minimal programs that pull in one model each, linked with
 * --gc-sections and no C runtime, so that `arm-none-eabi-size` of the program
 * minus the empty probe (PROBE_BASELINE) is what the model costs in flash and
 * RAM. Parameters are built on the stack as an application would. Exactly one
 * PROBE_* is defined per program.
 *
 * Each instance is two static objects, named so that scripts/firmware_check.sh
 * finds their sizes with nm: fw_state_* (gs_rig_state / gs_block_state, what a
 * step updates: the RAM per instance) and fw_consts_* (gs_rig_consts /
 * gs_*_consts, what init derives and a step only reads). Here init fills the
 * constants at start-up, so they sit in .bss next to the state; a product may
 * instead keep them in flash, as an image of an initialised rig. */
#include "gearsim/gearsim.h"

/* Inputs read through volatile so that nothing is folded away. */
static volatile gs_real sink;
static volatile gs_real source = GS_R(1.0);

#if defined(PROBE_GEAR_BLOCK)
static gs_simple_gear_consts fw_consts_gear;
static gs_block_state fw_state_gear;
int main(void)
{
    const gs_simple_gear_params p = gs_simple_gear_params_default();
    if (gs_simple_gear_init(&fw_consts_gear, &fw_state_gear, &p, NULL) != GS_OK) {
        return 1;
    }
    gs_gear_ports_in in = {source, source, source, source, source, 0};
    gs_gear_ports_out out;
    for (;;) {
        gs_simple_gear_step(&fw_consts_gear, &fw_state_gear, GS_R(1e-3), &in, &out);
        sink = out.base_torque_Nm;
    }
}
#elif defined(PROBE_RACK_BLOCK)
static gs_rack_pinion_consts fw_consts_rack;
static gs_block_state fw_state_rack;
int main(void)
{
    const gs_rack_pinion_params p = gs_rack_pinion_params_default();
    if (gs_rack_pinion_init(&fw_consts_rack, &fw_state_rack, &p, NULL) != GS_OK) {
        return 1;
    }
    gs_rack_ports_in in = {source, source, source, source, source, 0};
    gs_rack_ports_out out;
    for (;;) {
        gs_rack_pinion_step(&fw_consts_rack, &fw_state_rack, GS_R(1e-3), &in, &out);
        sink = out.pinion_torque_Nm;
    }
}
#elif defined(PROBE_GEAR_RIG)
static gs_rig_consts fw_consts_gear_rig;
static gs_rig_state fw_state_gear_rig;
int main(void)
{
    const gs_simple_gear_params g = gs_simple_gear_params_default();
    const gs_rig_params r = gs_rig_params_default();
    if (gs_rig_init_gear(&fw_consts_gear_rig, &fw_state_gear_rig, &g, &r, NULL) != GS_OK) {
        return 1;
    }
    gs_rig_input in = {source, source, source, source, source};
    gs_rig_output out;
    for (;;) {
        gs_rig_step(&fw_consts_gear_rig, &fw_state_gear_rig, &in, &out);
        sink = out.base_torque;
    }
}
#elif defined(PROBE_RACK_RIG)
static gs_rig_consts fw_consts_rack_rig;
static gs_rig_state fw_state_rack_rig;
int main(void)
{
    const gs_rack_pinion_params g = gs_rack_pinion_params_default();
    const gs_rig_params r = gs_rig_params_default();
    if (gs_rig_init_rack(&fw_consts_rack_rig, &fw_state_rack_rig, &g, &r, NULL) != GS_OK) {
        return 1;
    }
    gs_rig_input in = {source, source, source, source, source};
    gs_rig_output out;
    for (;;) {
        gs_rig_step(&fw_consts_rack_rig, &fw_state_rack_rig, &in, &out);
        sink = out.base_torque;
    }
}
#elif defined(PROBE_BOTH_RIGS)
static gs_rig_consts fw_consts_gear_rig;
static gs_rig_state fw_state_gear_rig;
static gs_rig_consts fw_consts_rack_rig;
static gs_rig_state fw_state_rack_rig;
static volatile const char *message;
int main(void)
{
    const gs_simple_gear_params g = gs_simple_gear_params_default();
    const gs_rack_pinion_params k = gs_rack_pinion_params_default();
    const gs_rig_params r = gs_rig_params_default();
    gs_error err;
    if (gs_rig_init_gear(&fw_consts_gear_rig, &fw_state_gear_rig, &g, &r, &err) != GS_OK ||
        gs_rig_init_rack(&fw_consts_rack_rig, &fw_state_rack_rig, &k, &r, &err) != GS_OK) {
        message = gs_status_str(err.status);
        return 1;
    }
    gs_rig_input in = {source, source, source, source, source};
    gs_rig_output out;
    for (;;) {
        gs_rig_step(&fw_consts_gear_rig, &fw_state_gear_rig, &in, &out);
        gs_rig_step(&fw_consts_rack_rig, &fw_state_rack_rig, &in, &out);
        gs_rig_reset(&fw_consts_rack_rig, &fw_state_rack_rig);
        sink = out.base_torque;
    }
}
#elif defined(PROBE_BASELINE)
int main(void)
{
    for (;;) {
        sink = source;
    }
}
#else
#error "define one PROBE_* macro"
#endif

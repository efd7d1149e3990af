/* scenarios.h - scripted rig scenarios shared by the Cortex-M4F test program
 * (run under QEMU) and its host twin (firmware/host_main.c path of main.c).
 *
 * Every scenario initialises a rig from fixed parameters and steps it with
 * inputs computed from the step index with +, -, *, / only (no libm), so the
 * same source gives the same inputs on every IEEE-754 target of one precision.
 */
#ifndef GEARSIM_FW_SCENARIOS_H
#define GEARSIM_FW_SCENARIOS_H

#include "gearsim/gearsim.h"

typedef struct {
    const char *name;
    /* Fills the rig's constants and initial state from the scenario's
     * parameters; returns GS_OK or the status. */
    gs_status (*init)(gs_rig_consts *consts, gs_rig_state *state, gs_error *err);
    /* Input of step k (0-based). */
    void (*input)(int k, gs_rig_input *in);
    int steps;
} fw_scenario;

extern const fw_scenario fw_scenarios[];
extern const int fw_scenario_count;

#endif /* GEARSIM_FW_SCENARIOS_H */

/*
 * What the parts of the HIL library share and nobody else sees: the bridge
 * (bridge.c) calls the parameter changes (tuning.c), the fault stage
 * (fault.c) and the scenario (scenario.c) at fixed points of a period.
 */
#ifndef GEARSIM_HIL_INTERNAL_H
#define GEARSIM_HIL_INTERNAL_H

#include "gearsim/hil.h"

/* bridge.c: the model's value of a feedback signal this period (an output
 * or an input applied), before any fault. */
double gs_hil_model_value_(const gs_hil_bridge *b, const gs_hil_signal *sig);
/* bridge.c: the value of a condition's source this period (NaN: none yet). */
double gs_hil_source_value_(const gs_hil_bridge *b, const gs_hil_condition *c);
int gs_hil_condition_holds_(const gs_hil_bridge *b, const gs_hil_condition *c);

/* tuning.c */
void gs_hil_init_tuning_(gs_hil_bridge *b, gs_rig_block block);
void gs_hil_swap_params_(gs_hil_bridge *b);
unsigned gs_hil_check_changes_(gs_hil_bridge *b, const gs_hil_scenario *s, gs_error *err);

/* fault.c: after period n's steps, before its frames: delays recorded,
 * triggers looked at, which faults act on period n (flag fault_active). */
void gs_hil_faults_update_(gs_hil_bridge *b, uint64_t n);
/* fault.c: signal s of frame f as the faults acting on it change it. */
double gs_hil_fault_value_(gs_hil_bridge *b, unsigned f, unsigned s, double x);
/* fault.c: a frame's bytes as the frame faults change them; the number of
 * times to send it (0: dropped, 2: duplicated). */
unsigned gs_hil_fault_frame_(gs_hil_bridge *b, unsigned f, gs_hil_frame *frame);
/* fault.c: the status counter of frame f with a counter_stop acting on it:
 * 1 and *value the counter to send (held), else 0. */
int gs_hil_fault_counter_(gs_hil_bridge *b, unsigned f, uint64_t next, uint64_t *value);

/* scenario.c: at the start of period n (after the commands are applied) and
 * after its steps (before its frames). */
void gs_hil_scenario_start_(gs_hil_bridge *b, uint64_t n);
void gs_hil_scenario_end_(gs_hil_bridge *b, uint64_t n);
/* scenario.c: the scenario's load for period n (0 without one). */
double gs_hil_scenario_load_(const gs_hil_bridge *b, uint64_t n);

#endif

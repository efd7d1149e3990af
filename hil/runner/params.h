/*
 * The runner's parameter file (docs/hil-runner.md, "Parameter file"): the
 * rig's C parameter structs as flat `key = value` lines.
 */
#ifndef GEARSIM_HIL_RUNNER_PARAMS_H
#define GEARSIM_HIL_RUNNER_PARAMS_H

#include <stdio.h>

#include "gearsim/rig.h"

typedef struct {
    gs_rig_block block;
    gs_simple_gear_params gear;
    gs_rack_pinion_params rack;
    gs_rig_params rig;             /* dt_s comes from --period / --substeps */
    gs_real ambient_temperature_K; /* run.ambient_temperature_K, default 293.15 */
} runner_params;

/* Read path into *out. On failure returns -1 with one line in message:
 * "FILE:LINE: key: what is wrong". */
int runner_params_load(const char *path, runner_params *out, char *message, size_t message_size);

/* Print every key the parser accepts, one per line (`gearsim-hil --list-params`). */
void runner_params_list(FILE *stream);

#endif

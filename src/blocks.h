/* blocks.h - block-parameter to mesh mapping, used by the blocks and rigs (internal). */
#ifndef GS_BLOCKS_H
#define GS_BLOCKS_H

#include "gearsim/simple_gear.h"
#include "gearsim/rack_pinion.h"
#include "mesh.h"

/* Validate params and fill a mesh (constants + initial state). The mesh is
 * written only on success. */
gs_status gs_simple_gear_mesh(gs_mesh_ *mesh, const gs_simple_gear_params *p, gs_error *err);
gs_status gs_rack_pinion_mesh(gs_mesh_ *mesh, const gs_rack_pinion_params *p, gs_error *err);

/* Defaults shared by both blocks. */
gs_backlash_params gs_backlash_params_default_(void);

#endif /* GS_BLOCKS_H */

/* regularised_friction.h - the driven side's regularised friction
 * (physics.md 11): the smooth law F(v)*tanh(4 v/v_th) on a driven side that
 * moves freely, as a damper whose coefficient is taken at the start speed of
 * each step and acts on its end speed (rigid mesh). */
#ifndef GS_REGULARISED_FRICTION_H
#define GS_REGULARISED_FRICTION_H

#include "gearsim/types.h"

/* The damping coefficient c >= 0 (N*m*s/rad or N*s/m) with c*w = F*tanh(4 w/v_th)
 * at the speed w (rad/s or m/s): the secant of the smooth law through rest,
 * 4 F/v_th at w = 0. level: F >= 0; inv_threshold: 1/v_th > 0. */
gs_real gs_creep_damping(gs_real level, gs_real w, gs_real inv_threshold);

#endif /* GS_REGULARISED_FRICTION_H */

/* rig_internal.h - the rig's private constants and the interface between
 * its files (internal). The rig is a block between a driven base shaft and an
 * inertia (physics.md 11):
 *  - rig.c: parameters (defaults, validation), the constants init derives,
 *    init, reset, info, run, and gs_rig_step, which picks the step path;
 *  - rig_rigid.c: the rigid mesh, speed-driven and torque-driven base;
 *  - rig_geared.h: the geared solve of a free base gear (inline), for a
 *    torque-driven base and the compliant shaft;
 *  - rig_compliance.c: the compliant base shaft;
 *  - rig_backlash.c: the contact sub-steps with the set-valued friction;
 *  - rig_terms.c: the friction level and the torque ripple the paths share.
 *
 * Four step paths share the mesh of mesh.h:
 *  - rigid mesh, speed-driven base: causal form A; the follower's inertia
 *    torque uses the filtered backward-difference base acceleration;
 *  - rigid mesh, torque-driven base: one degree of freedom, backward Euler;
 *    the viscous terms implicit, the meshing loss and the load's Coulomb
 *    friction set-valued (closed form per power-flow piece, gs_rig_geared_solve
 *    in rig_geared.h);
 *  - compliant base shaft: the same solve for the base gear in sub-steps of
 *    the shaft's implicit midpoint rule;
 *  - backlash: the follower (and a torque-driven base) carry their own
 *    speeds; the contact is integrated by backward Euler in a fixed number
 *    of sub-steps (contact.h), viscous terms implicit, the meshing loss's
 *    bounds at the sub-step's own contact force.
 *
 * Friction where a shaft moves freely (the load's Coulomb friction and the
 * meshing loss, physics.md 11 "Lossy meshes hold") is one mechanism: backward
 * Euler on a friction bounded by its magnitude in each direction. It stops a
 * shaft within a step when the bound can, holds it at rest while the applied
 * torque stays within the bounds, and never reverses it. */
#ifndef GS_RIG_INTERNAL_H
#define GS_RIG_INTERNAL_H

#include "gearsim/rig.h"
#include "mesh.h"

/* The base gear's side of the geared solve: J_B + h*visc and visc, the
 * implicit slope of the torques on it (viscous, and the compliant shaft's);
 * and, where init fixes the law and the driven side (geared_fixed), the
 * two power-flow pieces' masses lambda*M_f + M_b (rig_geared.h). */
typedef struct {
    gs_real mass;
    gs_real visc;
    gs_real den_fd; /* (1 - k_fd)*M_f + mass */
    gs_real den_bd; /* (1 + k_bd)*M_f + mass */
} geared_base_;

/* The geared solve's terms from the meshing law and the driven side's
 * friction bound (gs_rig_geared_law, rig_geared.h). */
typedef struct {
    gs_real l_fd; /* 1 - k_fd */
    gs_real l_bd; /* 1 + k_bd */
    gs_real hc;   /* h*|a|*c0 */
    gs_real hf;   /* h*|a|*bound */
} geared_law_;

/* What init derives for a rig; the public gs_rig_consts is an opaque view of
 * it. The step reads it and writes the public gs_rig_state. */
typedef struct {
    gs_mesh_ mesh;
    gs_base_drive base_drive;
    gs_temperature_source temperature_source;
    int substeps;
    int substeps_capped; /* 1: the automatic count stopped at GS_AUTO_SUBSTEPS_MAX */
    gs_real dt;
    gs_real base_inertia;
    gs_real initial_base_speed;
    gs_real driven_inertia;
    gs_real load_coulomb;
    gs_real inv_load_speed_threshold;
    int friction_regularised; /* a free driven side's friction is F(v)*tanh(4 v/v_th), a damper */
    int speed_ramp;           /* speed-driven rigid rig: torques at the step's mean speed */
    gs_real load_offset;
    gs_real inv_thermal_resistance;
    gs_real thermal_gain; /* dt/C over the step, K/W (gs_mesh_thermal_constants) */
    gs_real thermal_den;  /* 1 + thermal_gain/R: the ambient path's implicit term */
    gs_real accel_gain;   /* dt/(tau + dt) */
    gs_real inv_dt;       /* 1/dt */
    /* the geared solve's masses (rigid mesh with a free base gear: a torque-driven
     * base over dt, or the compliant shaft's base gear over its sub-step h),
     * viscous terms implicit: the base with mu_B (+ g/2 of the shaft's midpoint
     * rule, or g of its end-speed rule), the driven side a^2*(J_F + h*mu_F) */
    geared_base_ geared_base;
    geared_base_ geared_base_end;
    gs_real geared_follower_mass; /* a^2*(J_F + h*mu_F) */
    gs_real geared_follower_visc; /* a^2*mu_F */
    /* The geared solve's law and friction terms, fixed at init where the law
     * is (loss_static) and the driven side's mass and friction level too (not
     * regularised, no Stribeck term): the step reads them instead of deriving
     * them twice per sub-step. */
    int geared_fixed;
    geared_law_ geared_law; /* of the prepared law and F_C (rig_geared.h) */
    /* A loss law that does not depend on the temperature or the load (none,
     * constant and load-dependent efficiency) is prepared once, at init. */
    int loss_static;
    /* backlash: no friction on the follower at all (every sub-step is one
     * contact solve) */
    int follower_free;
    /* backlash and compliant shaft: a law read again in every sub-step (the
     * 2-D table, at the last sub-step's base load) */
    int law_per_substep;
    gs_loss_ctx_ loss_ctx;
    gs_mesh_friction_ loss_law;
    gs_real substep;                /* h = dt/substeps, s */
    gs_real inv_substeps;           /* 1/substeps */
    gs_real inv_driven_inertia_sub; /* 1/(J_F + h*mu_F): the implicit viscous term */
    gs_real inv_base_inertia_sub;   /* 1/(J_B + h*mu_B) (torque-driven base) */
    gs_real follower_lever;         /* s*r_F (m; the rack: s_R): T_F0 = -s*r_F*f */
    gs_real follower_kick;          /* h*s*r_F/(J_F + h*mu_F): the follower's speed per contact force */
    gs_real base_kick;              /* h*r_B/(J_B + h*mu_B): the base's (0 speed-driven) */
    gs_real bound_gain;             /* s*r_F*follower_kick/(h/m_eff): the follower's share of the
                                     * contact's inverse mass (rig_backlash.c) */
    gs_real contact_h_omega_n;      /* h*omega_n of the contact at the chosen sub-step */
    gs_contact_step_ contact;       /* backward-Euler contact constants for h */
    gs_contact_step_ contact_stuck; /* the same with the driven side held by its friction
                                      (torque-driven base: the base inertia alone) */
    /* the contact seen through the follower's friction on each branch of a
     * law fixed at init (loss_static, not regularised; rig_backlash.c):
     * h/m_eff times 1 + bound_gain*q_fd (the follower drives) and
     * 1 - bound_gain*q_bd (the base drives) */
    int friction_contacts_fixed;
    gs_contact_step_ contact_fd;
    gs_contact_step_ contact_bd;
    /* Stribeck friction: F(v) = F_C + excess*exp(-v^2/v_S^2) */
    int stribeck;
    gs_real stribeck_excess;       /* F_brk - F_C, N*m or N */
    gs_real inv_stribeck_speed_sq; /* 1/v_S^2 */
    /* compliance: spring k and damper c from the drive to the base gear */
    int compliant;
    int compliance_substeps;
    gs_real stiffness;     /* k, N*m/rad */
    gs_real shaft_damping; /* c, N*m*s/rad */
    gs_real compliance_h;  /* sub-step h = dt/compliance_substeps, s */
    gs_real inv_compliance_substeps;
    gs_real inv_compliance_h; /* 1/h */
    gs_real compliance_gain;  /* k*h/2 + c: d(shaft torque)/d(relative speed), midpoint rule */
    gs_real compliance_h_omega_n;
    /* torque ripple: A*cos(i*theta + phi) = a_i*cos(i*theta) - b_i*sin(i*theta) */
    int ripple;
    int mesh_teeth;
    gs_real ripple_rev_cos[GS_RIPPLE_HARMONICS]; /* a_i = A_i*cos(phi_i), N*m */
    gs_real ripple_rev_sin[GS_RIPPLE_HARMONICS]; /* b_i = A_i*sin(phi_i), N*m */
    gs_real ripple_mesh_cos[GS_RIPPLE_HARMONICS];
    gs_real ripple_mesh_sin[GS_RIPPLE_HARMONICS];
} rig_consts_;

/* ---- Terms the step paths share (rig_terms.c). */

/* The driven side's friction level at speed w_f: F_C, plus the Stribeck
 * hump (F_brk - F_C)*exp(-(w_f/v_S)^2), which is F_brk at rest. Evaluated at
 * the speed a (sub-)step starts from: explicit, like any speed-dependent
 * friction level here; the friction's direction stays implicit. */
gs_real gs_rig_stribeck_level(const rig_consts_ *r, gs_real w_f);

/* The friction level with the Stribeck term on or off (F_C, no call). */
static inline gs_real friction_level(const rig_consts_ *r, gs_real w_f)
{
    return r->stribeck ? gs_rig_stribeck_level(r, w_f) : r->load_coulomb;
}

/* The regularised friction's magnitude at the driven speed w_f: the smooth
 * law F(v)*|tanh(4 v/v_th)| of the speed-driven rigid rig. */
gs_real gs_rig_creep_level(const rig_consts_ *r, gs_real w_f);

/* Regularised, the meshing loss of a freely moving driven side is the
 * set-valued law at the strength the speed-driven rigid rig's smoothing
 * gives it at the (sub-)step's start: the coefficients times
 * s = |tanh(4 w_F/w_th)| (load-dependent laws, speed threshold) or
 * |tanh(4 T_F w_F/p_th)| (efficiency laws, power threshold; T_F the last net
 * follower torque). Zero at rest, so the mesh creeps like the load's
 * friction; a weaker set-valued law is still passive. */
gs_mesh_friction_ gs_rig_regularised_law(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real t_f, gs_real w_f);

/* The meshing law a free path uses this (sub-)step: law itself, or with
 * load_friction_regularised its regularised copy in *scratch. Inline, so
 * that the switch off costs one test. */
static inline const gs_mesh_friction_ *gs_rig_step_law(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real t_f,
                                                       gs_real w_f, gs_mesh_friction_ *scratch)
{
    if (!r->friction_regularised) {
        return law;
    }
    *scratch = gs_rig_regularised_law(r, law, t_f, w_f);
    return scratch;
}

/* The ripple torque (physics.md 11.5) the base shaft must add at base angle
 * theta: per-revolution harmonics of theta, per-tooth harmonics of Z*theta. */
gs_real gs_rig_ripple_torque(const rig_consts_ *r, gs_real theta);

/* cos and sin of any angle: the ripple's phases at init, its harmonics in
 * the step. */
void gs_rig_cos_sin(gs_real angle, gs_real *c, gs_real *s);

/* ---- The step paths. gs_rig_step (rig.c) has taken the speed sample (a
 * speed-driven base: the filtered acceleration, the first sample's speeds)
 * and prepared the meshing loss for this step (ctx; law, the loss as a
 * friction element, where a shaft moves freely) before it calls one; each
 * advances the speeds and writes the outputs of its path; gs_rig_step then
 * takes the thermal step and writes the outputs every path shares. */

/* Rigid mesh, speed-driven base (rig_rigid.c); w_prev is the last speed
 * sample. The caller advances the angles. */
void gs_rig_rigid_speed_driven(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                               gs_real w_prev, gs_rig_output *out);

/* Rigid mesh, torque-driven base (rig_rigid.c): one geared solve over dt.
 * The caller advances the angles. */
void gs_rig_rigid_torque_driven(const rig_consts_ *r, gs_rig_state *st, const gs_mesh_friction_ *law,
                                const gs_rig_input *in, gs_rig_output *out);

/* The compliant base shaft (rig_compliance.c; speed-driven base, rigid
 * mesh) in its sub-steps; w_d_start is the drive's speed at the step's
 * start. law is the step's; the 2-D table's is read again per sub-step.
 * Advances the angles. */
void gs_rig_compliant_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx,
                           const gs_mesh_friction_ *law, const gs_rig_input *in, gs_real w_d_start, gs_rig_output *out);

/* Backlash (rig_backlash.c): the contact sub-steps of either base drive.
 * law is the step's; the 2-D table's is read again per sub-step (held over
 * the step, its load lags by a step, an error the sub-steps do not shrink:
 * the solve_ivp reference tests caught it). Advances the angles and the
 * contact state. */
void gs_rig_backlash_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_mesh_friction_ *law,
                          const gs_rig_input *in, gs_rig_output *out);

#endif /* GS_RIG_INTERNAL_H */

/* rig.c - a block between a driven base shaft and an inertia (physics.md 11).
 *
 * Four step paths share the mesh of mesh.h:
 *  - rigid mesh, speed-driven base: causal form A; the follower's inertia
 *    torque uses the filtered backward-difference base acceleration;
 *  - rigid mesh, torque-driven base: one degree of freedom, backward Euler;
 *    the viscous terms implicit, the meshing loss and the load's Coulomb
 *    friction set-valued (closed form per power-flow piece, geared_solve);
 *  - compliant base shaft: the same solve for the base gear in sub-steps of
 *    the shaft's implicit midpoint rule;
 *  - backlash: the follower (and a torque-driven base) carry their own
 *    speeds; the contact is integrated by backward Euler in a fixed number
 *    of sub-steps (contact.h), viscous terms implicit, the meshing loss's
 *    bounds taken from the last contact force.
 *
 * Friction where a shaft moves freely (the load's Coulomb friction and the
 * meshing loss, physics.md 11 "Lossy meshes hold") is one mechanism: backward
 * Euler on a friction bounded by its magnitude in each direction. It stops a
 * shaft within a step when the bound can, holds it at rest while the applied
 * torque stays within the bounds, and never reverses it. */
#include <string.h>

#include "gearsim/rig.h"
#include "blocks.h"
#include "contact.h"
#include "gs_math.h"
#include "mesh.h"
#include "regularised_friction.h"
#include "validate.h"

/* The base gear's side of the geared solve: J_B + h*visc and visc, the
 * implicit slope of the torques on it (viscous, and the compliant shaft's). */
typedef struct {
    gs_real mass;
    gs_real visc;
} geared_base_;

/* What init derives for a rig; the public gs_rig_consts is an opaque view of
 * it. The step reads it and writes the public gs_rig_state. */
typedef struct {
    gs_mesh_ mesh;
    gs_base_drive base_drive;
    gs_temperature_source temperature_source;
    int substeps;
    int substeps_capped;           /* 1: the automatic count stopped at GS_AUTO_SUBSTEPS_MAX */
    gs_real dt;
    gs_real base_inertia;
    gs_real initial_base_speed;
    gs_real driven_inertia;
    gs_real load_coulomb;
    gs_real inv_load_speed_threshold;
    int friction_regularised;      /* a free driven side's friction is F(v)*tanh(4 v/v_th), a damper */
    int speed_ramp;                /* speed-driven rigid rig: torques at the step's mean speed */
    gs_real load_offset;
    gs_real inv_thermal_resistance;
    gs_real accel_gain;            /* dt/(tau + dt) */
    gs_real inv_dt;                /* 1/dt */
    /* the geared solve's masses (rigid mesh with a free base gear: a torque-driven
     * base over dt, or the compliant shaft's base gear over its sub-step h),
     * viscous terms implicit: the base with mu_B (+ g/2 of the shaft's midpoint
     * rule, or g of its end-speed rule), the driven side a^2*(J_F + h*mu_F) */
    geared_base_ geared_base;
    geared_base_ geared_base_end;
    gs_real geared_follower_mass;  /* a^2*(J_F + h*mu_F) */
    gs_real geared_follower_visc;  /* a^2*mu_F */
    /* A loss law that does not depend on the temperature or the load (none,
     * constant and load-dependent efficiency) is prepared once, at init. */
    int loss_static;
    gs_loss_ctx_ loss_ctx;
    gs_mesh_friction_ loss_law;
    gs_real substep;               /* h = dt/substeps, s */
    gs_real inv_substeps;          /* 1/substeps */
    gs_real inv_driven_inertia_sub;/* 1/(J_F + h*mu_F): the implicit viscous term */
    gs_real inv_base_inertia_sub;  /* 1/(J_B + h*mu_B) (torque-driven base) */
    gs_real follower_lever;        /* s*r_F (m; the rack: s_R): T_F0 = -s*r_F*f */
    gs_real follower_kick;         /* h*s*r_F/(J_F + h*mu_F): the follower's speed per contact force */
    gs_real base_kick;             /* h*r_B/(J_B + h*mu_B): the base's (0 speed-driven) */
    gs_real contact_h_omega_n;     /* h*omega_n of the contact at the chosen sub-step */
    gs_contact_step_ contact;      /* backward-Euler contact constants for h */
    gs_contact_step_ contact_stuck;/* the same with the driven side held by its friction
                                      (torque-driven base: the base inertia alone) */
    /* Stribeck friction: F(v) = F_C + excess*exp(-v^2/v_S^2) */
    int stribeck;
    gs_real stribeck_excess;       /* F_brk - F_C, N*m or N */
    gs_real inv_stribeck_speed_sq; /* 1/v_S^2 */
    /* compliance: spring k and damper c from the drive to the base gear */
    int compliant;
    int compliance_substeps;
    gs_real stiffness;             /* k, N*m/rad */
    gs_real shaft_damping;         /* c, N*m*s/rad */
    gs_real compliance_h;          /* sub-step h = dt/compliance_substeps, s */
    gs_real inv_compliance_substeps;
    gs_real inv_compliance_h;      /* 1/h */
    gs_real compliance_gain;       /* k*h/2 + c: d(shaft torque)/d(relative speed), midpoint rule */
    gs_real compliance_h_omega_n;
    /* torque ripple: A*cos(i*theta + phi) = a_i*cos(i*theta) - b_i*sin(i*theta) */
    int ripple;
    int mesh_teeth;
    gs_real ripple_rev_cos[GS_RIPPLE_HARMONICS];  /* a_i = A_i*cos(phi_i), N*m */
    gs_real ripple_rev_sin[GS_RIPPLE_HARMONICS];  /* b_i = A_i*sin(phi_i), N*m */
    gs_real ripple_mesh_cos[GS_RIPPLE_HARMONICS];
    gs_real ripple_mesh_sin[GS_RIPPLE_HARMONICS];
} rig_consts_;

GS_CONSTS_REALS_CHECK_(GS_RIG_CONSTS_REALS, rig_consts_);

/* The opaque public constants are a view of rig_consts_. */
static const rig_consts_ *consts_of(const gs_rig_consts *consts)
{
    return (const rig_consts_ *)(const void *)consts;
}

gs_rig_params gs_rig_params_default(void)
{
    gs_rig_params p;
    memset(&p, 0, sizeof p);
    p.dt_s = GS_R(1e-3);
    p.base_drive = GS_BASE_SPEED_DRIVEN;
    p.base_inertia_kg_m2 = GS_R(0.0);
    p.initial_base_speed_rad_s = GS_R(0.0);
    p.driven_inertia = GS_R(0.05);
    p.load_coulomb_friction = GS_R(0.0);
    p.load_coulomb_speed_threshold = GS_R(1e-3);
    p.load_offset = GS_R(0.0);
    p.heat_path = 0;
    p.thermal_resistance_K_W = GS_R(2.0);
    p.temperature_source = GS_TEMPERATURE_FROM_MODEL;
    p.accel_filter_time_constant_s = GS_R(0.0);
    p.contact_substeps = 0;
    p.load_breakaway_friction = GS_R(0.0);
    p.load_stribeck_speed = GS_R(0.01);
    p.compliance_stiffness_Nm_rad = GS_R(0.0);
    p.compliance_damping_Nm_s_rad = GS_R(0.0);
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        p.ripple_revolution_amplitude_Nm[i] = GS_R(0.0);
        p.ripple_revolution_phase_rad[i] = GS_R(0.0);
        p.ripple_mesh_amplitude_Nm[i] = GS_R(0.0);
        p.ripple_mesh_phase_rad[i] = GS_R(0.0);
    }
    p.ripple_mesh_teeth = 0;
    p.load_friction_regularised = 0;
    p.base_speed_ramp = 0;
    return p;
}

/* Stribeck: a breakaway level of 0 is none; any other must be >= F_C. */
static gs_status check_stribeck(const gs_rig_params *p, gs_error *err)
{
    gs_status s = gs_check_nonnegative(err, p->load_breakaway_friction, "load_breakaway_friction");
    if (s != GS_OK || !(p->load_breakaway_friction > GS_R(0.0))) {
        return s;
    }
    if (p->load_breakaway_friction < p->load_coulomb_friction) {
        return gs_fail(err, GS_E_BREAKAWAY, "load_breakaway_friction");
    }
    if ((s = gs_check_invertible(err, p->load_stribeck_speed, "load_stribeck_speed")) != GS_OK) {
        return s;
    }
    /* 1/v_S^2 is what the step uses */
    return gs_check_invertible(err, p->load_stribeck_speed * p->load_stribeck_speed, "load_stribeck_speed");
}

/* Compliance: the spring needs a base gear of its own (base_inertia > 0) that
 * only a speed-driven base on a rigid mesh provides in this version. */
static gs_status check_compliance(const gs_rig_params *p, int backlash, gs_error *err)
{
    gs_status s;
    if ((s = gs_check_nonnegative(err, p->compliance_stiffness_Nm_rad, "compliance_stiffness")) != GS_OK ||
        (s = gs_check_nonnegative(err, p->compliance_damping_Nm_s_rad, "compliance_damping")) != GS_OK ||
        !(p->compliance_stiffness_Nm_rad > GS_R(0.0))) {
        return s;
    }
    if (p->base_drive != GS_BASE_SPEED_DRIVEN || backlash) {
        return gs_fail(err, GS_E_COMBINATION, "compliance_stiffness");
    }
    return GS_OK; /* base_inertia >= 0 is checked with the drive; 0 puts the spring at the mesh */
}

static gs_status check_ripple(const gs_rig_params *p, gs_error *err)
{
    gs_status s;
    int mesh_harmonics = 0;
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        if ((s = gs_check_nonnegative(err, p->ripple_revolution_amplitude_Nm[i], "ripple_revolution_amplitude")) != GS_OK ||
            (s = gs_check_finite(err, p->ripple_revolution_phase_rad[i], "ripple_revolution_phase")) != GS_OK ||
            (s = gs_check_nonnegative(err, p->ripple_mesh_amplitude_Nm[i], "ripple_mesh_amplitude")) != GS_OK ||
            (s = gs_check_finite(err, p->ripple_mesh_phase_rad[i], "ripple_mesh_phase")) != GS_OK) {
            return s;
        }
        mesh_harmonics |= p->ripple_mesh_amplitude_Nm[i] > GS_R(0.0);
    }
    if (p->ripple_mesh_teeth < 0) {
        return gs_fail(err, GS_E_NEGATIVE, "ripple_mesh_teeth");
    }
    if (mesh_harmonics && p->ripple_mesh_teeth == 0) {
        return gs_fail(err, GS_E_NOT_POSITIVE, "ripple_mesh_teeth");
    }
    return GS_OK;
}

static gs_status check_rig(const gs_rig_params *p, gs_rig_block block, int backlash, gs_error *err)
{
    gs_status s;
    if (!gs_is_finite(p->dt_s) || !(p->dt_s > GS_R(0.0))) {
        return gs_fail(err, GS_E_STEP_SIZE, "dt");
    }
    if ((s = gs_check_invertible(err, p->dt_s, "dt")) != GS_OK) {
        return s;
    }
    switch (p->base_drive) {
    case GS_BASE_SPEED_DRIVEN:
        s = gs_check_nonnegative(err, p->base_inertia_kg_m2, "base_inertia");
        break;
    case GS_BASE_TORQUE_DRIVEN:
        s = gs_check_invertible(err, p->base_inertia_kg_m2, "base_inertia");
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "base_drive");
    }
    if (s != GS_OK) {
        return s;
    }
    switch (p->temperature_source) {
    case GS_TEMPERATURE_FROM_MODEL:
    case GS_TEMPERATURE_FROM_INPUT:
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "temperature_source");
    }
    const char *driven_name = block == GS_RIG_SIMPLE_GEAR ? "follower_inertia" : "rack_mass";
    if ((s = gs_check_finite(err, p->initial_base_speed_rad_s, "initial_base_speed")) != GS_OK ||
        (s = gs_check_invertible(err, p->driven_inertia, driven_name)) != GS_OK ||
        (s = gs_check_nonnegative(err, p->load_coulomb_friction, "load_coulomb_friction")) != GS_OK ||
        (s = gs_check_invertible(err, p->load_coulomb_speed_threshold, "load_coulomb_speed_threshold")) != GS_OK ||
        (s = gs_check_finite(err, p->load_offset, "load_offset")) != GS_OK ||
        (s = gs_check_nonnegative(err, p->accel_filter_time_constant_s, "accel_filter_time_constant")) != GS_OK) {
        return s;
    }
    if (p->heat_path && (s = gs_check_invertible(err, p->thermal_resistance_K_W, "thermal_resistance")) != GS_OK) {
        return s;
    }
    if (p->contact_substeps < 0 || p->contact_substeps > GS_MAX_SUBSTEPS) {
        return gs_fail(err, GS_E_SUBSTEPS, "contact_substeps");
    }
    if ((s = check_stribeck(p, err)) != GS_OK || (s = check_compliance(p, backlash, err)) != GS_OK) {
        return s;
    }
    return check_ripple(p, err);
}

/* The torque-driven base's share of 1/m_eff at the pitch line for sub-step
 * h, its viscous term implicit (0 for a speed-driven base). */
static gs_real base_inverse_mass(const rig_consts_ *r, gs_real h)
{
    const gs_mesh_ *m = &r->mesh;
    if (r->base_drive != GS_BASE_TORQUE_DRIVEN) {
        return GS_R(0.0);
    }
    return m->base_radius * m->base_radius / (r->base_inertia + h * m->mu_base);
}

/* 1/m_eff at the pitch line for sub-step h, with the viscous terms implicit. */
static gs_real contact_inverse_mass(const rig_consts_ *r, gs_real h)
{
    const gs_mesh_ *m = &r->mesh;
    return m->follower_radius * m->follower_radius / (r->driven_inertia + h * m->mu_follower)
           + base_inverse_mass(r, h);
}

/* Smallest count with (h*omega_n)^2 <= 0.25, i.e. h*omega_n <= 0.5, capped:
 * backward Euler is stable at any count; this only buys accuracy. */
static int automatic_substeps(const rig_consts_ *r)
{
    const gs_real k_over_m = r->mesh.stiffness * contact_inverse_mass(r, r->dt);
    int n = 1;
    while (n < GS_AUTO_SUBSTEPS_MAX) {
        const gs_real h = r->dt / (gs_real)n;
        if (h * h * k_over_m <= GS_R(0.25)) {
            break;
        }
        ++n;
    }
    return n;
}

/* sqrt(x2) for x2 >= 0 at init. */
static gs_real init_sqrt(gs_real x2)
{
    /* Newton for the square root (the core uses no libm), from above: it
     * decreases monotonically to the root; init only, so the count is loose */
    gs_real y = x2 > GS_R(1.0) ? x2 : GS_R(1.0);
    for (int i = 0; i < 200; ++i) {
        const gs_real next = GS_R(0.5) * (y + x2 / y);
        if (!(next < y)) {
            break;
        }
        y = next;
    }
    return y;
}

/* h*omega_n of the contact at sub-step h with 1/m_eff = inv_mass
 * (omega_n = sqrt(K/m_eff)). */
static gs_real contact_h_omega_n(const rig_consts_ *r, gs_real h, gs_real inv_mass)
{
    return init_sqrt(h * h * r->mesh.stiffness * inv_mass);
}

/* The compliant shaft: k over J_eff = J_B + a^2*J_F (base gear and driven
 * side geared rigidly), sub-stepped so that h*omega_c <= 0.2, where the
 * midpoint rule's frequency is within 0.4 % (physics.md 11), up to
 * GS_AUTO_SUBSTEPS_MAX. */
static void compliance_fill(rig_consts_ *r, const gs_rig_params *p)
{
    const gs_real a = r->mesh.inv_ratio;
    r->compliant = p->compliance_stiffness_Nm_rad > GS_R(0.0);
    r->stiffness = p->compliance_stiffness_Nm_rad;
    r->shaft_damping = p->compliance_damping_Nm_s_rad;
    r->compliance_substeps = 1;
    r->compliance_h_omega_n = GS_R(0.0);
    if (r->compliant) {
        const gs_real omega_sq = r->stiffness / (r->base_inertia + a * a * r->driven_inertia);
        while (r->compliance_substeps < GS_AUTO_SUBSTEPS_MAX) {
            const gs_real h = r->dt / (gs_real)r->compliance_substeps;
            if (h * h * omega_sq <= GS_R(0.04)) {
                break;
            }
            ++r->compliance_substeps;
        }
        const gs_real h = r->dt / (gs_real)r->compliance_substeps;
        r->compliance_h_omega_n = init_sqrt(h * h * omega_sq);
    }
    r->compliance_h = r->dt / (gs_real)r->compliance_substeps;
    r->inv_compliance_h = GS_R(1.0) / r->compliance_h;
    r->inv_compliance_substeps = GS_R(1.0) / (gs_real)r->compliance_substeps;
    r->compliance_gain = GS_R(0.5) * r->stiffness * r->compliance_h + r->shaft_damping;
    /* the geared solve's masses over the step (torque-driven rigid) or the shaft's sub-step */
    const gs_real h = r->compliant ? r->compliance_h : r->dt;
    r->geared_base.visc = r->mesh.mu_base + (r->compliant ? GS_R(0.5) * r->compliance_gain : GS_R(0.0));
    r->geared_base.mass = r->base_inertia + h * r->geared_base.visc;
    r->geared_base_end.visc = r->mesh.mu_base + r->compliance_gain;
    r->geared_base_end.mass = r->base_inertia + h * r->geared_base_end.visc;
    r->geared_follower_visc = a * a * r->mesh.mu_follower;
    r->geared_follower_mass = a * a * r->driven_inertia + h * r->geared_follower_visc;
}

/* cos and sin of any angle: one copy of the polynomials for init and step. */
static GS_NOINLINE void cos_sin(gs_real angle, gs_real *c, gs_real *s)
{
    gs_cos_sin(gs_reduce_angle(angle), c, s);
}

/* a = A*cos(phi), b = A*sin(phi) of each harmonic. */
static void ripple_fill(rig_consts_ *r, const gs_rig_params *p)
{
    int mesh_harmonics = 0;
    r->ripple = 0;
    r->mesh_teeth = p->ripple_mesh_teeth;
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        gs_real c;
        gs_real s;
        cos_sin(p->ripple_revolution_phase_rad[i], &c, &s);
        r->ripple_rev_cos[i] = p->ripple_revolution_amplitude_Nm[i] * c;
        r->ripple_rev_sin[i] = p->ripple_revolution_amplitude_Nm[i] * s;
        cos_sin(p->ripple_mesh_phase_rad[i], &c, &s);
        r->ripple_mesh_cos[i] = p->ripple_mesh_amplitude_Nm[i] * c;
        r->ripple_mesh_sin[i] = p->ripple_mesh_amplitude_Nm[i] * s;
        r->ripple |= p->ripple_revolution_amplitude_Nm[i] > GS_R(0.0) || p->ripple_mesh_amplitude_Nm[i] > GS_R(0.0);
        mesh_harmonics |= p->ripple_mesh_amplitude_Nm[i] > GS_R(0.0);
    }
    if (!mesh_harmonics) { /* the step skips the tooth-mesh angle */
        r->mesh_teeth = 0;
    }
}

/* Fills the rig around an already validated mesh; the rig parameters were
 * checked by check_rig. Writes in place: no second rig on the stack. */
static void rig_fill(rig_consts_ *r, const gs_rig_params *p)
{
    r->dt = p->dt_s;
    r->base_drive = p->base_drive;
    r->base_inertia = p->base_inertia_kg_m2;
    r->initial_base_speed = p->initial_base_speed_rad_s;
    r->driven_inertia = p->driven_inertia;
    r->load_coulomb = p->load_coulomb_friction;
    r->inv_load_speed_threshold = GS_R(1.0) / p->load_coulomb_speed_threshold;
    r->friction_regularised = p->load_friction_regularised != 0;
    r->speed_ramp = p->base_speed_ramp != 0;
    r->load_offset = p->load_offset;
    r->inv_thermal_resistance = p->heat_path ? GS_R(1.0) / p->thermal_resistance_K_W : GS_R(0.0);
    r->temperature_source = p->temperature_source;
    r->accel_gain = p->dt_s / (p->accel_filter_time_constant_s + p->dt_s);
    r->inv_dt = GS_R(1.0) / p->dt_s;
    r->substeps = 1;
    r->substeps_capped = 0;
    r->contact_h_omega_n = GS_R(0.0);
    if (r->mesh.backlash) {
        r->substeps = p->contact_substeps > 0 ? p->contact_substeps : automatic_substeps(r);
    }
    /* sub-step invariants: the step path multiplies instead of dividing */
    r->substep = r->dt / (gs_real)r->substeps;
    r->inv_substeps = GS_R(1.0) / (gs_real)r->substeps;
    r->inv_driven_inertia_sub = GS_R(1.0) / (r->driven_inertia + r->substep * r->mesh.mu_follower);
    r->inv_base_inertia_sub = r->base_drive == GS_BASE_TORQUE_DRIVEN
                                  ? GS_R(1.0) / (r->base_inertia + r->substep * r->mesh.mu_base)
                                  : GS_R(0.0);
    r->follower_lever = r->mesh.direction * r->mesh.follower_radius;
    r->follower_kick = r->substep * r->follower_lever * r->inv_driven_inertia_sub;
    r->base_kick = r->substep * r->mesh.base_radius * r->inv_base_inertia_sub;
    memset(&r->contact, 0, sizeof r->contact);
    memset(&r->contact_stuck, 0, sizeof r->contact_stuck);
    if (r->mesh.backlash) {
        const gs_real inv_eff_mass = contact_inverse_mass(r, r->substep); /* 1/m_eff at the pitch line, 1/kg */
        gs_contact_prepare(&r->mesh, r->substep, inv_eff_mass, &r->contact);
        if (r->base_drive == GS_BASE_TORQUE_DRIVEN) {
            gs_contact_prepare(&r->mesh, r->substep,
                               base_inverse_mass(r, r->substep), &r->contact_stuck);
        }
        r->contact_h_omega_n = contact_h_omega_n(r, r->substep, inv_eff_mass);
        r->substeps_capped = p->contact_substeps == 0 && r->contact_h_omega_n > GS_R(0.5);
    }
    r->loss_static = r->mesh.friction == GS_FRICTION_NONE || r->mesh.friction == GS_FRICTION_CONSTANT_EFFICIENCY
                     || r->mesh.friction == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    memset(&r->loss_ctx, 0, sizeof r->loss_ctx);
    gs_mesh_loss_prepare(&r->mesh, r->mesh.initial_temperature, &r->loss_ctx);
    gs_mesh_friction_law(&r->mesh, &r->loss_ctx, GS_R(0.0), &r->loss_law);
    r->stribeck = p->load_breakaway_friction > GS_R(0.0);
    r->stribeck_excess = r->stribeck ? p->load_breakaway_friction - p->load_coulomb_friction : GS_R(0.0);
    r->inv_stribeck_speed_sq =
        r->stribeck ? GS_R(1.0) / (p->load_stribeck_speed * p->load_stribeck_speed) : GS_R(0.0);
    compliance_fill(r, p);
    ripple_fill(r, p);
}

/* The rig parameters are checked first, so that once the block's mesh is
 * validated (and only then written into consts) nothing can fail: a failed
 * init leaves consts and state unchanged. */
gs_status gs_rig_init_gear(gs_rig_consts *consts, gs_rig_state *state,
                           const gs_simple_gear_params *gear, const gs_rig_params *params,
                           gs_error *err)
{
    if (consts == NULL || state == NULL || gear == NULL || params == NULL) {
        return gs_fail(err, GS_E_NULL,
                       consts == NULL ? "consts" : (state == NULL ? "state" : (gear == NULL ? "gear" : "params")));
    }
    rig_consts_ *r = (rig_consts_ *)(void *)consts;
    gs_status s = check_rig(params, GS_RIG_SIMPLE_GEAR, gear->backlash.enabled, err);
    if (s == GS_OK && (s = gs_simple_gear_mesh(&r->mesh, gear, err)) == GS_OK) {
        rig_fill(r, params);
        gs_rig_reset(consts, state);
    }
    return s;
}

gs_status gs_rig_init_rack(gs_rig_consts *consts, gs_rig_state *state,
                           const gs_rack_pinion_params *rack, const gs_rig_params *params,
                           gs_error *err)
{
    if (consts == NULL || state == NULL || rack == NULL || params == NULL) {
        return gs_fail(err, GS_E_NULL,
                       consts == NULL ? "consts" : (state == NULL ? "state" : (rack == NULL ? "rack" : "params")));
    }
    rig_consts_ *r = (rig_consts_ *)(void *)consts;
    gs_status s = check_rig(params, GS_RIG_RACK_PINION, rack->backlash.enabled, err);
    if (s == GS_OK && (s = gs_rack_pinion_mesh(&r->mesh, rack, err)) == GS_OK) {
        rig_fill(r, params);
        gs_rig_reset(consts, state);
    }
    return s;
}

void gs_rig_reset(const gs_rig_consts *consts, gs_rig_state *st)
{
    const rig_consts_ *r = consts_of(consts);
    gs_mesh_reset(&r->mesh, &st->block);
    st->started = 0;
    st->base_speed = r->base_drive == GS_BASE_TORQUE_DRIVEN ? r->initial_base_speed : GS_R(0.0);
    st->follower_speed = r->mesh.inv_ratio * st->base_speed;
    st->base_angle = GS_R(0.0);
    st->follower_position = GS_R(0.0);
    st->base_speed_sample = GS_R(0.0);
    st->base_acceleration = GS_R(0.0);
    st->shaft_twist = GS_R(0.0);
}

/* The driven side's friction level at speed w_f: F_C, plus the Stribeck
 * hump (F_brk - F_C)*exp(-(w_f/v_S)^2), which is F_brk at rest. Evaluated at
 * the speed a (sub-)step starts from: explicit, like any speed-dependent
 * friction level here; the friction's direction stays implicit. Past
 * (w_f/v_S)^2 = 40 the hump is 4.2e-18 of its height and is dropped. */
static GS_NOINLINE gs_real stribeck_level(const rig_consts_ *r, gs_real w_f)
{
    const gs_real z = w_f * w_f * r->inv_stribeck_speed_sq;
    return z < GS_R(40.0) ? r->load_coulomb + r->stribeck_excess * gs_exp_neg(z) : r->load_coulomb;
}

static inline gs_real friction_level(const rig_consts_ *r, gs_real w_f)
{
    return r->stribeck ? stribeck_level(r, w_f) : r->load_coulomb;
}

/* sum_i a_i*cos(i*x) - b_i*sin(i*x), i.e. sum_i A_i*cos(i*x + phi_i) (N*m).
 * The multiples come from the Chebyshev recurrence cos((i+1)x) = 2 cos x
 * cos(ix) - cos((i-1)x) (and the same for sin): one cos/sin pair per angle. */
/* The regularised friction's magnitude at the driven speed w_f: the smooth
 * law F(v)*|tanh(4 v/v_th)| of the speed-driven rigid rig. */
static gs_real creep_level(const rig_consts_ *r, gs_real w_f)
{
    return friction_level(r, w_f) * gs_abs(gs_tanh(GS_R(4.0) * w_f * r->inv_load_speed_threshold));
}

/* Regularised, the meshing loss of a freely moving driven side is the
 * set-valued law at the strength the speed-driven rigid rig's smoothing
 * gives it at the (sub-)step's start: the coefficients times
 * s = |tanh(4 w_F/w_th)| (load-dependent laws, speed threshold) or
 * |tanh(4 T_F w_F/p_th)| (efficiency laws, power threshold; T_F the last net
 * follower torque). Zero at rest, so the mesh creeps like the load's
 * friction; a weaker set-valued law is still passive. */
static gs_mesh_friction_ regularised_law(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real t_f, gs_real w_f)
{
    const gs_mesh_ *m = &r->mesh;
    gs_mesh_friction_ out = *law;
    if (!law->lossy) {
        return out;
    }
    const int on_speed = m->friction == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY
                         || m->friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    const gs_real x = on_speed ? w_f * m->inv_speed_threshold : t_f * w_f * m->inv_power_threshold;
    const gs_real strength = gs_abs(gs_tanh(GS_R(4.0) * x));
    out.c0 *= strength;
    out.k_fd *= strength;
    out.k_bd *= strength;
    out.q_fd = out.k_fd < GS_R(1.0) ? out.k_fd / (GS_R(1.0) - out.k_fd) : GS_R(-1.0);
    out.q_bd = out.k_bd / (GS_R(1.0) + out.k_bd);
    return out;
}

static gs_real harmonics(const gs_real *a, const gs_real *b, gs_real angle)
{
    gs_real c1;
    gs_real s1;
    cos_sin(angle, &c1, &s1);
    gs_real c_prev = GS_R(1.0), s_prev = GS_R(0.0), c = c1, sn = s1;
    gs_real sum = GS_R(0.0);
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        sum += a[i] * c - b[i] * sn;
        const gs_real c_next = GS_R(2.0) * c1 * c - c_prev;
        const gs_real s_next = GS_R(2.0) * c1 * sn - s_prev;
        c_prev = c;
        s_prev = sn;
        c = c_next;
        sn = s_next;
    }
    return sum;
}

/* The ripple torque (physics.md 11.5) the base shaft must add at base angle
 * theta: per-revolution harmonics of theta, per-tooth harmonics of Z*theta. */
static gs_real ripple_torque(const rig_consts_ *r, gs_real theta)
{
    /* Z*theta is formed from the reduced theta: Z is an integer, so the
     * phase survives where Z*theta itself would have lost it */
    const gs_real reduced = gs_reduce_angle(theta);
    gs_real tau = harmonics(r->ripple_rev_cos, r->ripple_rev_sin, reduced);
    if (r->mesh_teeth > 0) {
        tau += harmonics(r->ripple_mesh_cos, r->ripple_mesh_sin, (gs_real)r->mesh_teeth * reduced);
    }
    return tau;
}

/* External torque on the driven side of the speed-driven rigid rig: load,
 * offset and Coulomb (and Stribeck) friction smoothed on the imposed speed. */
static gs_real driven_external(const rig_consts_ *r, gs_real load, gs_real w_f)
{
    return load + r->load_offset
           - friction_level(r, w_f) * gs_tanh(GS_R(4.0) * w_f * r->inv_load_speed_threshold);
}

static void rigid_speed_driven(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                               gs_real w_prev, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    /* the step's mean speed under the samples' linear ramp, or this sample */
    const gs_real w_b = r->speed_ramp ? GS_R(0.5) * (w_prev + in->base_speed) : in->base_speed;
    const gs_real alpha_b = st->base_acceleration;
    const gs_real w_f = m->inv_ratio * w_b;
    const gs_real a_f = m->inv_ratio * alpha_b;
    const gs_real tau_f = driven_external(r, in->load, w_f) - r->driven_inertia * a_f;
    const gs_real t_f = tau_f - m->mu_follower * w_f;
    const gs_real tau_mesh = gs_mesh_loss_torque(m, ctx, t_f, w_f);
    const gs_real tau_b = m->mu_base * w_b + m->inv_ratio * (tau_mesh - t_f);
    st->block.follower_torque = t_f;
    st->base_speed = w_b;
    st->follower_speed = w_f;
    out->base_torque = tau_b + r->base_inertia * alpha_b;
    if (r->ripple) { /* at the step's mid angle: the mean over the step to second order */
        out->base_torque += ripple_torque(r, st->base_angle + GS_R(0.5) * r->dt * w_b);
    }
    out->base_port_torque = tau_b;
    out->follower_port_torque = tau_f;
    out->follower_acceleration = a_f;
    out->mesh_loss_power = tau_mesh * w_f;
    out->loss_power = out->mesh_loss_power + m->mu_base * w_b * w_b + m->mu_follower * w_f * w_f;
    out->port_power = tau_b * w_b + tau_f * w_f;
}

/* A base gear geared rigidly to the driven side, over a (sub-)step h from
 * base speed w, by backward Euler, with the meshing loss and the load's
 * Coulomb friction set-valued (physics.md 11, "Lossy meshes hold").
 *
 * Base-referred (a = omega_F/omega_B), the step's momentum balance is
 *   (M_b + M_f)*w' = y0 + x0 - h*|a|*(tau_mesh*sigma_F + F_C*sigma_F)
 * with y0 = J_B*w + h*drive (the base side), x0 = a*(J_F*a*w + h*push) (the
 * driven side), M_b = J_B + h*(mu_B + drive_slope), M_f = a^2*(J_F + h*mu_F).
 * Sliding in a direction sigma, the loss of physics.md 2 at full strength is
 * linear in T_F on each side of the power flow, so the balance is the minimum
 * (sigma = +1) or maximum (sigma = -1) of two affine functions of w', one per
 * power-flow direction: lambda*(x0 - sigma*hF) + y0 - sigma*hC0 -
 * (lambda*M_f + M_b)*w' with lambda = 1 - k_fd (the follower drives) or
 * 1 + k_bd (the base drives). Both decrease with w' (the first unless the
 * gear self-locks, lambda*M_f + M_b <= 0, when it never crosses zero). So:
 * the rig moves forward when both are positive at w' = 0, to the smaller
 * root; backward when both are negative, to the larger; otherwise neither
 * side can drive the other and it stays at rest. The two cases exclude each
 * other, and at rest some friction within the bounds holds it. No iteration,
 * no linearisation: the loss never moves the rig against its push. */
typedef struct {
    gs_real w;        /* base speed at the end */
    gs_real t_f;      /* net follower torque T_F */
    gs_real tau_mesh; /* the meshing loss, follower-referred */
    gs_real coulomb;  /* the load's Coulomb torque that acted (against the follower's motion) */
} geared_end;

static geared_end geared_solve(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real h, gs_real inv_h,
                               const geared_base_ *base, gs_real w, gs_real drive, gs_real push)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real a_abs = gs_abs(a);
    const gs_real w_f = a * w;
    const gs_real level = friction_level(r, w_f);
    /* Regularised, the load's friction is a damper (the secant of the smooth
     * law at the start speed, regularised_friction.h) on the end speed, an
     * addition to mu_F, and no set-valued bound. */
    gs_real follower_visc = r->geared_follower_visc;
    gs_real follower_mass = r->geared_follower_mass;
    gs_real bound = level;
    gs_real creep = GS_R(0.0);
    if (r->friction_regularised) {
        creep = gs_creep_damping(level, w_f, r->inv_load_speed_threshold);
        follower_visc += a * a * creep;
        follower_mass += h * a * a * creep;
        bound = GS_R(0.0);
    }
    /* In increments dw = w' - w, so that the momenta J*w, large against a
     * step's change, do not round the speed (float drifted by 1e-7 per step):
     * each piece is n + sigma-terms = (lambda*M_f + M_b)*dw with
     * n = lambda*(h*a*push - h*a^2*mu_F*w) + h*drive - h*(mu_B + slope)*w. */
    const gs_real hf = h * a_abs * bound;
    const gs_real hc = h * a_abs * law->c0;
    const gs_real follower = h * (a * push - follower_visc * w);
    const gs_real own = h * (drive - base->visc * w);
    const gs_real l_fd = GS_R(1.0) - law->k_fd;
    const gs_real l_bd = GS_R(1.0) + law->k_bd;
    const gs_real den_fd = l_fd * follower_mass + base->mass;
    const gs_real den_bd = l_bd * follower_mass + base->mass;
    gs_real w_end = GS_R(0.0);
    gs_real n_fd = l_fd * (follower - hf) + own - hc;
    gs_real n_bd = l_bd * (follower - hf) + own - hc;
    /* at w' = 0 (dw = -w) each piece is n + den*w */
    if (n_fd + den_fd * w > GS_R(0.0) && n_bd + den_bd * w > GS_R(0.0)) {
        gs_real dw = n_bd / den_bd;
        if (den_fd > GS_R(0.0)) {
            dw = gs_min(dw, n_fd / den_fd);
        }
        w_end = gs_max(w + dw, GS_R(0.0));
    } else {
        n_fd = l_fd * (follower + hf) + own + hc;
        n_bd = l_bd * (follower + hf) + own + hc;
        if (n_fd + den_fd * w < GS_R(0.0) && n_bd + den_bd * w < GS_R(0.0)) {
            gs_real dw = n_bd / den_bd;
            if (den_fd > GS_R(0.0)) {
                dw = gs_max(dw, n_fd / den_fd);
            }
            w_end = gs_min(w + dw, GS_R(0.0));
        }
    }
    const gs_real y0 = r->base_inertia * w + h * drive;
    geared_end e;
    e.w = w_end;
    const gs_real w_f_end = a * w_end;
    /* T_F without the Coulomb torque: push - mu_F*w_F' - J_F*(w_F' - w_F)/h */
    const gs_real t_f_free = push - m->mu_follower * w_f_end - r->driven_inertia * (w_f_end - w_f) * inv_h;
    if (w_f_end > GS_R(0.0) || w_f_end < GS_R(0.0)) {
        e.coulomb = r->friction_regularised ? creep * w_f_end : (w_f_end > GS_R(0.0) ? level : -level);
        e.t_f = t_f_free - e.coulomb;
        e.tau_mesh = gs_mesh_friction_torque(law, e.t_f, w_f_end);
    } else {
        /* At rest: T_B = y0/h holds the base; what a loss-free mesh would
         * need from the Coulomb friction to hold the driven side, the
         * Coulomb friction takes up to its level and the mesh the rest. */
        const gs_real hold = t_f_free + y0 * inv_h / a;
        e.coulomb = gs_clamp(hold, -bound, bound);
        e.t_f = t_f_free - e.coulomb;
        e.tau_mesh = hold - e.coulomb;
    }
    return e;
}

static void rigid_torque_driven(const rig_consts_ *r, gs_rig_state *st, const gs_mesh_friction_ *law, const gs_rig_input *in,
                                gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real w = st->base_speed;
    gs_real drive = in->base_torque;
    if (r->ripple) {
        /* at the start angle: with the angle advanced by the end speed this is
         * symplectic Euler, so the ripple's potential energy does not drift */
        drive -= ripple_torque(r, st->base_angle);
    }
    const gs_mesh_friction_ law_now = r->friction_regularised ? regularised_law(r, law, st->block.follower_torque, a * w)
                                                               : *law;
    const geared_end e =
        geared_solve(r, &law_now, r->dt, r->inv_dt, &r->geared_base, w, drive, in->load + r->load_offset);
    const gs_real w_f = a * e.w;
    const gs_real tau_b = m->mu_base * e.w + a * (e.tau_mesh - e.t_f);
    const gs_real tau_f = e.t_f + m->mu_follower * w_f;
    st->block.follower_torque = e.t_f;
    st->base_speed = e.w;
    st->follower_speed = w_f;
    out->base_torque = in->base_torque;
    out->base_port_torque = tau_b;
    out->follower_port_torque = tau_f;
    out->follower_acceleration = a * (e.w - w) * r->inv_dt;
    out->mesh_loss_power = e.tau_mesh * w_f;
    out->loss_power = out->mesh_loss_power + m->mu_base * e.w * e.w + m->mu_follower * w_f * w_f;
    out->port_power = tau_b * e.w + tau_f * w_f;
}

/* The compliant shaft (speed-driven base, rigid mesh): the drive turns at
 * the input speed, ramped linearly from the last sample over the step; a
 * spring k and damper c carry its torque to the base gear (J_B), which turns
 * the driven side through the rigid mesh. Per sub-step h the shaft follows
 * the implicit midpoint rule, with phi the twist (drive minus gear angle):
 *   phi' = phi + h*(w_d - (w + w')/2),  tau_s = k*(phi + phi')/2 + c*(w_d - (w + w')/2),
 * which is tau_s = k*phi + g*(w_d - w/2) - (g/2)*w' with g = k*h/2 + c: an
 * explicit torque and an implicit slope g/2 for geared_solve. The rule
 * keeps the undamped shaft's energy exactly and is stable at any k*h^2/J.
 * Its kinetic energy changes by the work at the mean speed (w + w')/2, so
 * the dissipative torques (viscous, friction, meshing loss), which act
 * against the end speed w', must not point along that mean: where they
 * would (the gear stops or reverses within the sub-step against a friction
 * holding it) the sub-step is solved again with the gear's angle advanced
 * by the end speed, phi' = phi + h*(w_d - w'), tau_s = k*(phi + phi')/2 +
 * c*(w_d - w'), whose kinetic energy changes by the work at w' and which is
 * passive for any friction (physics.md 11). */
static void compliant_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, gs_mesh_friction_ *law,
                           const gs_rig_input *in, gs_real w_d_start, gs_rig_output *out)
{
    const int law_per_substep = r->mesh.friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real h = r->compliance_h;
    const gs_real inv_h = r->inv_compliance_h;
    const gs_real g = r->compliance_gain;
    const gs_real push = in->load + r->load_offset;
    const gs_real w_f_start = st->follower_speed;
    const gs_real ramp = (in->base_speed - w_d_start) * r->inv_compliance_substeps;
    gs_real sum_shaft = GS_R(0.0), sum_tau_b = GS_R(0.0), sum_tau_f = GS_R(0.0);
    gs_real sum_mesh = GS_R(0.0), sum_loss = GS_R(0.0), sum_port = GS_R(0.0);
    for (int k = 0; k < r->compliance_substeps; ++k) {
        const gs_real w = st->base_speed;
        const gs_real phi = st->shaft_twist;
        if (law_per_substep && k > 0) {
            gs_mesh_friction_law(m, ctx, st->block.follower_torque, law);
        }
        /* the ramped drive speed at the sub-step's middle: its mean over the sub-step */
        const gs_real w_d = w_d_start + ramp * ((gs_real)k + GS_R(0.5));
        gs_real ripple = GS_R(0.0);
        if (r->ripple) {
            /* at the mid angle the start speed predicts: with the angle
             * advanced by the mean speed the map stays area-preserving */
            ripple = ripple_torque(r, st->base_angle + GS_R(0.5) * h * w);
        }
        const gs_real spring = r->stiffness * phi - ripple;
        const gs_mesh_friction_ law_now =
            r->friction_regularised ? regularised_law(r, law, st->block.follower_torque, a * w) : *law;
        geared_end e =
            geared_solve(r, &law_now, h, inv_h, &r->geared_base, w, spring + g * (w_d - GS_R(0.5) * w), push);
        gs_real w_adv = GS_R(0.5) * (w + e.w);
        /* the dissipative torque on the base gear (base-referred) opposes w',
         * and so the mean speed too, unless the gear stops or turns within
         * the sub-step */
        if (!(w * e.w > GS_R(0.0)) &&
            (m->mu_base * e.w + a * (e.coulomb + m->mu_follower * a * e.w + e.tau_mesh)) * w_adv < GS_R(0.0)) {
            e = geared_solve(r, &law_now, h, inv_h, &r->geared_base_end, w, spring + g * w_d, push);
            w_adv = e.w;
        }
        const gs_real phi_end = phi + h * (w_d - w_adv);
        const gs_real tau_shaft = GS_R(0.5) * r->stiffness * (phi + phi_end) + r->shaft_damping * (w_d - w_adv);
        const gs_real w_f = a * e.w;
        const gs_real tau_b = m->mu_base * e.w + a * (e.tau_mesh - e.t_f);
        const gs_real tau_f = e.t_f + m->mu_follower * w_f;
        st->block.follower_torque = e.t_f;
        st->shaft_twist = phi_end;
        st->base_speed = e.w;
        st->follower_speed = w_f;
        /* the angles with the speed the twist used */
        st->base_angle += h * w_adv;
        st->follower_position += h * a * w_adv;
        sum_shaft += tau_shaft;
        sum_tau_b += tau_b;
        sum_tau_f += tau_f;
        sum_mesh += e.tau_mesh * w_f;
        sum_loss += e.tau_mesh * w_f + m->mu_base * e.w * e.w + m->mu_follower * w_f * w_f;
        sum_port += tau_b * e.w + tau_f * w_f;
    }
    const gs_real inv_n = r->inv_compliance_substeps;
    out->base_torque = sum_shaft * inv_n;
    out->base_port_torque = sum_tau_b * inv_n;
    out->follower_port_torque = sum_tau_f * inv_n;
    out->mesh_loss_power = sum_mesh * inv_n;
    out->loss_power = sum_loss * inv_n;
    out->port_power = sum_port * inv_n;
    out->follower_acceleration = (st->follower_speed - w_f_start) / r->dt;
}

/* The contact's state inside a step: kept in locals over the sub-steps. */
typedef struct {
    gs_real x;   /* backlash position, m */
    gs_real f;   /* the last sub-step's contact force, N */
    int locked;  /* the static-contact lock */
} contact_state;

typedef struct {
    gs_real w_b, w_f; /* speeds at the end of the sub-step */
    gs_real f, f_spring, u;
} substep_end;

/* One sub-step with the follower moving freely from its free end speed
 * w_f_free (every torque but the contact included): the backward-Euler
 * contact. Changes only the lock flag. A speed-driven base has no kick
 * (base_kick = 0): its speed is imposed. */
static inline substep_end contact_moving(const rig_consts_ *r, contact_state *c, gs_real w_b_free, gs_real w_f_free)
{
    substep_end e;
    const gs_real u_free = r->mesh.base_radius * w_b_free - r->follower_lever * w_f_free;
    e.u = gs_contact_solve(&r->mesh, &r->contact, c->x, u_free, c->f, &c->locked, &e.f, &e.f_spring);
    e.w_f = w_f_free + r->follower_kick * e.f;
    e.w_b = w_b_free - r->base_kick * e.f;
    return e;
}

/* contact_moving with a friction torque `friction` (N*m or N, on the
 * follower) added to the free motion: sliding against the motion. */
static inline substep_end contact_sliding(const rig_consts_ *r, contact_state *c, gs_real w_b_free, gs_real momentum,
                                          gs_real friction)
{
    return contact_moving(r, c, w_b_free, (momentum + r->substep * friction) * r->inv_driven_inertia_sub);
}

/* One sub-step with the follower held at rest by its friction: the contact
 * sees the base alone. A speed-driven base imposes the tooth motion, so the
 * force is the law at the end of the sub-step; a torque-driven base solves
 * the backward-Euler contact with its own inertia. */
static inline substep_end contact_stuck(const rig_consts_ *r, contact_state *c, gs_real w_b_free)
{
    const gs_mesh_ *m = &r->mesh;
    substep_end e;
    const gs_real u_free = m->base_radius * w_b_free;
    if (r->base_drive == GS_BASE_SPEED_DRIVEN) {
        e.u = u_free;
        e.f = gs_contact_force(m, c->x + r->substep * u_free, u_free, &e.f_spring);
    } else {
        e.u = gs_contact_solve(m, &r->contact_stuck, c->x, u_free, c->f, &c->locked, &e.f, &e.f_spring);
    }
    e.w_f = GS_R(0.0);
    e.w_b = w_b_free - r->base_kick * e.f;
    return e;
}

/* How a sub-step's friction on the follower came out. */
typedef enum { FRICTION_NONE = 0, FRICTION_FORWARD, FRICTION_BACKWARD, FRICTION_STUCK } friction_mode;

/* One sub-step with a friction torque on the follower inside [-fwd, bwd]
 * (backward Euler, set-valued at rest): fwd is what opposes forward motion,
 * bwd backward motion, a negative bound none at all (the mesh self-locks
 * that way). momentum is J_F*w_F + h*(every other torque but the contact).
 * The joint contact-and-friction solution is one of three: sliding on in the
 * current direction, stuck, or sliding the other way; they are tried in that
 * order and the first consistent one is taken, so a sub-step costs one
 * contact solve while sliding on and at most three (five with the
 * static-contact lock, see below). *friction is the friction torque on the
 * follower. */
static substep_end substep_with_friction(const rig_consts_ *r, contact_state *c, gs_real w_f, gs_real w_b_free,
                                         gs_real momentum, gs_real fwd, gs_real bwd, gs_real *friction,
                                         friction_mode *mode)
{
    const int locked = c->locked;
    substep_end e;
    if (w_f > GS_R(0.0) && !(fwd < GS_R(0.0))) {
        *friction = -fwd;
        *mode = FRICTION_FORWARD;
        e = contact_sliding(r, c, w_b_free, momentum, *friction);
        if (!(e.w_f < GS_R(0.0))) { /* at exactly 0 any friction within the bounds is consistent */
            return e;
        }
        c->locked = locked;
    } else if (w_f < GS_R(0.0) && !(bwd < GS_R(0.0))) {
        *friction = bwd;
        *mode = FRICTION_BACKWARD;
        e = contact_sliding(r, c, w_b_free, momentum, *friction);
        if (!(e.w_f > GS_R(0.0))) {
            return e;
        }
        c->locked = locked;
    }
    e = contact_stuck(r, c, w_b_free);
    /* J_F*(0 - w_F) = h*(others + s*r_F*f + friction) */
    const gs_real needed = -(momentum * r->contact.inv_h + r->follower_lever * e.f);
    if ((fwd < GS_R(0.0) || needed >= -fwd) && (bwd < GS_R(0.0) || needed <= bwd)) {
        *friction = needed;
        *mode = FRICTION_STUCK;
        return e;
    }
    c->locked = locked;
    /* against the way the rest pushes (a finite bound that way: the other
     * was not exceeded) */
    if (needed < GS_R(0.0)) {
        *friction = -fwd;
        *mode = FRICTION_FORWARD;
    } else {
        *friction = bwd;
        *mode = FRICTION_BACKWARD;
    }
    e = contact_sliding(r, c, w_b_free, momentum, *friction);
    if (*friction * e.w_f <= GS_R(0.0)) {
        return e;
    }
    /* Only with the static-contact lock: the locked follower moves with the
     * base whatever its friction does, so the friction opposes that motion (a
     * fourth solve). If that releases the lock and the follower turns back,
     * or the mesh has no bound that way, the lock's hysteresis leaves no
     * consistent friction: the sub-step runs without it (a fifth solve),
     * which never does negative work. */
    c->locked = locked;
    if (e.w_f > GS_R(0.0) ? !(fwd < GS_R(0.0)) : !(bwd < GS_R(0.0))) {
        *friction = e.w_f > GS_R(0.0) ? -fwd : bwd;
        *mode = e.w_f > GS_R(0.0) ? FRICTION_FORWARD : FRICTION_BACKWARD;
        e = contact_sliding(r, c, w_b_free, momentum, *friction);
        if (*friction * e.w_f <= GS_R(0.0)) {
            return e;
        }
        c->locked = locked;
    }
    *friction = GS_R(0.0);
    *mode = FRICTION_NONE;
    return contact_moving(r, c, w_b_free, momentum * r->inv_driven_inertia_sub);
}

/* The meshing loss's bounds on the follower for the loss-free tooth torque
 * t_f0 = -s*r_F*f: the solution of T_F = T_F0 + tau_mesh(T_F) (physics.md
 * 4.6) with the law at full strength, for motion forward (*fwd) and backward
 * (*bwd). With a = sigma*T_F0 + c0: the follower drives (a >= 0) against
 * c0 + q_fd*a, unbounded where the mesh self-locks (q_fd < 0: *bound = -1);
 * the base drives (a < 0) against c0 - q_bd*a. */
static inline void mesh_bounds(const gs_mesh_friction_ *law, gs_real t_f0, gs_real *fwd, gs_real *bwd)
{
    const gs_real a_fwd = law->c0 + t_f0;
    const gs_real a_bwd = law->c0 - t_f0;
    if (a_fwd >= GS_R(0.0)) {
        *fwd = law->q_fd < GS_R(0.0) ? GS_R(-1.0) : law->c0 + law->q_fd * a_fwd;
    } else {
        *fwd = law->c0 - law->q_bd * a_fwd;
    }
    if (a_bwd >= GS_R(0.0)) {
        *bwd = law->q_fd < GS_R(0.0) ? GS_R(-1.0) : law->c0 + law->q_fd * a_bwd;
    } else {
        *bwd = law->c0 - law->q_bd * a_bwd;
    }
}

/* The follower's friction in one sub-step with backlash: the meshing loss
 * on the last contact force (physics.md 4.6), a set-valued friction on the
 * follower added to the load's Coulomb friction; it holds the follower at
 * rest within its bounds and opposes its motion beyond them. Returns the
 * sub-step's end and the meshing loss that acted (*tau_mesh, against the
 * follower's motion), and updates *t_f, the net follower torque T_F of the
 * law on that force the way the follower slides (the base load of the 2-D
 * table: a fixed point in steady contact; T_F0 at rest or where the mesh
 * self-locks). */
static substep_end substep_friction(const rig_consts_ *r, const gs_mesh_friction_ *law, contact_state *c, gs_real w_f,
                                    gs_real w_b_free, gs_real momentum, gs_real *tau_mesh, gs_real *t_f)
{
    gs_real mesh_fwd = GS_R(0.0), mesh_bwd = GS_R(0.0);
    const gs_real t_f0 = -r->follower_lever * c->f;
    *t_f = t_f0;
    if (law->lossy) {
        mesh_bounds(law, t_f0, &mesh_fwd, &mesh_bwd);
        if (w_f > GS_R(0.0) && !(mesh_fwd < GS_R(0.0))) {
            *t_f = t_f0 + mesh_fwd;
        } else if (w_f < GS_R(0.0) && !(mesh_bwd < GS_R(0.0))) {
            *t_f = t_f0 - mesh_bwd;
        }
    }
    /* Regularised, the load's friction bound is the smooth law at the
     * sub-step's start speed, F(v)*|tanh(4 v/v_th)|: zero at rest, so the
     * driven side creeps instead of sticking, and, solved jointly with the
     * contact like the Coulomb bound, it never reverses the motion. (A
     * damper applied before the contact, then the contact, created energy
     * where the contact turned the follower within the sub-step: fuzz
     * finding.) */
    const gs_real level = r->friction_regularised ? creep_level(r, w_f) : friction_level(r, w_f);
    const gs_real fwd = mesh_fwd < GS_R(0.0) ? mesh_fwd : mesh_fwd + level;
    const gs_real bwd = mesh_bwd < GS_R(0.0) ? mesh_bwd : mesh_bwd + level;
    gs_real friction = GS_R(0.0);
    friction_mode mode = FRICTION_NONE;
    substep_end e;
    if (fwd > GS_R(0.0) || fwd < GS_R(0.0) || bwd > GS_R(0.0) || bwd < GS_R(0.0)) {
        e = substep_with_friction(r, c, w_f, w_b_free, momentum, fwd, bwd, &friction, &mode);
    } else {
        e = contact_moving(r, c, w_b_free, momentum * r->inv_driven_inertia_sub);
    }
    /* the meshing loss's share of the friction (it acts on the follower as
     * -tau_mesh): all of it beyond the Coulomb level; at rest the Coulomb
     * friction holds what it can and the mesh the rest */
    switch (mode) {
    case FRICTION_FORWARD:
        *tau_mesh = mesh_fwd;
        break;
    case FRICTION_BACKWARD:
        *tau_mesh = -mesh_bwd;
        break;
    case FRICTION_STUCK:
        *tau_mesh = gs_clamp(friction, -level, level) - friction;
        break;
    case FRICTION_NONE:
        *tau_mesh = GS_R(0.0);
        break;
    }
    return e;
}

static void backlash_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, gs_mesh_friction_ *law,
                          const gs_rig_input *in, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const int n = r->substeps;
    const gs_real h = r->substep;
    const int speed_driven = r->base_drive == GS_BASE_SPEED_DRIVEN;
    /* no friction on the follower at all: every sub-step is one contact solve */
    const int free_follower = !law->lossy && !r->stribeck && !(r->load_coulomb > GS_R(0.0));
    /* the 2-D table reads its efficiency at the last sub-step's base load */
    const int law_per_substep = m->friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    const gs_real w_b_start = st->base_speed;
    const gs_real w_f_start = st->follower_speed;
    const gs_real push_h = h * (in->load + r->load_offset);
    /* the held speed ramps linearly from the last sample to this one */
    const gs_real ramp = (in->base_speed - w_b_start) * r->inv_substeps;
    gs_real w_b = w_b_start, w_f = w_f_start;
    gs_real theta_b = st->base_angle, x_f = st->follower_position;
    gs_real t_f = st->block.follower_torque;
    contact_state c = {st->block.backlash_position, st->block.contact_force, st->block.contact_locked};
    gs_real sum_f = GS_R(0.0), sum_fu = GS_R(0.0), sum_su = GS_R(0.0), sum_w_b = GS_R(0.0), sum_w_f = GS_R(0.0);
    gs_real sum_visc = GS_R(0.0), sum_tau_mesh = GS_R(0.0), sum_mesh = GS_R(0.0), sum_ripple = GS_R(0.0);
    gs_real motor_h = h * in->base_torque;
    if (r->ripple && !speed_driven) {
        /* a torque-driven base: at the step's start angle, held over the
         * sub-steps (symplectic Euler over the step, as in the rigid rig) */
        motor_h -= h * ripple_torque(r, theta_b);
    }
    for (int k = 0; k < n; ++k) {
        gs_real w_b_free;
        if (speed_driven) {
            w_b_free = k + 1 < n ? w_b_start + ramp * (gs_real)(k + 1) : in->base_speed;
            if (r->ripple) { /* at the sub-step's mid angle */
                sum_ripple += ripple_torque(r, theta_b + GS_R(0.5) * h * w_b_free);
            }
        } else {
            w_b_free = (r->base_inertia * w_b + motor_h) * r->inv_base_inertia_sub;
        }
        const gs_real momentum = r->driven_inertia * w_f + push_h;
        substep_end e;
        gs_real tau_mesh = GS_R(0.0);
        if (free_follower) {
            e = contact_moving(r, &c, w_b_free, momentum * r->inv_driven_inertia_sub);
        } else {
            if (law_per_substep && k > 0) {
                gs_mesh_friction_law(m, ctx, t_f, law);
            }
            if (r->friction_regularised) {
                const gs_mesh_friction_ law_now = regularised_law(r, law, t_f, w_f);
                e = substep_friction(r, &law_now, &c, w_f, w_b_free, momentum, &tau_mesh, &t_f);
            } else {
                e = substep_friction(r, law, &c, w_f, w_b_free, momentum, &tau_mesh, &t_f);
            }
        }
        /* x moves with the relative speed the contact was solved for: the end
         * speeds give it back only to rounding, and that rounding times the
         * spring force (held teeth: large force, u = 0) would create energy */
        c.x += h * e.u;
        c.f = e.f;
        w_b = e.w_b;
        w_f = e.w_f;
        theta_b += h * w_b;
        x_f += h * w_f;
        /* Powers paired with the end speeds like every port term, and the
         * friction never does negative work. The ports take
         * tau_B*w_B + tau_F*w_F = f*(r_B*w_B - s*r_F*w_F) + mesh + viscous,
         * with the relative speed the contact was solved for: the difference
         * of the two port terms, each the force times a pitch-line speed,
         * would round by eps times those, which locked teeth exchanging
         * kilojoules within a step turned into millijoules (float fuzz
         * finding). */
        sum_f += e.f;
        sum_fu += e.f * e.u;
        sum_su += e.f_spring * e.u;
        sum_w_b += w_b;
        sum_w_f += w_f;
        sum_visc += m->mu_base * w_b * w_b + m->mu_follower * w_f * w_f;
        sum_tau_mesh += tau_mesh;
        sum_mesh += tau_mesh * w_f;
    }
    st->block.backlash_position = c.x;
    st->block.contact_force = c.f;
    st->block.contact_locked = c.locked;
    st->block.follower_torque = free_follower ? -r->follower_lever * c.f : t_f;
    st->base_speed = w_b;
    st->follower_speed = w_f;
    st->base_angle = theta_b;
    st->follower_position = x_f;
    const gs_real inv_n = r->inv_substeps;
    out->base_port_torque = (m->base_radius * sum_f + m->mu_base * sum_w_b) * inv_n;
    out->base_torque = speed_driven ? out->base_port_torque + r->base_inertia * st->base_acceleration
                                       : in->base_torque;
    if (r->ripple && speed_driven) {
        out->base_torque += sum_ripple * inv_n;
    }
    out->follower_port_torque = (sum_tau_mesh - r->follower_lever * sum_f + m->mu_follower * sum_w_f) * inv_n;
    out->mesh_loss_power = sum_mesh * inv_n;
    out->loss_power = (sum_mesh + sum_visc + sum_fu - sum_su) * inv_n;
    out->port_power = (sum_fu + sum_mesh + sum_visc) * inv_n;
    out->contact_force = sum_f * inv_n;
    out->follower_acceleration = (w_f - w_f_start) * r->inv_dt;
}

void gs_rig_step(const gs_rig_consts *consts, gs_rig_state *st, const gs_rig_input *in,
                 gs_rig_output *out)
{
    const rig_consts_ *r = consts_of(consts);
    const gs_mesh_ *m = &r->mesh;
    const int from_input = r->temperature_source == GS_TEMPERATURE_FROM_INPUT;
    gs_real w_drive_start = st->base_speed_sample;
    if (r->base_drive == GS_BASE_SPEED_DRIVEN) {
        const gs_real w_in = in->base_speed;
        if (!st->started) {
            /* the first sample sets the speeds: no acceleration, teeth moving together */
            st->base_speed_sample = w_in;
            st->base_speed = w_in;
            st->follower_speed = m->inv_ratio * w_in;
            w_drive_start = w_in;
        }
        const gs_real raw = (w_in - st->base_speed_sample) / r->dt;
        st->base_acceleration += r->accel_gain * (raw - st->base_acceleration);
        st->base_speed_sample = w_in;
    }
    st->started = 1;
    gs_loss_ctx_ ctx_now;
    const gs_loss_ctx_ *ctx = &r->loss_ctx;
    if (!r->loss_static) {
        gs_mesh_loss_prepare(m, from_input ? in->measured_temperature : st->block.temperature, &ctx_now);
        ctx = &ctx_now;
    }
    out->contact_force = GS_R(0.0);
    if (m->backlash || r->compliant || r->base_drive == GS_BASE_TORQUE_DRIVEN) {
        /* a free driven side or base gear: the meshing loss as a friction element */
        gs_mesh_friction_ law = r->loss_law;
        if (!r->loss_static) {
            gs_mesh_friction_law(m, ctx, st->block.follower_torque, &law);
        }
        if (m->backlash) {
            backlash_step(r, st, ctx, &law, in, out);
        } else if (r->compliant) {
            compliant_step(r, st, ctx, &law, in, w_drive_start, out);
        } else {
            rigid_torque_driven(r, st, &law, in, out);
            st->base_angle += r->dt * st->base_speed;
            st->follower_position += r->dt * st->follower_speed;
        }
    } else {
        rigid_speed_driven(r, st, ctx, in, w_drive_start, out);
        st->base_angle += r->dt * st->base_speed;
        st->follower_position += r->dt * st->follower_speed;
        if (r->speed_ramp) { /* the speeds reported: this sample's, at the step's end */
            st->base_speed = in->base_speed;
            st->follower_speed = m->inv_ratio * in->base_speed;
        }
    }
    if (from_input) {
        st->block.temperature = in->measured_temperature;
    } else {
        gs_mesh_thermal_step(m, &st->block, r->dt, out->loss_power, GS_R(0.0), in->ambient_temperature,
                             r->inv_thermal_resistance);
    }
    out->base_speed = st->base_speed;
    out->base_angle = st->base_angle;
    out->follower_speed = st->follower_speed;
    out->follower_position = st->follower_position;
    out->contact_energy = m->backlash ? gs_contact_energy(m, st->block.backlash_position) : GS_R(0.0);
    out->temperature = st->block.temperature;
    out->backlash_position = st->block.backlash_position;
}

void gs_rig_get_info(const gs_rig_consts *consts, gs_rig_info *info)
{
    const rig_consts_ *r = consts_of(consts);
    info->contact_substeps = r->substeps;
    info->contact_h_omega_n = r->contact_h_omega_n;
    info->substeps_capped = r->substeps_capped;
    info->follower_per_base = r->mesh.inv_ratio;
    info->compliance_substeps = r->compliance_substeps;
    info->compliance_h_omega_n = r->compliance_h_omega_n;
}

void gs_rig_run(const gs_rig_consts *consts, gs_rig_state *state, size_t n, const gs_rig_input *in,
                gs_rig_output *out)
{
    for (size_t i = 0; i < n; ++i) {
        gs_rig_step(consts, state, &in[i], &out[i]);
    }
}

/* ---- The field tables of gearsim/fields.h, for generic readers (Python, tools). */
#define GS_IS_INT_gs_real 0
#define GS_IS_INT_int 1
#define GS_INPUT_INFO_(type, name, gear_unit, rack_unit, doc) \
    {#name, gear_unit, rack_unit, doc, offsetof(gs_rig_input, name), GS_IS_INT_##type},
#define GS_OUTPUT_INFO_(type, name, gear_unit, rack_unit, doc) \
    {#name, gear_unit, rack_unit, doc, offsetof(gs_rig_output, name), GS_IS_INT_##type},
#define GS_BLOCK_STATE_INFO_(type, name, gear_unit, rack_unit, doc) \
    {#name, gear_unit, rack_unit, doc, offsetof(gs_rig_state, block.name), GS_IS_INT_##type},
#define GS_RIG_STATE_INFO_(type, name, gear_unit, rack_unit, doc) \
    {#name, gear_unit, rack_unit, doc, offsetof(gs_rig_state, name), GS_IS_INT_##type},

const gs_field_info gs_rig_input_info[GS_RIG_INPUT_FIELDS] = {GS_RIG_INPUT_LIST(GS_INPUT_INFO_)};
const gs_field_info gs_rig_output_info[GS_RIG_OUTPUT_FIELDS] = {GS_RIG_OUTPUT_LIST(GS_OUTPUT_INFO_)};
const gs_field_info gs_rig_state_info[GS_RIG_STATE_FIELDS] = {
    GS_BLOCK_STATE_LIST(GS_BLOCK_STATE_INFO_) GS_RIG_STATE_LIST(GS_RIG_STATE_INFO_)};

/* rig.c - a block between a driven base shaft and an inertia (physics.md 11).
 *
 * Three step paths share the mesh of mesh.h:
 *  - rigid mesh, speed-driven base: causal form A; the follower's inertia
 *    torque uses the filtered backward-difference base acceleration;
 *  - rigid mesh, torque-driven base: one degree of freedom; the meshing loss
 *    is linearised around the last follower torque (two fixed passes), the
 *    viscous terms and the load's Coulomb friction are implicit;
 *  - backlash: the follower (and a torque-driven base) carry their own
 *    speeds; the contact is integrated by backward Euler in a fixed number
 *    of sub-steps, viscous terms implicit, the meshing loss evaluated at the
 *    start of each sub-step from the last contact force.
 *
 * Friction on a free driven side (the load's Coulomb friction, and with
 * backlash the meshing loss) is one mechanism: backward Euler on a friction
 * bounded by its magnitude (a velocity projection). It stops the driven side
 * within a step when the bound can, holds it at rest while the applied torque
 * stays within the Coulomb friction, and never reverses it. */
#include <string.h>

#include "gearsim/rig.h"
#include "blocks.h"
#include "gs_math.h"
#include "mesh.h"
#include "regularised_friction.h"
#include "validate.h"

#define LINEARISATION_PASSES 2

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
    int friction_regularised;      /* a free driven side's friction is F(v)*tanh(4 v/v_th) */
    int speed_ramp;                /* speed-driven rigid rig: torques at the step's mean speed */
    gs_real load_offset;
    gs_real inv_thermal_resistance;
    gs_real accel_gain;            /* dt/(tau + dt) */
    gs_real substep;               /* h = dt/substeps, s */
    gs_real inv_substeps;          /* 1/substeps */
    gs_real inv_driven_inertia_sub;/* 1/(J_F + h*mu_F): the implicit viscous term */
    gs_real inv_base_inertia_sub;  /* 1/(J_B + h*mu_B) (torque-driven base) */
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

GS_STATIC_ASSERT_(rig_consts_size, sizeof(gs_rig_consts) >= sizeof(rig_consts_));

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

/* Compliance: the spring turns a base gear of its own (base_inertia >= 0; 0
 * puts the spring at the mesh) that only a speed-driven base on a rigid mesh
 * provides in this version. */
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
    return GS_OK; /* base_inertia >= 0: checked with the drive; 0 puts the spring at the mesh */
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
    r->inv_compliance_substeps = GS_R(1.0) / (gs_real)r->compliance_substeps;
    r->compliance_gain = GS_R(0.5) * r->stiffness * r->compliance_h + r->shaft_damping;
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

/* Backward Euler on a speed with a friction of magnitude <= bound (both in
 * speed units over the step): w_free is the end speed without the friction.
 * The friction stops the motion if it can (the speed ends at exactly 0),
 * else it slides against the motion; it never reverses it. */
static gs_real friction_project(gs_real w_free, gs_real bound)
{
    if (gs_abs(w_free) <= bound) {
        return GS_R(0.0);
    }
    return w_free > GS_R(0.0) ? w_free - bound : w_free + bound;
}

static void rigid_speed_driven(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                               gs_real w_prev, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    /* the step's mean speed under a linear ramp, or this sample */
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

/* A base gear of inertia J_B geared rigidly to the driven side, over a
 * (sub-)step h from speed w: the end speed and the net follower torque T_F
 * (seeded with t_f). drive is the explicit torque on the base gear;
 * drive_slope*w_end is taken off it implicitly (the compliant shaft's share
 * that depends on the end speed; 0 for a motor). */
typedef struct {
    gs_real w;   /* base speed at the end */
    gs_real dw;  /* its change */
    gs_real t_f; /* T_F */
} geared_base_end;

static geared_base_end geared_base_step(const rig_consts_ *r, const gs_loss_ctx_ *ctx, gs_real h, gs_real w, gs_real t_f,
                                        gs_real drive, gs_real drive_slope, gs_real push)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    /* the friction level at the start speed (Stribeck: explicit in the speed) */
    const gs_real level = friction_level(r, a * w);
    /* regularised: the friction is a damper taken at the start speed, never a bound */
    const gs_real creep = r->friction_regularised ? gs_creep_damping(level, a * w, r->inv_load_speed_threshold)
                                                  : GS_R(0.0);
    geared_base_end e = {w, GS_R(0.0), t_f};
    for (int pass = 0; pass < LINEARISATION_PASSES; ++pass) {
        /* tau_mesh ~ m0 + m1*T_F; J_B dw/h = drive - mu_B w' - a (tau_mesh - T_F) with
         * T_F = push + coulomb - J_F a dw/h - mu_F a w'. (1 - m1) >= 0 unless the
         * gear self-locks. The Coulomb torque on the follower, in [-F, F] with
         * F the friction level, reaches the base through q: backward Euler
         * with a set-valued sign. */
        gs_real m0;
        gs_real m1;
        gs_mesh_loss_linearize(m, ctx, e.t_f, a * e.w, &m0, &m1);
        const gs_real q = a * gs_max(GS_R(1.0) - m1, GS_R(0.0));
        const gs_real visc = m->mu_base + q * (m->mu_follower + creep) * a + drive_slope;
        const gs_real denominator = (r->base_inertia + q * a * r->driven_inertia) / h + visc;
        const gs_real w_free = w + (drive - a * m0 + q * push - visc * w) / denominator;
        const gs_real bound = r->friction_regularised ? GS_R(0.0) : gs_abs(q) * level / denominator;
        e.w = friction_project(w_free, bound);
        e.dw = e.w - w;
        /* the Coulomb torque that gives w_next: -F_C*sign(w_F) sliding, what holds it at rest */
        const gs_real coulomb = bound > GS_R(0.0) ? (e.w - w_free) * denominator / q : GS_R(0.0);
        e.t_f = push + coulomb - creep * a * e.w - r->driven_inertia * a * e.dw / h - m->mu_follower * a * e.w;
    }
    return e;
}

static void rigid_torque_driven(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                                gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real h = r->dt;
    const gs_real a = m->inv_ratio;
    const gs_real push = in->load + r->load_offset;
    gs_real drive = in->base_torque;
    if (r->ripple) {
        /* at the start angle: with the angle advanced by the end speed this is
         * symplectic Euler, so the ripple's potential energy does not drift */
        drive -= ripple_torque(r, st->base_angle);
    }
    const geared_base_end e = geared_base_step(r, ctx, h, st->base_speed, st->block.follower_torque, drive,
                                               GS_R(0.0), push);
    const gs_real w_next = e.w;
    const gs_real dw = e.dw;
    const gs_real t_f = e.t_f;
    const gs_real w_f = a * w_next;
    const gs_real tau_mesh = gs_mesh_loss_torque(m, ctx, t_f, w_f);
    const gs_real tau_b = m->mu_base * w_next + a * (tau_mesh - t_f);
    const gs_real tau_f = t_f + m->mu_follower * w_f;
    st->block.follower_torque = t_f;
    st->base_speed = w_next;
    st->follower_speed = w_f;
    out->base_torque = in->base_torque;
    out->base_port_torque = tau_b;
    out->follower_port_torque = tau_f;
    out->follower_acceleration = a * dw / h;
    out->mesh_loss_power = tau_mesh * w_f;
    out->loss_power = out->mesh_loss_power + m->mu_base * w_next * w_next + m->mu_follower * w_f * w_f;
    out->port_power = tau_b * w_next + tau_f * w_f;
}

/* The compliant shaft (speed-driven base, rigid mesh): the drive turns at
 * the input speed, ramped linearly from the last sample over the step; a
 * spring k and damper c carry its torque to the base gear (J_B), which turns
 * the driven side through the rigid mesh. Per sub-step h the shaft follows
 * the implicit midpoint rule, with phi the twist (drive minus gear angle):
 *   phi' = phi + h*(w_d - (w + w')/2),  tau_s = k*(phi + phi')/2 + c*(w_d - (w + w')/2),
 * which is tau_s = k*phi + g*(w_d - w/2) - (g/2)*w' with g = k*h/2 + c: an
 * explicit torque and an implicit slope g/2 for geared_base_step. The rule
 * keeps the undamped shaft's energy exactly and is stable at any k*h^2/J. */
static void compliant_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                           gs_real w_d_start, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real h = r->compliance_h;
    const gs_real g = r->compliance_gain;
    const gs_real push = in->load + r->load_offset;
    const gs_real w_f_start = st->follower_speed;
    gs_real sum_shaft = GS_R(0.0), sum_tau_b = GS_R(0.0), sum_tau_f = GS_R(0.0);
    gs_real sum_mesh = GS_R(0.0), sum_loss = GS_R(0.0), sum_port = GS_R(0.0);
    for (int k = 0; k < r->compliance_substeps; ++k) {
        const gs_real w = st->base_speed;
        const gs_real phi = st->shaft_twist;
        /* the ramped drive speed at the sub-step's middle: its mean over the sub-step */
        const gs_real w_d =
            w_d_start + (in->base_speed - w_d_start) * (((gs_real)k + GS_R(0.5)) * r->inv_compliance_substeps);
        gs_real drive = r->stiffness * phi + g * (w_d - GS_R(0.5) * w);
        if (r->ripple) {
            /* at the mid angle the start speed predicts: with the angle
             * advanced by the mean speed the map stays area-preserving */
            drive -= ripple_torque(r, st->base_angle + GS_R(0.5) * h * w);
        }
        const geared_base_end e = geared_base_step(r, ctx, h, w, st->block.follower_torque, drive, GS_R(0.5) * g, push);
        const gs_real w_mid = GS_R(0.5) * (w + e.w);
        const gs_real phi_end = phi + h * (w_d - w_mid);
        const gs_real tau_shaft = GS_R(0.5) * r->stiffness * (phi + phi_end) + r->shaft_damping * (w_d - w_mid);
        const gs_real w_f = a * e.w;
        const gs_real tau_mesh = gs_mesh_loss_torque(m, ctx, e.t_f, w_f);
        const gs_real tau_b = m->mu_base * e.w + a * (tau_mesh - e.t_f);
        const gs_real tau_f = e.t_f + m->mu_follower * w_f;
        st->block.follower_torque = e.t_f;
        st->shaft_twist = phi_end;
        st->base_speed = e.w;
        st->follower_speed = w_f;
        /* the angles with the mean speed, like the twist */
        st->base_angle += h * w_mid;
        st->follower_position += h * a * w_mid;
        sum_shaft += tau_shaft;
        sum_tau_b += tau_b;
        sum_tau_f += tau_f;
        sum_mesh += tau_mesh * w_f;
        sum_loss += tau_mesh * w_f + m->mu_base * e.w * e.w + m->mu_follower * w_f * w_f;
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

typedef struct {
    gs_real w_b, w_f; /* speeds at the end of the sub-step */
    gs_real f, f_spring, u;
} substep_end;

/* The base's end speed for a contact force f over the sub-step. */
static inline gs_real base_end_speed(const rig_consts_ *r, gs_real w_b_free, gs_real f)
{
    return r->base_drive == GS_BASE_SPEED_DRIVEN
               ? w_b_free
               : w_b_free - r->substep * r->mesh.base_radius * f * r->inv_base_inertia_sub;
}

/* One sub-step with the follower moving freely from its free end speed
 * w_f_free (every torque but the contact included): the backward-Euler
 * contact. Changes only the lock flag. */
static inline substep_end contact_moving(const rig_consts_ *r, gs_rig_state *st, gs_real w_b_free, gs_real w_f_free)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real sr_f = m->direction * m->follower_radius;
    substep_end e;
    const gs_real u_free = m->base_radius * w_b_free - sr_f * w_f_free;
    e.u = gs_contact_solve(m, &st->block, &r->contact, st->block.backlash_position, u_free, &e.f, &e.f_spring);
    e.w_f = w_f_free + r->substep * sr_f * e.f * r->inv_driven_inertia_sub;
    e.w_b = base_end_speed(r, w_b_free, e.f);
    return e;
}

/* contact_moving with a friction torque `friction` (N*m or N, on the
 * follower) added to the free motion: sliding against the motion. */
static inline substep_end contact_sliding(const rig_consts_ *r, gs_rig_state *st, gs_real w_b_free, gs_real momentum, gs_real friction)
{
    return contact_moving(r, st, w_b_free, (momentum + r->substep * friction) * r->inv_driven_inertia_sub);
}

/* One sub-step with the follower held at rest by its friction: the contact
 * sees the base alone. A speed-driven base imposes the tooth motion, so the
 * force is the law at the end of the sub-step; a torque-driven base solves
 * the backward-Euler contact with its own inertia. */
static inline substep_end contact_stuck(const rig_consts_ *r, gs_rig_state *st, gs_real w_b_free)
{
    const gs_mesh_ *m = &r->mesh;
    substep_end e;
    const gs_real u_free = m->base_radius * w_b_free;
    if (r->base_drive == GS_BASE_SPEED_DRIVEN) {
        e.u = u_free;
        e.f = gs_contact_force(m, st->block.backlash_position + r->substep * u_free, u_free, &e.f_spring);
    } else {
        e.u = gs_contact_solve(m, &st->block, &r->contact_stuck, st->block.backlash_position, u_free, &e.f, &e.f_spring);
    }
    e.w_f = GS_R(0.0);
    e.w_b = base_end_speed(r, w_b_free, e.f);
    return e;
}

/* One sub-step with a friction torque of magnitude <= bound on the follower
 * (backward Euler, set-valued at rest): momentum is J_F*w_F + h*(every other
 * torque but the contact). The joint contact-and-friction solution is one of
 * three: sliding on in the current direction, stuck, or sliding the other
 * way; they are tried in that order and the first consistent one is taken,
 * so a sub-step costs one contact solve while sliding on and at most three
 * (five with the static-contact lock, see below). *friction is the friction
 * torque on the follower. */
static substep_end substep_with_friction(const rig_consts_ *r, gs_rig_state *st, gs_real w_b_free, gs_real momentum, gs_real bound,
                                         gs_real *friction)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real w_f = st->follower_speed;
    const int locked = st->block.contact_locked;
    substep_end e;
    if (!(bound > GS_R(0.0))) {
        *friction = GS_R(0.0);
        return contact_moving(r, st, w_b_free, momentum * r->inv_driven_inertia_sub);
    }
    if (w_f > GS_R(0.0) || w_f < GS_R(0.0)) {
        *friction = -gs_sign(w_f) * bound;
        e = contact_sliding(r, st, w_b_free, momentum, *friction);
        if (*friction * e.w_f <= GS_R(0.0)) { /* at exactly 0 any friction within the bound is consistent */
            return e;
        }
        st->block.contact_locked = locked;
    }
    e = contact_stuck(r, st, w_b_free);
    /* J_F*(0 - w_F) = h*(others + s*r_F*f + friction) */
    const gs_real needed = -(momentum * r->contact.inv_h + m->direction * m->follower_radius * e.f);
    if (gs_abs(needed) <= bound) {
        *friction = needed;
        return e;
    }
    st->block.contact_locked = locked;
    *friction = needed < GS_R(0.0) ? -bound : bound; /* against the way the rest pushes */
    e = contact_sliding(r, st, w_b_free, momentum, *friction);
    if (*friction * e.w_f <= GS_R(0.0)) {
        return e;
    }
    /* Only with the static-contact lock: the locked follower moves with the
     * base whatever its friction does, so the friction opposes that motion (a
     * fourth solve). If that releases the lock and the follower turns back,
     * the lock's hysteresis leaves no consistent friction: the sub-step runs
     * without it (a fifth solve), which never does negative work. */
    st->block.contact_locked = locked;
    *friction = -gs_sign(e.w_f) * bound;
    e = contact_sliding(r, st, w_b_free, momentum, *friction);
    if (*friction * e.w_f <= GS_R(0.0)) {
        return e;
    }
    st->block.contact_locked = locked;
    *friction = GS_R(0.0);
    return contact_moving(r, st, w_b_free, momentum * r->inv_driven_inertia_sub);
}

static void backlash_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                          gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const int n = r->substeps;
    const gs_real h = r->substep;
    const gs_real r_b = m->base_radius;
    const gs_real sr_f = m->direction * m->follower_radius;
    const int speed_driven = r->base_drive == GS_BASE_SPEED_DRIVEN;
    const gs_real w_b_start = st->base_speed;
    const gs_real w_f_start = st->follower_speed;
    const gs_real push = in->load + r->load_offset;
    gs_real sum_tau_b = GS_R(0.0), sum_tau_f = GS_R(0.0), sum_mesh = GS_R(0.0), sum_loss = GS_R(0.0);
    gs_real sum_port = GS_R(0.0), sum_f = GS_R(0.0), sum_ripple = GS_R(0.0);
    for (int k = 0; k < n; ++k) {
        const gs_real w_f = st->follower_speed;
        /* The meshing loss on the last contact force (physics.md 4.6) acts as
         * a friction on the follower, bounded like the load's Coulomb
         * friction. Only its part that opposes the motion is applied: the
         * Simscape smoothing's active sliver near zero power would be an
         * explicit torque proportional to the contact force, which a stiff
         * contact on a light follower turns into a divergence. */
        const gs_real t_f0 = -sr_f * st->block.contact_force;
        const gs_real tau_law = gs_mesh_loss_from_tooth(m, ctx, t_f0, w_f, st->block.follower_torque);
        st->block.follower_torque = t_f0 + tau_law;
        const gs_real mesh_friction = tau_law * w_f > GS_R(0.0) ? gs_abs(tau_law) : GS_R(0.0);
        gs_real momentum = r->driven_inertia * w_f + h * push;
        gs_real bound = mesh_friction;
        if (r->friction_regularised) { /* a damper on the free motion, before the contact */
            const gs_real c = gs_creep_damping(friction_level(r, w_f), w_f, r->inv_load_speed_threshold);
            momentum += h * gs_creep_torque(c, momentum, r->driven_inertia + h * m->mu_follower, h);
        } else {
            bound += friction_level(r, w_f);
        }
        /* the held speed ramps linearly from the last sample to this one */
        gs_real w_b_free =
            speed_driven ? w_b_start + (in->base_speed - w_b_start) * ((gs_real)(k + 1) * r->inv_substeps)
                         : (r->base_inertia * st->base_speed + h * in->base_torque) * r->inv_base_inertia_sub;
        if (r->ripple) {
            /* a held speed: at the sub-step's mid angle; a torque-driven base:
             * at the start angle (symplectic Euler, as in the rigid rig) */
            const gs_real tau_ripple =
                ripple_torque(r, speed_driven ? st->base_angle + GS_R(0.5) * h * w_b_free : st->base_angle);
            sum_ripple += tau_ripple;
            if (!speed_driven) {
                w_b_free -= h * tau_ripple * r->inv_base_inertia_sub;
            }
        }
        gs_real friction;
        const substep_end e = substep_with_friction(r, st, w_b_free, momentum, bound, &friction);
        /* the meshing loss's share of the friction (it acts on the follower as -tau_mesh) */
        const gs_real tau_mesh = bound > GS_R(0.0) ? -friction * (mesh_friction / bound) : GS_R(0.0);
        /* x moves with the relative speed the contact was solved for: the end
         * speeds give it back only to rounding, and that rounding times the
         * spring force (held teeth: large force, u = 0) would create energy */
        st->block.backlash_position += h * e.u;
        st->block.contact_force = e.f;
        st->base_speed = e.w_b;
        st->follower_speed = e.w_f;
        st->base_angle += h * e.w_b;
        st->follower_position += h * e.w_f;
        const gs_real tau_b = r_b * e.f + m->mu_base * e.w_b;
        const gs_real tau_f = -sr_f * e.f + tau_mesh + m->mu_follower * e.w_f;
        /* paired with the end speeds like every port term: the power identity
         * of the sub-step is exact, and the friction never does negative work */
        const gs_real p_mesh = tau_mesh * e.w_f;
        sum_tau_b += tau_b;
        sum_tau_f += tau_f;
        sum_mesh += p_mesh;
        sum_loss += p_mesh + m->mu_base * e.w_b * e.w_b + m->mu_follower * e.w_f * e.w_f
                    + (e.f - e.f_spring) * e.u;
        sum_port += tau_b * e.w_b + tau_f * e.w_f;
        sum_f += e.f;
    }
    const gs_real inv_n = r->inv_substeps;
    out->base_port_torque = sum_tau_b * inv_n;
    out->base_torque = speed_driven ? out->base_port_torque + r->base_inertia * st->base_acceleration
                                       : in->base_torque;
    if (r->ripple && speed_driven) {
        out->base_torque += sum_ripple * inv_n;
    }
    out->follower_port_torque = sum_tau_f * inv_n;
    out->mesh_loss_power = sum_mesh * inv_n;
    out->loss_power = sum_loss * inv_n;
    out->port_power = sum_port * inv_n;
    out->contact_force = sum_f * inv_n;
    out->follower_acceleration = (st->follower_speed - w_f_start) / r->dt;
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
    gs_loss_ctx_ ctx;
    gs_mesh_loss_prepare(m, from_input ? in->measured_temperature : st->block.temperature, &ctx);
    out->contact_force = GS_R(0.0);
    if (m->backlash) {
        backlash_step(r, st, &ctx, in, out);
    } else if (r->compliant) {
        compliant_step(r, st, &ctx, in, w_drive_start, out);
    } else {
        if (r->base_drive == GS_BASE_SPEED_DRIVEN) {
            rigid_speed_driven(r, st, &ctx, in, w_drive_start, out);
        } else {
            rigid_torque_driven(r, st, &ctx, in, out);
        }
        st->base_angle += r->dt * st->base_speed;
        st->follower_position += r->dt * st->follower_speed;
        if (r->speed_ramp && r->base_drive == GS_BASE_SPEED_DRIVEN) { /* the speeds reported: at the step's end */
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

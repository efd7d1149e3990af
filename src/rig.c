/* rig.c - the rig's parameters and lifecycle (physics.md 11): defaults,
 * validation, the constants init derives from them, init, reset, info, run,
 * and gs_rig_step, which takes the speed sample, prepares the meshing loss
 * and hands the step to its path (rig_internal.h: rigid, compliant shaft,
 * backlash). */
#include <string.h>

#include "rig_internal.h"
#include "rig_geared.h"
#include "blocks.h"
#include "gs_math.h"
#include "mesh_law.h"
#include "validate.h"

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
        if ((s = gs_check_nonnegative(err, p->ripple_revolution_amplitude_Nm[i], "ripple_revolution_amplitude")) !=
                GS_OK ||
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
    return m->follower_radius * m->follower_radius / (r->driven_inertia + h * m->mu_follower) + base_inverse_mass(r, h);
}

/* Smallest count with h*omega_n <= GS_AUTO_H_OMEGA_N_MAX, capped: backward
 * Euler is stable and passive at any count; this only buys accuracy. */
static int automatic_substeps(const rig_consts_ *r)
{
    const gs_real k_over_m = r->mesh.stiffness * contact_inverse_mass(r, r->dt);
    int n = 1;
    while (n < GS_AUTO_SUBSTEPS_MAX) {
        const gs_real h = r->dt / (gs_real)n;
        if (h * h * k_over_m <= (gs_real)GS_AUTO_H_OMEGA_N_MAX * (gs_real)GS_AUTO_H_OMEGA_N_MAX) {
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

/* The two power-flow pieces' masses of one base rule, with the law prepared
 * at init. */
static void geared_masses(const rig_consts_ *r, geared_base_ *base)
{
    base->den_fd = gs_rig_geared_piece_mass(r->geared_law.l_fd, r->geared_follower_mass, base);
    base->den_bd = gs_rig_geared_piece_mass(r->geared_law.l_bd, r->geared_follower_mass, base);
}

/* The contact's constants on each branch of a meshing law fixed at init
 * (rig_backlash.c, contact_against); a self-locking branch has none. */
static void friction_contacts_fill(rig_consts_ *r)
{
    const gs_mesh_friction_ *law = &r->loss_law;
    memset(&r->contact_fd, 0, sizeof r->contact_fd);
    memset(&r->contact_bd, 0, sizeof r->contact_bd);
    r->friction_contacts_fixed = r->mesh.backlash && r->loss_static && law->lossy && !r->friction_regularised;
    if (r->friction_contacts_fixed) {
        if (!(law->q_fd < GS_R(0.0))) {
            gs_contact_scale(&r->contact, GS_R(1.0) + r->bound_gain * law->q_fd, &r->contact_fd);
        }
        gs_contact_scale(&r->contact, GS_R(1.0) - r->bound_gain * law->q_bd, &r->contact_bd);
    }
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
    r->geared_fixed = r->loss_static && !r->friction_regularised && !r->stribeck;
    r->geared_law = gs_rig_geared_law(&r->loss_law, h * gs_abs(a), r->load_coulomb);
    geared_masses(r, &r->geared_base);
    geared_masses(r, &r->geared_base_end);
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
        gs_rig_cos_sin(p->ripple_revolution_phase_rad[i], &c, &s);
        r->ripple_rev_cos[i] = p->ripple_revolution_amplitude_Nm[i] * c;
        r->ripple_rev_sin[i] = p->ripple_revolution_amplitude_Nm[i] * s;
        gs_rig_cos_sin(p->ripple_mesh_phase_rad[i], &c, &s);
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
    gs_mesh_thermal_constants(&r->mesh, r->dt, r->inv_thermal_resistance, &r->thermal_gain, &r->thermal_den);
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
    r->bound_gain = GS_R(0.0);
    memset(&r->contact, 0, sizeof r->contact);
    memset(&r->contact_stuck, 0, sizeof r->contact_stuck);
    if (r->mesh.backlash) {
        const gs_real inv_eff_mass = contact_inverse_mass(r, r->substep); /* 1/m_eff at the pitch line, 1/kg */
        gs_contact_prepare(&r->mesh, r->substep, inv_eff_mass, &r->contact);
        if (r->base_drive == GS_BASE_TORQUE_DRIVEN) {
            gs_contact_prepare(&r->mesh, r->substep, base_inverse_mass(r, r->substep), &r->contact_stuck);
        }
        r->bound_gain = r->contact.inv_c * r->follower_lever * r->follower_kick;
        r->contact_h_omega_n = contact_h_omega_n(r, r->substep, inv_eff_mass);
        r->substeps_capped = p->contact_substeps == 0 && r->contact_h_omega_n > (gs_real)GS_AUTO_H_OMEGA_N_MAX;
    }
    r->loss_static = r->mesh.friction == GS_FRICTION_NONE || r->mesh.friction == GS_FRICTION_CONSTANT_EFFICIENCY ||
                     r->mesh.friction == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    r->law_per_substep = r->mesh.friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    memset(&r->loss_ctx, 0, sizeof r->loss_ctx);
    gs_mesh_loss_prepare(&r->mesh, r->mesh.initial_temperature, &r->loss_ctx);
    gs_mesh_friction_law(&r->mesh, &r->loss_ctx, GS_R(0.0), &r->loss_law);
    r->stribeck = p->load_breakaway_friction > GS_R(0.0);
    r->stribeck_excess = r->stribeck ? p->load_breakaway_friction - p->load_coulomb_friction : GS_R(0.0);
    r->inv_stribeck_speed_sq = r->stribeck ? GS_R(1.0) / (p->load_stribeck_speed * p->load_stribeck_speed) : GS_R(0.0);
    r->follower_free = !r->loss_law.lossy && !r->stribeck && !(r->load_coulomb > GS_R(0.0));
    friction_contacts_fill(r);
    compliance_fill(r, p);
    ripple_fill(r, p);
}

/* The rig parameters are checked first, so that once the block's mesh is
 * validated (and only then written into consts) nothing can fail: a failed
 * init leaves consts and state unchanged. */
gs_status gs_rig_init_gear(gs_rig_consts *consts, gs_rig_state *state, const gs_simple_gear_params *gear,
                           const gs_rig_params *params, gs_error *err)
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

gs_status gs_rig_init_rack(gs_rig_consts *consts, gs_rig_state *state, const gs_rack_pinion_params *rack,
                           const gs_rig_params *params, gs_error *err)
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

void gs_rig_step(const gs_rig_consts *consts, gs_rig_state *st, const gs_rig_input *in, gs_rig_output *out)
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
        gs_mesh_loss_prepare_inline(m, from_input ? in->measured_temperature : st->block.temperature, &ctx_now);
        ctx = &ctx_now;
    }
    out->contact_force = GS_R(0.0);
    if (m->backlash || r->compliant || r->base_drive == GS_BASE_TORQUE_DRIVEN) {
        /* a free driven side or base gear: the meshing loss as a friction element */
        const gs_mesh_friction_ *law = &r->loss_law;
        gs_mesh_friction_ law_now;
        if (!r->loss_static) {
            gs_mesh_friction_law_inline(m, ctx, st->block.follower_torque, &law_now);
            law = &law_now;
        }
        if (m->backlash) {
            gs_rig_backlash_step(r, st, ctx, law, in, out);
        } else if (r->compliant) {
            gs_rig_compliant_step(r, st, ctx, law, in, w_drive_start, out);
        } else {
            gs_rig_rigid_torque_driven(r, st, law, in, out);
            st->base_angle += r->dt * st->base_speed;
            st->follower_position += r->dt * st->follower_speed;
        }
    } else {
        gs_rig_rigid_speed_driven(r, st, ctx, in, w_drive_start, out);
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
        gs_mesh_thermal_step(m, &st->block, r->thermal_gain, r->thermal_den, out->loss_power,
                             r->inv_thermal_resistance * in->ambient_temperature);
    }
    out->base_speed = st->base_speed;
    out->base_angle = st->base_angle;
    out->follower_speed = st->follower_speed;
    out->follower_position = st->follower_position;
    out->contact_energy =
        m->backlash ? gs_contact_energy(m, r->contact.transition, st->block.backlash_position) : GS_R(0.0);
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

void gs_rig_run(const gs_rig_consts *consts, gs_rig_state *state, size_t n, const gs_rig_input *in, gs_rig_output *out)
{
    for (size_t i = 0; i < n; ++i) {
        gs_rig_step(consts, state, &in[i], &out[i]);
    }
}

/* ---- The field tables of gearsim/fields.h, for generic readers (Python, tools). */
#define GS_IS_INT_gs_real 0
#define GS_IS_INT_int     1
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
const gs_field_info gs_rig_state_info[GS_RIG_STATE_FIELDS] = {GS_BLOCK_STATE_LIST(GS_BLOCK_STATE_INFO_)
                                                                  GS_RIG_STATE_LIST(GS_RIG_STATE_INFO_)};

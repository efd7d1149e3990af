/*
 * bench_common.h - the benchmark configurations and their input, shared by
 * the host benchmark (gearsim_bench.c) and the Cortex-M4 one (m4/m4_bench.c).
 *
 * Every configuration is a speed-driven rig stepped at dt = 1 ms on the same
 * realistic input: a sinusoidal base speed with reversals and a load that
 * changes sign (see bench_make_inputs). The input is one full period of
 * BENCH_PERIOD samples, cycled; it joins seamlessly. It is generated without
 * libm (rotation recurrences in double), so the host and the MCU build step
 * exactly the same input.
 */
#ifndef GEARSIM_BENCH_COMMON_H
#define GEARSIM_BENCH_COMMON_H

#include <stddef.h>

#include "gearsim/gearsim.h"

#define BENCH_PERIOD 4000 /* lcm of the input tones' periods at dt = 1 ms */
#define BENCH_DT_S   1e-3

typedef struct {
    const char *name;
    const char *description;
    gs_rig_block block;
    /* fills the block and rig parameters from their defaults */
    void (*setup_gear)(gs_simple_gear_params *g, gs_rig_params *r);
    void (*setup_rack)(gs_rack_pinion_params *p, gs_rig_params *r);
} bench_config;

/* ---- Simple Gear configurations (teeth ratio 2, opposite rotation, defaults
 * of docs/physics.md section 9 unless set here; follower inertia 0.05 kg*m^2). */
static inline void sg_ideal(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)g;
    (void)r;
}

static inline void sg_constant(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    g->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}

static inline void sg_load(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    g->friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
}

static inline void sg_temp(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    g->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    g->initial_temperature_K = GS_R(295.0); /* crosses the 300 K breakpoint while it heats */
}

static inline void sg_temp_load(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    g->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    g->initial_temperature_K = GS_R(295.0);
}

static inline void backlash_on(gs_backlash_params *b, gs_hard_stop_model model)
{
    b->enabled = 1;
    b->hard_stop_model = model;
}

static inline void sg_backlash_smooth(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    backlash_on(&g->backlash, GS_HARD_STOP_SMOOTH);
}

static inline void sg_backlash_full_undamped(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    backlash_on(&g->backlash, GS_HARD_STOP_FULL_UNDAMPED);
}

static inline void sg_backlash_full_damped(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    backlash_on(&g->backlash, GS_HARD_STOP_FULL_DAMPED);
}

/* Everything a Simple Gear rig can have at once. */
static inline void sg_full(gs_simple_gear_params *g, gs_rig_params *r)
{
    g->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    g->initial_temperature_K = GS_R(295.0);
    g->viscous_coefficients[0] = GS_R(0.002);
    g->viscous_coefficients[1] = GS_R(0.004);
    backlash_on(&g->backlash, GS_HARD_STOP_SMOOTH);
    r->heat_path = 1;
    r->thermal_resistance_K_W = GS_R(2.0);
    r->load_coulomb_friction = GS_R(0.05);
}

/* The rigid rig the Python/numpy alternative reproduces (bench/python). */
static inline void sg_constant_viscous(gs_simple_gear_params *g, gs_rig_params *r)
{
    (void)r;
    g->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g->viscous_coefficients[0] = GS_R(0.002);
    g->viscous_coefficients[1] = GS_R(0.004);
}

/* The rig terms of physics.md 11 (Stribeck, compliance, ripple), each on
 * sg_constant (or sg_backlash_smooth) so that its cost is the difference. */
static inline void sg_stribeck(gs_simple_gear_params *g, gs_rig_params *r)
{
    g->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    r->load_coulomb_friction = GS_R(0.1);
    r->load_breakaway_friction = GS_R(0.3);
    r->load_stribeck_speed = GS_R(0.5);
}

static inline void sg_backlash_stribeck(gs_simple_gear_params *g, gs_rig_params *r)
{
    backlash_on(&g->backlash, GS_HARD_STOP_SMOOTH);
    r->load_coulomb_friction = GS_R(0.1);
    r->load_breakaway_friction = GS_R(0.3);
    r->load_stribeck_speed = GS_R(0.5);
}

/* 50 Hz shaft resonance (J_eff = 0.01 + 0.05/4 kg*m^2): two sub-steps */
static inline void sg_compliance(gs_simple_gear_params *g, gs_rig_params *r)
{
    g->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    r->base_inertia_kg_m2 = GS_R(0.01);
    r->compliance_stiffness_Nm_rad = GS_R(2220.0);
    r->compliance_damping_Nm_s_rad = GS_R(1.0);
}

static inline void sg_ripple(gs_simple_gear_params *g, gs_rig_params *r)
{
    g->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    r->ripple_revolution_amplitude_Nm[0] = GS_R(0.05);
    r->ripple_revolution_amplitude_Nm[1] = GS_R(0.02);
    r->ripple_mesh_amplitude_Nm[0] = GS_R(0.01);
    r->ripple_mesh_amplitude_Nm[1] = GS_R(0.005);
    r->ripple_mesh_phase_rad[0] = GS_R(0.3);
    r->ripple_mesh_teeth = 20;
}

/* ---- Rack & Pinion configurations (rack mass 2 kg; pinion radius 0.1 m, or
 * 20 teeth x 5 mm = 15.9 mm with the tooth parameterization). */
static inline void rack_common(gs_rack_pinion_params *p, gs_rig_params *r, int teeth)
{
    p->parameterization = teeth ? GS_PARAMETERIZE_TOOTH_PARAMETERS : GS_PARAMETERIZE_PINION_RADIUS;
    r->driven_inertia = GS_R(2.0);
}

static inline void rp_constant_radius(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 0);
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}

static inline void rp_constant_teeth(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 1);
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}

static inline void rp_temp_radius(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 0);
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    p->initial_temperature_K = GS_R(295.0);
}

static inline void rp_temp_teeth(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 1);
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    p->initial_temperature_K = GS_R(295.0);
}

static inline void rp_backlash_radius(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 0);
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    backlash_on(&p->backlash, GS_HARD_STOP_SMOOTH);
}

static inline void rp_backlash_teeth(gs_rack_pinion_params *p, gs_rig_params *r)
{
    rack_common(p, r, 1);
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    backlash_on(&p->backlash, GS_HARD_STOP_SMOOTH);
}

#define GEAR(name, desc)                            \
    {                                               \
#name, desc, GS_RIG_SIMPLE_GEAR, name, NULL \
    }
#define RACK(name, desc)                            \
    {                                               \
#name, desc, GS_RIG_RACK_PINION, NULL, name \
    }

static const bench_config CONFIGS[] = {
    GEAR(sg_ideal, "Simple Gear, ideal (no losses)"),
    GEAR(sg_constant, "Simple Gear, constant efficiency"),
    GEAR(sg_load, "Simple Gear, load-dependent efficiency"),
    GEAR(sg_temp, "Simple Gear, temperature table + thermal mass"),
    GEAR(sg_temp_load, "Simple Gear, temperature x load table + thermal mass"),
    GEAR(sg_backlash_smooth, "Simple Gear, backlash, smooth hard stop"),
    GEAR(sg_backlash_full_undamped, "Simple Gear, backlash, full stiffness, undamped rebound"),
    GEAR(sg_backlash_full_damped, "Simple Gear, backlash, full stiffness, damped rebound"),
    GEAR(sg_full, "Simple Gear full rig: backlash + T x load table + heat path + viscous"),
    GEAR(sg_constant_viscous, "Simple Gear, constant efficiency + viscous (Python comparison)"),
    GEAR(sg_stribeck, "Simple Gear, constant efficiency + Stribeck friction"),
    GEAR(sg_backlash_stribeck, "Simple Gear, backlash (smooth) + Stribeck friction"),
    GEAR(sg_compliance, "Simple Gear, constant efficiency + compliant base shaft (50 Hz)"),
    GEAR(sg_ripple, "Simple Gear, constant efficiency + torque ripple (2 + 2 harmonics, 20 teeth)"),
    RACK(rp_constant_radius, "Rack & Pinion, constant efficiency, radius"),
    RACK(rp_constant_teeth, "Rack & Pinion, constant efficiency, tooth parameters"),
    RACK(rp_temp_radius, "Rack & Pinion, temperature table + thermal mass, radius"),
    RACK(rp_temp_teeth, "Rack & Pinion, temperature table + thermal mass, tooth parameters"),
    RACK(rp_backlash_radius, "Rack & Pinion, backlash (smooth) + constant efficiency, radius"),
    RACK(rp_backlash_teeth, "Rack & Pinion, backlash (smooth) + constant efficiency, tooth parameters"),
};
#define N_CONFIGS (sizeof CONFIGS / sizeof CONFIGS[0])

/* sin and cos of |x| <= 0.5 by their Taylor series (exact in double there). */
static inline void bench_sincos(double x, double *s, double *c)
{
    double term_s = x, term_c = 1.0, sum_s = x, sum_c = 1.0;
    const double x2 = x * x;
    for (int k = 1; k < 12; ++k) {
        term_s *= -x2 / (double)((2 * k) * (2 * k + 1));
        term_c *= -x2 / (double)((2 * k - 1) * (2 * k));
        sum_s += term_s;
        sum_c += term_c;
    }
    *s = sum_s;
    *c = sum_c;
}

/* A sine tone by rotation: value sin(phase0 + k*theta) at step k. */
typedef struct {
    double s, c, ds, dc;
} bench_tone;

static inline bench_tone bench_tone_make(double frequency_hz, double phase0)
{
    bench_tone t;
    bench_sincos(6.283185307179586 * frequency_hz * BENCH_DT_S, &t.ds, &t.dc);
    bench_sincos(phase0, &t.s, &t.c);
    return t;
}

static inline double bench_tone_next(bench_tone *t)
{
    const double value = t->s;
    const double s = t->s * t->dc + t->c * t->ds;
    t->c = t->c * t->dc - t->s * t->ds;
    t->s = s;
    return value;
}

/* Base speed (rad/s): 20 sin(2 pi 0.5 t) + 4 sin(2 pi 1.25 t), reversing twice
 * a second. Load (N*m on the follower): 2 + 6 sin(2 pi 0.25 t + 0.3) +
 * 0.5 sin(2 pi 5 t), changing sign; divided by the pinion radius for the rack
 * (N), so both rigs see the same torques. Ambient 293.15 K. */
static inline void bench_make_inputs(gs_rig_input *in, double load_scale)
{
    bench_tone w1 = bench_tone_make(0.5, 0.0), w2 = bench_tone_make(1.25, 0.0);
    bench_tone l1 = bench_tone_make(0.25, 0.3), l2 = bench_tone_make(5.0, 0.0);
    for (int i = 0; i < BENCH_PERIOD; ++i) {
        const double w = 20.0 * bench_tone_next(&w1) + 4.0 * bench_tone_next(&w2);
        const double load = 2.0 + 6.0 * bench_tone_next(&l1) + 0.5 * bench_tone_next(&l2);
        in[i].base_speed = (gs_real)w;
        in[i].base_torque = GS_R(0.0);
        in[i].load = (gs_real)(load_scale * load);
        in[i].ambient_temperature = GS_R(293.15);
        in[i].measured_temperature = GS_R(300.0);
    }
}

/* Initialises the rig (its constants and state) and fills the input period
 * `in` for configuration c. Returns the init status; err receives the failing
 * parameter. */
static inline gs_status bench_setup(const bench_config *c, gs_rig_consts *consts, gs_rig_state *state, gs_rig_input *in,
                                    gs_error *err)
{
    gs_rig_params rp = gs_rig_params_default();
    rp.dt_s = (gs_real)BENCH_DT_S;
    gs_status s;
    double load_scale = 1.0;
    if (c->block == GS_RIG_SIMPLE_GEAR) {
        gs_simple_gear_params g = gs_simple_gear_params_default();
        c->setup_gear(&g, &rp);
        s = gs_rig_init_gear(consts, state, &g, &rp, err);
    } else {
        gs_rack_pinion_params p = gs_rack_pinion_params_default();
        c->setup_rack(&p, &rp);
        load_scale = 1.0 / (double)gs_rack_pinion_radius(&p);
        s = gs_rig_init_rack(consts, state, &p, &rp, err);
    }
    if (s == GS_OK) {
        bench_make_inputs(in, load_scale);
    }
    return s;
}

#endif /* GEARSIM_BENCH_COMMON_H */

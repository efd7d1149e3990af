/* mesh.h - the transmission shared by both blocks (internal).
 *
 * Both blocks are a mesh omega_B = ratio*omega_F between a base shaft and a
 * follower (a shaft, or the rack with "radius" 1). This header gathers the
 * meshing-loss laws (physics.md 2, 6), the hard-stop contact (4), the thermal
 * mass (5) and the block-level step, so that each exists once. */
#ifndef GS_MESH_H
#define GS_MESH_H

#include "gearsim/types.h"
#include "gs_math.h"

/* ---- Internal constants: what init derives and the step only reads. The
 * state lives in the public gs_block_state. Plain data, no pointers. */
typedef struct {
    gs_real x[GS_TABLE_MAX];
    gs_real y[GS_TABLE_MAX];
    int n;
} gs_table1_;

typedef struct {
    gs_real x[GS_TABLE_MAX]; /* rows: temperature, K */
    gs_real y[GS_TABLE_MAX]; /* columns: base load, N*m */
    gs_real z[GS_TABLE_MAX][GS_TABLE_MAX];
    int nx;
    int ny;
} gs_table2_;

/* The mesh shared by both blocks: omega_F = inv_ratio * omega_B, where
 * inv_ratio = s/g (Simple Gear) or s_R*r_P (Rack & Pinion, follower = rack). */
typedef struct {
    gs_real inv_ratio;       /* omega_F / omega_B (signed) */
    gs_real base_radius;     /* r_B or r_P, m (backlash geometry) */
    gs_real follower_radius; /* r_F (m) or 1 for the rack */
    gs_real direction;       /* s or s_R, +1 or -1 */
    gs_real mu_base;         /* viscous, N*m/(rad/s) */
    gs_real mu_follower;     /* viscous, N*m/(rad/s) or N/(m/s) */
    gs_friction_model friction;
    gs_loss_smoothing smoothing;
    gs_real eta;                 /* constant efficiency */
    gs_real inv_power_threshold; /* 1/p_th, 1/W */
    gs_real coulomb_idle;        /* g*tau_idle, follower-referred, N*m */
    gs_real load_slope;          /* k of eq. 2.5 */
    gs_real inv_speed_threshold; /* 1/omega_th */
    gs_real base_load_scale;     /* |T_F| -> base load: 1/g */
    int thermal_enabled;
    gs_real thermal_mass;        /* J/K */
    gs_real initial_temperature; /* K */
    /* backlash */
    int backlash;
    gs_hard_stop_model hard_stop;
    gs_real half_gap;       /* b/2, m */
    gs_real inv_transition; /* 1/d */
    gs_real stiffness;
    gs_real damping;
    gs_real initial_position;
    int no_pull;
    int lock_enabled;
    gs_real lock_speed;
    gs_real lock_release_force;
    /* The efficiency table of the friction model in use: only one law is
     * active, so the tables share their storage. */
    union {
        gs_table1_ eta_of_T;      /* temperature-dependent efficiency */
        gs_table2_ eta_of_T_load; /* temperature- and load-dependent efficiency */
    } table;
} gs_mesh_;

/* Constants of the backward-Euler contact for one sub-step length
 * (src/hard_stop.c), computed at init so that the step path divides little. */
typedef struct {
    gs_real h;                   /* sub-step, s */
    gs_real inv_h;               /* 1/h, 1/s */
    gs_real c;                   /* h/m_eff, s/kg */
    gs_real inv_c;               /* m_eff/h, kg/s */
    gs_real c_stiffness;         /* c*K, 1/s */
    gs_real c_damping;           /* c*D: lambda = c*D*p0 of the damped affine piece */
    gs_real kappa;               /* c*(K*h + D): the damped law's slope in h*Phi over delta */
    gs_real kappa_spring;        /* c*K*h: the spring's share of it */
    gs_real h_over_d;            /* h/d (smooth law): the scaled penetration per closing speed, s */
    gs_real d_over_h;            /* d/h, m/s */
    gs_real inv_kappa;           /* 1/kappa */
    gs_real inv_affine_damped;   /* 1/(1 + kappa) */
    gs_real inv_affine_undamped; /* 1/(1 + c*K*h) */
    gs_real transition;          /* d, m (smooth law) */
    int law_force_conditioned;   /* kappa < 1: the law may give the root's force */
} gs_contact_step_;

/* A compile-time check (C99: a negative array size). */
#define GS_STATIC_ASSERT_(name, cond) typedef char gs_static_assert_##name[(cond) ? 1 : -1]

/* The public opaque constants (gs_rig_consts, gs_*_consts) are views of
 * internal types, published as a count of reals (GS_RIG_CONSTS_REALS,
 * GS_BLOCK_CONSTS_REALS) because the layout is private. The check below keeps
 * the published count exact, so that it cannot go stale unnoticed when the
 * internal layout changes. Where enums are int-sized and reals aligned to
 * their size (the hosts: x86-64, AArch64, ...) a count that differs from what
 * the internal type needs fails to compile with "conflicting types for
 * 'gs_set_<MACRO>_to'"; the type the compiler reports for the second
 * declaration, char[N] ("have" in GCC's message, the first type in clang's),
 * gives the value N to write in the header. Where enums are packed into one
 * byte (arm-none-eabi) the internal type is a few bytes smaller: there the
 * published count must hold it. */
#define GS_REALS_FOR_(bytes) (((bytes) + sizeof(gs_real) - 1u) / sizeof(gs_real))
typedef struct {
    char c;
    gs_real x;
} gs_real_alignment_probe_;
#define GS_EXACT_CONSTS_ABI_ \
    (sizeof(gs_friction_model) == sizeof(int) && sizeof(gs_real_alignment_probe_) == 2u * sizeof(gs_real))
#define GS_CONSTS_REALS_CHECK_(macro, internal)                                                       \
    GS_STATIC_ASSERT_(macro##_holds_internal, (size_t)(macro) * sizeof(gs_real) >= sizeof(internal)); \
    extern char gs_set_##macro##_to[macro];                                                           \
    extern char gs_set_##macro##_to[GS_EXACT_CONSTS_ABI_ ? GS_REALS_FOR_(sizeof(internal)) : (size_t)(macro)]

/* Mesh-loss quantities that depend only on the temperature, evaluated once
 * per step. */
typedef struct {
    gs_real loss_forward;  /* L_fd = 1 - eta       (follower driving) */
    gs_real loss_backward; /* L_bd = 1/eta - 1     (base driving) */
    /* the 2-D table's temperature bracket: rows t_lo, t_hi, weight t_w (each
     * lookup interpolates the two load columns it needs in temperature, then
     * in load: the same arithmetic as collapsing every column first) */
    int t_lo, t_hi;
    gs_real t_w;
} gs_loss_ctx_;

/* Common mesh set-up (the block inits call these after their own checks). */
gs_status gs_mesh_set_backlash(gs_mesh_ *m, const gs_backlash_params *p, gs_real base_radius, gs_real follower_radius,
                               gs_error *err);
gs_status gs_mesh_set_thermal(gs_mesh_ *m, gs_real thermal_mass, gs_real initial_temperature, gs_error *err);
/* The initial state of a mesh. */
void gs_mesh_reset(const gs_mesh_ *m, gs_block_state *st);
/* Copies a validated temperature -> efficiency table into the mesh. */
void gs_mesh_set_temperature_table(gs_mesh_ *m, const gs_real *temperature, const gs_real *eta, int n);

/* Meshing loss (mesh_loss.c). */
void gs_mesh_loss_prepare(const gs_mesh_ *m, gs_real temperature, gs_loss_ctx_ *ctx);
/* tau_mesh (follower-referred) for net follower torque T and speed w. */
gs_real gs_mesh_loss_torque(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real T, gs_real w);
/* tau_mesh for a known loss-free tooth torque T_F0 (backlash contact): the
 * solution of T_F = T_F0 + tau_mesh(T_F) (physics.md 4.6), so that steady
 * contact transmits the torques of the rigid law. load_estimate is a recent
 * T_F (the base load of the 2-D table, a fixed point in steady contact). */
gs_real gs_mesh_loss_from_tooth(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real t_f0, gs_real w,
                                gs_real load_estimate);

/* The meshing loss as a friction element, where a rig's driven side or base
 * gear moves freely (physics.md 11, "Lossy meshes hold"). Sliding with the
 * follower speed's sign sigma, the loss is the law of section 2 at full
 * strength,
 *   tau_mesh = sigma*(c0 + k_fd*max(sigma*T_F, 0) + k_bd*max(-sigma*T_F, 0)),
 * k_fd where the follower drives (sigma*T_F > 0), k_bd where the base drives;
 * at rest it holds anything within those bounds (set-valued). */
typedef struct {
    gs_real c0;   /* follower-referred constant part (g*tau_idle), N*m or N */
    gs_real k_fd; /* slope on |T_F| with the follower driving */
    gs_real k_bd; /* slope on |T_F| with the base driving */
    gs_real q_fd; /* k_fd/(1 - k_fd): the bound on the loss-free tooth torque, follower
                     driving; < 0 where 1 - k_fd <= 0 (self-locking: no bound) */
    gs_real q_bd; /* k_bd/(1 + k_bd): the same, base driving */
    int lossy;    /* 0: no meshing loss */
} gs_mesh_friction_;

/* q_fd and q_bd from k_fd and k_bd (see the fields). */
static inline void gs_mesh_friction_bounds(gs_mesh_friction_ *law)
{
    law->q_fd = law->k_fd < GS_R(1.0) ? law->k_fd / (GS_R(1.0) - law->k_fd) : GS_R(-1.0);
    law->q_bd = law->k_bd / (GS_R(1.0) + law->k_bd);
}

/* The law's coefficients for the step. The 2-D table reads its efficiency
 * at the base load |load_estimate|/g (a recent T_F). */
void gs_mesh_friction_law(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real load_estimate, gs_mesh_friction_ *law);
/* The loss torque of the law sliding with follower speed w (w != 0) under
 * the net follower torque t_f; 0 for w = 0. */
static inline gs_real gs_mesh_friction_torque(const gs_mesh_friction_ *law, gs_real t_f, gs_real w)
{
    if (w > GS_R(0.0)) {
        return law->c0 + (t_f > GS_R(0.0) ? law->k_fd * t_f : -law->k_bd * t_f);
    }
    if (w < GS_R(0.0)) {
        return -law->c0 + (t_f < GS_R(0.0) ? law->k_fd * t_f : -law->k_bd * t_f);
    }
    return GS_R(0.0);
}

/* Hard-stop contact (hard_stop.c; the spring energy and the scaled
 * constants inline here). x: backlash position (m), u: relative tooth
 * velocity (m/s). */
gs_real gs_contact_force(const gs_mesh_ *m, gs_real x, gs_real u, gs_real *f_spring);
/* Energy stored in the contact spring at x (J); inline: every backlash step
 * reports it. d is the smooth law's transition depth (gs_contact_step_'s
 * transition, 1/inv_transition, kept by init so that the step does not
 * divide). */
static inline gs_real gs_contact_energy(const gs_mesh_ *m, gs_real d, gs_real x)
{
    gs_real delta = GS_R(0.0);
    if (x > m->half_gap) {
        delta = x - m->half_gap;
    } else if (x < -m->half_gap) {
        delta = -m->half_gap - x;
    }
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        /* integral of S(s/d)*K*s ds: K*(3 s^4/(4 d^2) - 2 s^5/(5 d^3)) up to d, then linear spring */
        const gs_real s = gs_min(delta, d);
        const gs_real s2 = s * s;
        const gs_real ramp = m->stiffness * s2 * s2 * m->inv_transition * m->inv_transition *
                             (GS_R(0.75) - GS_R(0.4) * s * m->inv_transition);
        if (delta > d) {
            return ramp + GS_R(0.5) * m->stiffness * (delta * delta - d * d);
        }
        return ramp;
    }
    return GS_R(0.5) * m->stiffness * delta * delta;
}

/* The constants of gs_contact_solve for sub-step h (s) and the inverse
 * effective mass inv_mass (1/kg) at the pitch line. */
void gs_contact_prepare(const gs_mesh_ *m, gs_real h, gs_real inv_mass, gs_contact_step_ *cs);
/* The same constants with h/m_eff multiplied by lambda > 0 (the inverse mass
 * the contact sees scaled; rig_backlash.c, per solve where the law is not
 * fixed at init: inline). */
static inline void gs_contact_scale(const gs_contact_step_ *cs, gs_real lambda, gs_contact_step_ *scaled)
{
    const gs_real inv_lambda = GS_R(1.0) / lambda;
    *scaled = *cs;
    scaled->c = cs->c * lambda;
    scaled->inv_c = cs->inv_c * inv_lambda;
    scaled->c_stiffness = cs->c_stiffness * lambda;
    scaled->c_damping = cs->c_damping * lambda;
    scaled->kappa = cs->kappa * lambda;
    scaled->kappa_spring = cs->kappa_spring * lambda;
    scaled->inv_kappa = cs->inv_kappa * inv_lambda;
    scaled->inv_affine_damped = GS_R(1.0) / (GS_R(1.0) + scaled->kappa);
    scaled->inv_affine_undamped = GS_R(1.0) / (GS_R(1.0) + scaled->kappa_spring);
    scaled->law_force_conditioned = scaled->kappa < GS_R(1.0);
}
/* The backward-Euler contact over one sub-step: src/contact.h. */

/* Thermal mass: C dT/dt = P + G (T_amb - T), the heat P (losses and any
 * explicit heat flow) explicit, the ambient path through conductance G
 * implicit (stable for any thermal mass). Over a step dt:
 *   T' = (T + a*(P + G*T_amb)) / (1 + a*G),  a = dt/C.
 * gain (a) and den (1 + a*G) are the step's constants: the rig fixes them at
 * init, the block step derives them from its dt. */
static inline void gs_mesh_thermal_constants(const gs_mesh_ *m, gs_real dt, gs_real conductance_W_K, gs_real *gain_K_W,
                                             gs_real *den)
{
    *gain_K_W = m->thermal_enabled ? dt / m->thermal_mass : GS_R(0.0);
    *den = GS_R(1.0) + *gain_K_W * conductance_W_K;
}

static inline void gs_mesh_thermal_step(const gs_mesh_ *m, gs_block_state *st, gs_real gain_K_W, gs_real den,
                                        gs_real heat_W, gs_real ambient_flow_W)
{
    if (!m->thermal_enabled) {
        return; /* no thermal mass: the temperature stays */
    }
    st->temperature = (st->temperature + gain_K_W * (heat_W + ambient_flow_W)) / den;
}

/* Block-level step shared by both blocks: rigid (form A) or backlash (form C). */
typedef struct {
    gs_real base_speed, follower_speed, follower_torque, heat_flow, temperature;
    int use_temperature;
} gs_mesh_in_;
typedef struct {
    gs_real base_torque, follower_torque, follower_speed, loss_torque, mesh_loss_power, loss_power, temperature,
        position, contact_force;
} gs_mesh_out_;
void gs_mesh_block_step(const gs_mesh_ *m, gs_block_state *st, gs_real dt, const gs_mesh_in_ *in, gs_mesh_out_ *out);

#endif /* GS_MESH_H */

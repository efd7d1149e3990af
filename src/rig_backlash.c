/* rig_backlash.c - the rig with backlash (rig_internal.h): the follower (and
 * a torque-driven base) carry their own speeds; the contact is integrated by
 * backward Euler in a fixed number of sub-steps (contact.h), viscous terms
 * implicit, and the follower's friction (the load's, and the meshing loss
 * with its bounds taken from the last contact force) is solved with the
 * contact, set-valued at rest. */
#include "rig_internal.h"
#include "contact.h"
#include "gs_math.h"

/* The contact's state inside a step: kept in locals over the sub-steps. */
typedef struct {
    gs_real x;  /* backlash position, m */
    gs_real f;  /* the last sub-step's contact force, N */
    int locked; /* the static-contact lock */
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
    const gs_real level = r->friction_regularised ? gs_rig_creep_level(r, w_f) : friction_level(r, w_f);
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

void gs_rig_backlash_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_mesh_friction_ *law,
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
    gs_mesh_friction_ table_law; /* its law after the first sub-step */
    const gs_mesh_friction_ *law_sub = law;
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
        motor_h -= h * gs_rig_ripple_torque(r, theta_b);
    }
    for (int k = 0; k < n; ++k) {
        gs_real w_b_free;
        if (speed_driven) {
            w_b_free = k + 1 < n ? w_b_start + ramp * (gs_real)(k + 1) : in->base_speed;
            if (r->ripple) { /* at the sub-step's mid angle */
                sum_ripple += gs_rig_ripple_torque(r, theta_b + GS_R(0.5) * h * w_b_free);
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
                gs_mesh_friction_law(m, ctx, t_f, &table_law);
                law_sub = &table_law;
            }
            gs_mesh_friction_ law_now;
            const gs_mesh_friction_ *law_k = gs_rig_step_law(r, law_sub, t_f, w_f, &law_now);
            e = substep_friction(r, law_k, &c, w_f, w_b_free, momentum, &tau_mesh, &t_f);
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
    out->base_torque = speed_driven ? out->base_port_torque + r->base_inertia * st->base_acceleration : in->base_torque;
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

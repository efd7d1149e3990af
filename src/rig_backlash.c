/* rig_backlash.c - the rig with backlash (rig_internal.h): the follower (and
 * a torque-driven base) carry their own speeds; the contact is integrated by
 * backward Euler in a fixed number of sub-steps (contact.h), viscous terms
 * implicit, and the follower's friction (the load's, and the meshing loss
 * with its bounds at the sub-step's own contact force) is solved with the
 * contact, set-valued at rest. */
#include "rig_internal.h"
#include "contact.h"
#include "gs_math.h"

/* The smooth law's bracketed solve (contact.h, smooth_root), here beside
 * its only caller, the sub-step, so that the compiler sees which registers
 * the call keeps. Decisions are taken on the penetration delta = p0 + h*v,
 * values in the closing speed v. */
GS_NOINLINE gs_real gs_smooth_root_bracketed(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free,
                                             gs_real guess, gs_real *spring)
{
    const smooth_problem p = smooth_setup(m, cs, p0, v_free);
    const gs_real to_t = cs->h_over_d;
    const gs_real d = cs->transition;
    const gs_real delta_free = p0 + cs->h * v_free;
    const gs_real lambda = cs->c_damping * p0; /* h*Phi = delta - delta_free + kappa*delta - lambda, affine */
    gs_real lo = -p0 * cs->inv_h;              /* the teeth just touching */
    gs_real hi = v_free;
    if (m->no_pull) {
        if (cs->kappa * delta_free <= lambda) {
            /* the clipped force is zero at the free motion's end */
            *spring = spring_force(m, delta_free);
            return v_free;
        }
        /* Below the speed where K*delta + D*v = 0 the clipped force is zero
         * and Phi < 0: the root lies above it. Starting the bracket there
         * keeps the kink of the clip out of Newton's way; on a stiff contact
         * (kappa ~ 1e6) Newton stepped across it from the flat side and
         * bisection did not close the bracket in 12 passes (fuzz finding). */
        lo = gs_max(lo, -cs->c_stiffness * p0 * cs->inv_kappa);
    } else {
        /* the law pulls while the teeth separate: keep to one side of v = 0 */
        const gs_real at_rest = residual_at_rest(m, cs, p0, v_free);
        if (!(at_rest < GS_R(0.0) || at_rest > GS_R(0.0))) {
            *spring = spring_force(m, p0);
            return GS_R(0.0);
        }
        if (at_rest < GS_R(0.0)) {
            lo = gs_max(lo, GS_R(0.0));
        } else {
            hi = GS_R(0.0);
        }
    }
    /* closing speed at which the penetration reaches the transition depth d */
    const gs_real v_full = (d - p0) * cs->inv_h;
    if (hi > v_full) {
        /* beyond d the law is affine: the root there if h*Phi(d) <= 0 */
        if (lo >= v_full || d - delta_free + cs->kappa * d - lambda <= GS_R(0.0)) {
            const gs_real v = gs_clamp((v_free - cs->c_stiffness * p0) * cs->inv_affine_damped, gs_max(v_full, lo), hi);
            *spring = m->stiffness * (p0 + cs->h * v);
            return v;
        }
        hi = v_full;
    }
    gs_real t_lo = lo * to_t + p.t0; /* psi(t_lo) <= 0 <= psi(t_hi), narrowed every pass */
    gs_real t_hi = hi * to_t + p.t0;
    gs_real t = guess * to_t + p.t0;
    if (!(t > t_lo && t < t_hi)) {
        t = GS_R(0.5) * (t_lo + t_hi);
    }
    /* NEWTON_ITERATIONS steps: an evaluation before each and after the last */
    for (int i = 0; i <= NEWTON_ITERATIONS; ++i) {
        const smooth_point x = smooth_at(&p, t);
        if (x.psi > GS_R(0.0)) {
            t_hi = t;
        } else if (x.psi < GS_R(0.0)) {
            t_lo = t;
        }
        int near;
        if (smooth_accepts(&p, &x, &near)) {
            return smooth_end(m, cs, &p, &x, spring);
        }
        if (i == NEWTON_ITERATIONS) {
            continue; /* out of passes */
        }
        gs_real step;
        const gs_real slope = smooth_step_from(&p, &x, near, &step);
        t = GS_R(0.5) * (t_lo + t_hi);
        /* the pulling law can make psi fall: bisect */
        if (slope > GS_R(0.0) && x.t - step > t_lo && x.t - step < t_hi) {
            t = x.t - step;
        }
    }
    /* out of passes: the bracket end nearer v = 0, passive */
    lo = (t_lo - p.t0) * cs->d_over_h;
    hi = (t_hi - p.t0) * cs->d_over_h;
    if (lo < GS_R(0.0) && hi > GS_R(0.0)) {
        if (residual_at_rest(m, cs, p0, v_free) > GS_R(0.0)) {
            hi = GS_R(0.0);
        } else {
            lo = GS_R(0.0);
        }
    }
    const gs_real v = lo >= GS_R(0.0) ? lo : hi;
    const gs_real delta = p0 + cs->h * v;
    *spring = delta > GS_R(0.0) ? spring_force(m, delta) : GS_R(0.0);
    return v;
}

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

/* The follower's friction in a sub-step: the meshing law (physics.md 4.6)
 * and the load's friction level. */
typedef struct {
    const gs_mesh_friction_ *law;
    gs_real level; /* the load's Coulomb (or Stribeck, or creep) level, N*m or N */
} follower_friction;

/* The bound of the follower's friction one way (sigma = +1: against forward
 * motion, -1: backward), on one branch of the meshing law: the solution of
 * T_F = T_F0 + tau_mesh(T_F) at full strength, with T_F0 = -s*r_F*f, is
 * affine in the contact force f on each side of a = c0 - sigma*s*r_F*f = 0:
 * bound(f) = level + c0*(1 + q) - sigma*q*s*r_F*f, with q = q_fd where the
 * follower drives (a >= 0) and -q_bd where the base drives. A mesh that
 * self-locks (q_fd < 0) has no bound that way. */
typedef struct {
    gs_real constant; /* level + c0*(1 + q) */
    gs_real q;
    int follower_drives; /* the branch a >= 0 */
    int unbounded;       /* self-locking that way: no bound */
} friction_bound;

static inline friction_bound bound_branch(const follower_friction *fr, int follower_drives)
{
    friction_bound b = {fr->level, GS_R(0.0), follower_drives, 0};
    if (fr->law->lossy) {
        if (follower_drives) {
            b.q = fr->law->q_fd;
            b.unbounded = b.q < GS_R(0.0);
        } else {
            b.q = -fr->law->q_bd;
        }
        b.constant = fr->level + fr->law->c0 * (GS_R(1.0) + b.q);
    }
    return b;
}

/* Which branch the law is on at the tooth torque lever_f = s*r_F*f. */
static inline int follower_drives_at(const follower_friction *fr, gs_real sigma, gs_real lever_f)
{
    return fr->law->c0 - sigma * lever_f >= GS_R(0.0);
}

static inline friction_bound bound_at(const follower_friction *fr, gs_real sigma, gs_real lever_f)
{
    return bound_branch(fr, fr->law->lossy && follower_drives_at(fr, sigma, lever_f));
}

static inline gs_real bound_value(const friction_bound *b, gs_real sigma, gs_real lever_f)
{
    return b->constant - sigma * b->q * lever_f;
}

/* One sub-step sliding the way sigma against the bound b, solved jointly
 * with the contact: the friction on the follower, -sigma*bound(f), is the law
 * at the sub-step's own force f. Its part in f, q*s*r_F*f, adds to the
 * contact's pull on the follower: the contact sees the follower's inverse
 * mass times (1 + q), its constants scaled by lambda = 1 + bound_gain*q
 * (h/m_eff times lambda). (Taking the bound at the last sub-step's force, as
 * until 2026-11, rang where the contact answers rigidly and the follower
 * drives: the force alternated about the consistent one with a gain of up to
 * q_fd, and an efficiency of 0.5 or less on locked teeth, 0.15 on the full
 * laws, settled on wrong torques or never.) */
static GS_ALWAYS_INLINE substep_end contact_against(const rig_consts_ *r, contact_state *c, gs_real w_b_free,
                                                    gs_real momentum, gs_real sigma, const friction_bound *b,
                                                    gs_real lever_f_guess, gs_real *friction)
{
    const gs_real lambda = GS_R(1.0) + r->bound_gain * b->q;
    if (!(b->q > GS_R(0.0) || b->q < GS_R(0.0)) || !(lambda > GS_R(0.0))) {
        /* a bound that does not change with the force, or (lambda <= 0: an
         * efficiency of 0 where the base drives, only by rounding) one held
         * at the guess */
        *friction = -sigma * bound_value(b, sigma, lever_f_guess);
        return contact_moving(r, c, w_b_free, (momentum + r->substep * *friction) * r->inv_driven_inertia_sub);
    }
    const gs_real w_f_free = (momentum - r->substep * sigma * b->constant) * r->inv_driven_inertia_sub;
    gs_contact_step_ scaled;
    const gs_contact_step_ *cs = &scaled;
    if (r->friction_contacts_fixed) { /* each branch's constants, scaled at init */
        cs = b->follower_drives ? &r->contact_fd : &r->contact_bd;
    } else {
        gs_contact_scale(&r->contact, lambda, &scaled);
    }
    substep_end e;
    const gs_real u_free = r->mesh.base_radius * w_b_free - r->follower_lever * w_f_free;
    e.u = gs_contact_solve(&r->mesh, cs, c->x, u_free, c->f, &c->locked, &e.f, &e.f_spring);
    e.w_f = w_f_free + r->follower_kick * (GS_R(1.0) + b->q) * e.f;
    e.w_b = w_b_free - r->base_kick * e.f;
    *friction = -sigma * bound_value(b, sigma, r->follower_lever * e.f);
    return e;
}

/* contact_against where the compiler decides: the generic sub-steps and the
 * rare branch changes (slide_other_branch) share it, and GCC keeps it out of
 * line, one copy. (Forced out of line, GS_NOINLINE, it cost the torque-driven
 * backlash scenarios 20 % at -O2: docs/performance.md, sixth round.) */
static inline substep_end contact_against_shared(const rig_consts_ *r, contact_state *c, gs_real w_b_free,
                                                 gs_real momentum, gs_real sigma, const friction_bound *b,
                                                 gs_real lever_f_guess, gs_real *friction)
{
    return contact_against(r, c, w_b_free, momentum, sigma, b, lever_f_guess, friction);
}

/* slide() where the first branch was not consistent with its own force: the
 * other branch, and where that is not either, the kink between them (a = 0,
 * the bound level + c0), where the force then sits. */
static substep_end slide_other_branch(const rig_consts_ *r, const follower_friction *fr, contact_state *c,
                                      gs_real w_b_free, gs_real momentum, gs_real sigma, int first_drives,
                                      gs_real lever_f_guess, gs_real *friction)
{
    const int locked = c->locked;
    friction_bound b = bound_branch(fr, !first_drives);
    if (!b.unbounded) {
        const substep_end e = contact_against_shared(r, c, w_b_free, momentum, sigma, &b, lever_f_guess, friction);
        if (follower_drives_at(fr, sigma, r->follower_lever * e.f) == b.follower_drives) {
            return e;
        }
        c->locked = locked;
    }
    b.constant = fr->level + fr->law->c0;
    b.q = GS_R(0.0);
    return contact_against_shared(r, c, w_b_free, momentum, sigma, &b, lever_f_guess, friction);
}

/* Sliding the way sigma, the law on its branch at the force lever_f_guess
 * first (slide_other_branch where that is not consistent). *friction is the
 * friction torque on the follower. Returns 0 (no solve) where the mesh
 * self-locks that way at the guess. inline_solve (the one-sub-step copy):
 * the first solve inline, one for either bound; otherwise the shared copy. */
static GS_ALWAYS_INLINE int slide(const rig_consts_ *r, const follower_friction *fr, contact_state *c, gs_real w_b_free,
                                  gs_real momentum, gs_real sigma, gs_real lever_f_guess, substep_end *e,
                                  gs_real *friction, const int inline_solve)
{
    if (!inline_solve && !fr->law->lossy) {
        /* the load's friction alone, a constant bound, in a call of its own
         * (one call for both bounds made GCC's -O2 code for the generic
         * sub-steps 25 % slower on the torque-driven full-law scenario) */
        const friction_bound level = {fr->level, GS_R(0.0), 0, 0};
        *e = contact_against_shared(r, c, w_b_free, momentum, sigma, &level, lever_f_guess, friction);
        return 1;
    }
    const int locked = c->locked;
    /* without a meshing loss the bound is the load's friction alone, a
     * constant with no branches to check */
    const friction_bound b = bound_at(fr, sigma, lever_f_guess);
    if (b.unbounded) {
        return 0;
    }
    *e = inline_solve ? contact_against(r, c, w_b_free, momentum, sigma, &b, lever_f_guess, friction)
                      : contact_against_shared(r, c, w_b_free, momentum, sigma, &b, lever_f_guess, friction);
    if (!fr->law->lossy || follower_drives_at(fr, sigma, r->follower_lever * e->f) == b.follower_drives) {
        return 1;
    }
    c->locked = locked;
    *e = slide_other_branch(r, fr, c, w_b_free, momentum, sigma, b.follower_drives, lever_f_guess, friction);
    return 1;
}

/* One sub-step with the follower's friction, set-valued at rest, solved
 * with the contact by backward Euler. momentum is J_F*w_F + h*(every other
 * torque but the contact and the friction). The joint solution is one of
 * three: sliding on in the current direction, stuck, or sliding the other
 * way; they are tried in that order and the first consistent one is taken,
 * so a sub-step costs one contact solve while sliding on (more where the
 * law changes branch) and at most three (five with the static-contact lock:
 * a locked follower moves with the base whatever its friction does, so a
 * fourth solve makes the friction oppose that motion; if that releases the
 * lock and the follower turns back, or the mesh has no bound that way, the
 * lock's hysteresis leaves no consistent friction, and a fifth runs the
 * sub-step without it, which never does negative work). One loop over the
 * stages, so that the solve is inlined once. *friction is the friction
 * torque on the follower. */
typedef enum { STAGE_SLIDE_ON, STAGE_STUCK, STAGE_AGAINST_PUSH, STAGE_AGAINST_LOCKED, STAGE_NONE } friction_stage;

static GS_ALWAYS_INLINE substep_end substep_with_friction(const rig_consts_ *r, const follower_friction *fr,
                                                          contact_state *c, gs_real w_f, gs_real w_b_free,
                                                          gs_real momentum, gs_real *friction, friction_mode *mode,
                                                          const int inline_solve)
{
    const int locked = c->locked;
    gs_real guess = r->follower_lever * c->f; /* the force that picks the law's branch */
    gs_real sigma = w_f > GS_R(0.0) ? GS_R(1.0) : GS_R(-1.0);
    friction_stage stage = w_f > GS_R(0.0) || w_f < GS_R(0.0) ? STAGE_SLIDE_ON : STAGE_STUCK;
    substep_end e;
    for (;;) {
        if (stage == STAGE_STUCK) {
            e = contact_stuck(r, c, w_b_free);
            /* J_F*(0 - w_F) = h*(others + s*r_F*f + friction), the bounds at this f */
            const gs_real lever_f = r->follower_lever * e.f;
            const gs_real needed = -(momentum * r->contact.inv_h + lever_f);
            const friction_bound fwd = bound_at(fr, GS_R(1.0), lever_f);
            const friction_bound bwd = bound_at(fr, GS_R(-1.0), lever_f);
            if ((fwd.unbounded || needed >= -bound_value(&fwd, GS_R(1.0), lever_f)) &&
                (bwd.unbounded || needed <= bound_value(&bwd, GS_R(-1.0), lever_f))) {
                *friction = needed;
                *mode = FRICTION_STUCK;
                return e;
            }
            c->locked = locked;
            /* against the way the rest pushes (a bound that way: the other
             * was not exceeded) */
            sigma = needed < GS_R(0.0) ? GS_R(1.0) : GS_R(-1.0);
            guess = lever_f;
            stage = STAGE_AGAINST_PUSH;
            continue;
        }
        if (stage == STAGE_NONE) {
            *friction = GS_R(0.0);
            *mode = FRICTION_NONE;
            return contact_moving(r, c, w_b_free, momentum * r->inv_driven_inertia_sub);
        }
        if (!slide(r, fr, c, w_b_free, momentum, sigma, guess, &e, friction, inline_solve)) {
            stage = stage == STAGE_SLIDE_ON ? STAGE_STUCK : STAGE_NONE;
            continue;
        }
        *mode = sigma > GS_R(0.0) ? FRICTION_FORWARD : FRICTION_BACKWARD;
        /* sliding on: at exactly 0 any friction within the bounds is consistent */
        if (stage == STAGE_SLIDE_ON ? !(sigma * e.w_f < GS_R(0.0)) : *friction * e.w_f <= GS_R(0.0)) {
            return e;
        }
        c->locked = locked;
        if (stage == STAGE_AGAINST_PUSH) {
            sigma = e.w_f > GS_R(0.0) ? GS_R(1.0) : GS_R(-1.0);
            guess = r->follower_lever * e.f;
            stage = STAGE_AGAINST_LOCKED;
        } else {
            stage = stage == STAGE_SLIDE_ON ? STAGE_STUCK : STAGE_NONE;
        }
    }
}

/* The follower's friction in one sub-step with backlash: the meshing loss
 * (physics.md 4.6), a set-valued friction on the follower added to the
 * load's Coulomb friction, taken at the sub-step's own contact force; it
 * holds the follower at rest within its bounds and opposes its motion beyond
 * them. Returns the sub-step's end and the meshing loss that acted
 * (*tau_mesh, against the follower's motion), and sets *t_f, the net
 * follower torque T_F of the law on that force (the base load of the 2-D
 * table: T_F0 at rest). Inline, with its stages, into each copy of the
 * sub-steps that has friction (inline_solve: slide()). */
static GS_ALWAYS_INLINE substep_end substep_friction(const rig_consts_ *r, const gs_mesh_friction_ *law,
                                                     contact_state *c, gs_real w_f, gs_real w_b_free, gs_real momentum,
                                                     gs_real *tau_mesh, gs_real *t_f, const int inline_solve)
{
    /* Regularised, the load's friction bound is the smooth law at the
     * sub-step's start speed, F(v)*|tanh(4 v/v_th)|: zero at rest, so the
     * driven side creeps instead of sticking, and, solved jointly with the
     * contact like the Coulomb bound, it never reverses the motion. (A
     * damper applied before the contact, then the contact, created energy
     * where the contact turned the follower within the sub-step: fuzz
     * finding.) */
    const follower_friction fr = {law, r->friction_regularised ? gs_rig_creep_level(r, w_f) : friction_level(r, w_f)};
    gs_real friction = GS_R(0.0);
    friction_mode mode = FRICTION_NONE;
    substep_end e;
    if (law->lossy || fr.level > GS_R(0.0) || fr.level < GS_R(0.0)) {
        e = substep_with_friction(r, &fr, c, w_f, w_b_free, momentum, &friction, &mode, inline_solve);
    } else {
        e = contact_moving(r, c, w_b_free, momentum * r->inv_driven_inertia_sub);
    }
    /* the meshing loss's share of the friction (it acts on the follower as
     * -tau_mesh): all of it beyond the load's level; at rest the load's
     * friction holds what it can and the mesh the rest */
    const gs_real t_f0 = -r->follower_lever * e.f;
    *t_f = t_f0;
    switch (mode) {
    case FRICTION_FORWARD:
        *tau_mesh = -friction - fr.level;
        *t_f = t_f0 + *tau_mesh;
        break;
    case FRICTION_BACKWARD:
        *tau_mesh = -friction + fr.level;
        *t_f = t_f0 + *tau_mesh;
        break;
    case FRICTION_STUCK:
        *tau_mesh = gs_clamp(friction, -fr.level, fr.level) - friction;
        break;
    case FRICTION_NONE:
        *tau_mesh = GS_R(0.0);
        break;
    }
    return e;
}

/* The step's sub-steps. Its four copies (two free-follower ones inline in
 * gs_rig_backlash_step, two friction ones in functions of their own) fix
 * some of speed_driven, free_follower and one_substep (the count known to be
 * 1) to constants, so that each keeps only its own branches, and the
 * one-sub-step copies no loop state (docs/performance.md, fourth and sixth
 * rounds). */
static GS_ALWAYS_INLINE void backlash_substeps(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx,
                                               const gs_mesh_friction_ *law, const gs_rig_input *in, gs_rig_output *out,
                                               const int speed_driven, const int free_follower, const int one_substep)
{
    const gs_mesh_ *m = &r->mesh;
    const int n = one_substep ? 1 : r->substeps;
    const gs_real h = r->substep;
    const int law_per_substep = r->law_per_substep;
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
            e = substep_friction(r, law_k, &c, w_f, w_b_free, momentum, &tau_mesh, &t_f, one_substep);
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
        if (!free_follower) {
            sum_tau_mesh += tau_mesh;
            sum_mesh += tau_mesh * w_f;
        }
    }
    st->block.backlash_position = c.x;
    st->block.contact_force = c.f;
    st->block.contact_locked = c.locked;
    st->block.follower_torque = free_follower ? -r->follower_lever * c.f : t_f;
    st->base_speed = w_b;
    st->follower_speed = w_f;
    st->base_angle = theta_b;
    st->follower_position = x_f;
    const gs_real inv_n = one_substep ? GS_R(1.0) : r->inv_substeps; /* x*1 is x: the same bits */
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

/* The speed-driven friction path at one sub-step, in a function of its own:
 * its friction stages and its first solve inline (inline_solve), while the
 * generic copy (below) keeps the compiler's choices. (In one function, the
 * two copies made GCC move the friction stages out of line: the generic
 * copy then cost 12-19 % more on the torque-driven backlash scenarios.) */
static GS_NOINLINE void backlash_one_substep_friction(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx,
                                                      const gs_mesh_friction_ *law, const gs_rig_input *in,
                                                      gs_rig_output *out)
{
    backlash_substeps(r, st, ctx, law, in, out, 1, 0, 1);
}

/* The generic friction copy (a torque-driven base, or several sub-steps),
 * also a function of its own: gs_rig_backlash_step's frame, held below
 * either friction copy, is then only the free copies' (the step's
 * worst-case stack on the Cortex-M4F: 1136 -> 968 B at -Os). */
static GS_NOINLINE void backlash_friction_substeps(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx,
                                                   const gs_mesh_friction_ *law, const gs_rig_input *in,
                                                   gs_rig_output *out, const int speed_driven)
{
    backlash_substeps(r, st, ctx, law, in, out, speed_driven, 0, 0);
}

void gs_rig_backlash_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_mesh_friction_ *law,
                          const gs_rig_input *in, gs_rig_output *out)
{
    const int speed_driven = r->base_drive == GS_BASE_SPEED_DRIVEN;
    if (!r->follower_free) {
        if (speed_driven && r->substeps == 1) {
            /* the same usual choice with friction on the follower */
            backlash_one_substep_friction(r, st, ctx, law, in, out);
        } else {
            backlash_friction_substeps(r, st, ctx, law, in, out, speed_driven);
        }
    } else if (speed_driven && r->substeps == 1) {
        /* the automatic count's usual choice at 1 kHz: the cheapest copy */
        backlash_substeps(r, st, ctx, law, in, out, 1, 1, 1);
    } else {
        backlash_substeps(r, st, ctx, law, in, out, speed_driven, 1, 0);
    }
}

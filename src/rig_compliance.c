/* rig_compliance.c - the rig's compliant base shaft (rig_internal.h): a
 * spring and damper between the speed-driven drive and the base gear, which
 * the geared solve (rig_geared.h) couples to the driven side in each of the
 * shaft's sub-steps. */
#include "rig_geared.h"

/* The compliant shaft (speed-driven base, rigid mesh): the drive turns at
 * the input speed, ramped linearly from the last sample over the step; a
 * spring k and damper c carry its torque to the base gear (J_B), which turns
 * the driven side through the rigid mesh. Per sub-step h the shaft follows
 * the implicit midpoint rule, with phi the twist (drive minus gear angle):
 *   phi' = phi + h*(w_d - (w + w')/2),  tau_s = k*(phi + phi')/2 + c*(w_d - (w + w')/2),
 * which is tau_s = k*phi + g*(w_d - w/2) - (g/2)*w' with g = k*h/2 + c: an
 * explicit torque and an implicit slope g/2 for gs_rig_geared_solve. The rule
 * keeps the undamped shaft's energy exactly and is stable at any k*h^2/J.
 * Its kinetic energy changes by the work at the mean speed (w + w')/2, so
 * the dissipative torques (viscous, friction, meshing loss), which act
 * against the end speed w', must not point along that mean: where they
 * would (the gear stops or reverses within the sub-step against a friction
 * holding it) the sub-step is solved again with the gear's angle advanced
 * by the end speed, phi' = phi + h*(w_d - w'), tau_s = k*(phi + phi')/2 +
 * c*(w_d - w'), whose kinetic energy changes by the work at w' and which is
 * passive for any friction (physics.md 11). */
void gs_rig_compliant_step(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx,
                           const gs_mesh_friction_ *law, const gs_rig_input *in, gs_real w_d_start, gs_rig_output *out)
{
    const int law_per_substep = r->law_per_substep;
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real h = r->compliance_h;
    const gs_real inv_h = r->inv_compliance_h;
    const gs_real g = r->compliance_gain;
    const gs_real push = in->load + r->load_offset;
    const gs_real w_f_start = st->follower_speed;
    const gs_real ramp = (in->base_speed - w_d_start) * r->inv_compliance_substeps;
    const int n = r->compliance_substeps;
    gs_mesh_friction_ table_law; /* the 2-D table's law after the first sub-step */
    const gs_mesh_friction_ *law_sub = law;
    /* the state in locals over the sub-steps, written back once */
    gs_real w = st->base_speed, w_f = w_f_start, phi = st->shaft_twist, t_f = st->block.follower_torque;
    gs_real theta_b = st->base_angle, x_f = st->follower_position;
    gs_real sum_shaft = GS_R(0.0), sum_tau_b = GS_R(0.0), sum_tau_f = GS_R(0.0);
    gs_real sum_mesh = GS_R(0.0), sum_loss = GS_R(0.0), sum_port = GS_R(0.0);
    for (int k = 0; k < n; ++k) {
        if (law_per_substep && k > 0) {
            gs_mesh_friction_law(m, ctx, t_f, &table_law);
            law_sub = &table_law;
        }
        /* the ramped drive speed at the sub-step's middle: its mean over the sub-step */
        const gs_real w_d = w_d_start + ramp * ((gs_real)k + GS_R(0.5));
        gs_real ripple = GS_R(0.0);
        if (r->ripple) {
            /* at the mid angle the start speed predicts: with the angle
             * advanced by the mean speed the map stays area-preserving */
            ripple = gs_rig_ripple_torque(r, theta_b + GS_R(0.5) * h * w);
        }
        const gs_real spring = r->stiffness * phi - ripple;
        gs_mesh_friction_ law_now;
        const gs_mesh_friction_ *law_k = gs_rig_step_law(r, law_sub, t_f, a * w, &law_now);
        /* The midpoint rule first. The dissipative torque on the base gear
         * (base-referred) opposes w', and so the mean speed too, unless the
         * gear stops or turns within the sub-step; where it would not, the
         * end-speed rule. One call site, so that the solve is inlined once. */
        int end_speed_rule = 0;
        geared_end e;
        gs_real w_adv;
        for (;;) {
            const geared_base_ *base = end_speed_rule ? &r->geared_base_end : &r->geared_base;
            const gs_real drive = end_speed_rule ? spring + g * w_d : spring + g * (w_d - GS_R(0.5) * w);
            e = gs_rig_geared_solve(r, law_k, h, inv_h, base, w, drive, push);
            if (end_speed_rule) {
                w_adv = e.w;
                break;
            }
            w_adv = GS_R(0.5) * (w + e.w);
            if (w * e.w > GS_R(0.0) ||
                !((m->mu_base * e.w + a * (e.coulomb + m->mu_follower * a * e.w + e.tau_mesh)) * w_adv < GS_R(0.0))) {
                break;
            }
            end_speed_rule = 1;
        }
        const gs_real phi_end = phi + h * (w_d - w_adv);
        const gs_real tau_shaft = GS_R(0.5) * r->stiffness * (phi + phi_end) + r->shaft_damping * (w_d - w_adv);
        w = e.w;
        w_f = a * w;
        t_f = e.t_f;
        phi = phi_end;
        const gs_real tau_b = m->mu_base * w + a * (e.tau_mesh - t_f);
        const gs_real tau_f = t_f + m->mu_follower * w_f;
        /* the angles with the speed the twist used */
        theta_b += h * w_adv;
        x_f += h * a * w_adv;
        const gs_real mesh_power = e.tau_mesh * w_f;
        sum_shaft += tau_shaft;
        sum_tau_b += tau_b;
        sum_tau_f += tau_f;
        sum_mesh += mesh_power;
        sum_loss += mesh_power + m->mu_base * w * w + m->mu_follower * w_f * w_f;
        sum_port += tau_b * w + tau_f * w_f;
    }
    st->block.follower_torque = t_f;
    st->shaft_twist = phi;
    st->base_speed = w;
    st->follower_speed = w_f;
    st->base_angle = theta_b;
    st->follower_position = x_f;
    const gs_real inv_n = r->inv_compliance_substeps;
    out->base_torque = sum_shaft * inv_n;
    out->base_port_torque = sum_tau_b * inv_n;
    out->follower_port_torque = sum_tau_f * inv_n;
    out->mesh_loss_power = sum_mesh * inv_n;
    out->loss_power = sum_loss * inv_n;
    out->port_power = sum_port * inv_n;
    out->follower_acceleration = (w_f - w_f_start) / r->dt;
}

/* run_rig.c - step a Simple Gear rig and a Rack & Pinion rig and print a table.
 * A speed-driven base ramps up, cruises and reverses; the follower carries an
 * inertia and a load torque. */
#include <stdio.h>

#include "gearsim/gearsim.h"

static int run_gear(void)
{
    gs_simple_gear_params gear = gs_simple_gear_params_default();
    gear.teeth_ratio = GS_R(3.0);
    gear.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    gear.efficiency_const = GS_R(0.95);
    gear.viscous_coefficients[0] = GS_R(1e-3);
    gs_rig_params rp = gs_rig_params_default();
    rp.driven_inertia = GS_R(0.05);
    gs_rig_consts consts; /* what init derives: read-only afterwards */
    gs_rig_state state;   /* what a step updates */
    gs_error err;
    if (gs_rig_init_gear(&consts, &state, &gear, &rp, &err) != GS_OK) {
        fprintf(stderr, "gear rig: %s: %s\n", err.parameter, err.message);
        return 1;
    }
    printf("Simple Gear rig (ratio 3, opposite, efficiency 0.95), dt = 1 ms\n");
    printf("%8s %12s %12s %14s %14s %12s\n", "t [s]", "w_B [rad/s]", "load [N*m]", "tau_B [N*m]", "w_F [rad/s]",
           "P_loss [W]");
    for (int i = 0; i <= 3000; ++i) {
        const gs_real t = GS_R(1e-3) * (gs_real)i;
        gs_rig_input in = {0};
        in.base_speed = t < GS_R(1.0) ? GS_R(100.0) * t : (t < GS_R(2.0) ? GS_R(100.0) : GS_R(300.0) - GS_R(100.0) * t);
        in.load = GS_R(-6.0);
        in.ambient_temperature = GS_R(293.15);
        gs_rig_output out;
        gs_rig_step(&consts, &state, &in, &out);
        if (i % 250 == 0) {
            printf("%8.3f %12.3f %12.3f %14.5f %14.5f %12.4f\n", (double)t, (double)in.base_speed, (double)in.load,
                   (double)out.base_torque, (double)out.follower_speed, (double)out.loss_power);
        }
    }
    return 0;
}

static int run_rack(void)
{
    gs_rack_pinion_params rack = gs_rack_pinion_params_default();
    rack.parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS;
    rack.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    gs_rig_params rp = gs_rig_params_default();
    rp.driven_inertia = GS_R(10.0); /* rack mass, kg */
    rp.load_coulomb_friction = GS_R(20.0);
    gs_rig_consts consts;
    gs_rig_state state;
    gs_error err;
    if (gs_rig_init_rack(&consts, &state, &rack, &rp, &err) != GS_OK) {
        fprintf(stderr, "rack rig: %s: %s\n", err.parameter, err.message);
        return 1;
    }
    printf("\nRack & Pinion rig (20 teeth x 5 mm, efficiency 0.8, rack 10 kg, Coulomb 20 N)\n");
    printf("%8s %12s %14s %14s %14s\n", "t [s]", "w_P [rad/s]", "tau_P [N*m]", "v_R [m/s]", "x_R [m]");
    for (int i = 0; i <= 2000; ++i) {
        const gs_real t = GS_R(1e-3) * (gs_real)i;
        gs_rig_input in = {0};
        in.base_speed = t < GS_R(1.0) ? GS_R(20.0) : GS_R(-20.0);
        gs_rig_output out;
        gs_rig_step(&consts, &state, &in, &out);
        if (i % 250 == 0) {
            printf("%8.3f %12.3f %14.5f %14.5f %14.5f\n", (double)t, (double)in.base_speed, (double)out.base_torque,
                   (double)out.follower_speed, (double)out.follower_position);
        }
    }
    return 0;
}

int main(void)
{
    return run_gear() != 0 || run_rack() != 0;
}

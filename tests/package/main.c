/* A consumer of the installed package: found with find_package(gearsim) or
 * pkg-config, it steps a default gear rig at constant speed. With the load
 * torque L on the follower and the rigid ideal gear (ratio 2, opposite), the
 * base torque is L/2 (physics.md 1.2). */
#include <stdio.h>

#include "gearsim/gearsim.h"

int main(void)
{
    gs_rig rig;
    gs_error err;
    const gs_simple_gear_params gear = gs_simple_gear_params_default();
    const gs_rig_params params = gs_rig_params_default();
    if (gs_rig_init_gear(&rig, &gear, &params, &err) != GS_OK) {
        fprintf(stderr, "init: %s: %s\n", err.parameter, err.message);
        return 1;
    }
    gs_rig_input in = {0};
    in.base_speed_rad_s = GS_R(10.0);
    in.load = GS_R(1.0);
    gs_rig_output out;
    gs_rig_step(&rig, &in, &out);
    gs_rig_step(&rig, &in, &out);
    printf("gearsim %s: base torque %g N*m (expected 0.5)\n", GS_VERSION_STRING, (double)out.base_torque_Nm);
    return (out.base_torque_Nm > GS_R(0.4999999) && out.base_torque_Nm < GS_R(0.5000001)) ? 0 : 1;
}

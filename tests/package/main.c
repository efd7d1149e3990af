/* A consumer of gearsim as a user builds it: found with find_package(gearsim)
 * (tests/package/CMakeLists.txt), with pkg-config, embedded with
 * add_subdirectory() (tests/package/subproject), and in the root's tests
 * (build.version). It prints the library's version and steps a default gear
 * rig at constant speed. With the load torque L on the follower and the rigid
 * ideal gear (ratio 2, opposite), the base torque is L/2 (physics.md 1.2).
 * Exits non-zero when the library's gs_version() differs from the header's
 * GS_VERSION_STRING (a stale library) or the torque is off. */
#include <stdio.h>
#include <string.h>

#include "gearsim/gearsim.h"

int main(void)
{
    gs_rig_consts consts;
    gs_rig_state state;
    gs_error err;
    const gs_simple_gear_params gear = gs_simple_gear_params_default();
    const gs_rig_params params = gs_rig_params_default();
    const char *version = gs_version();
    printf("gs_version() = %s (header GS_VERSION_STRING = %s)\n", version, GS_VERSION_STRING);
    if (strcmp(version, GS_VERSION_STRING) != 0) {
        fprintf(stderr, "library version %s differs from the header's %s\n", version, GS_VERSION_STRING);
        return 1;
    }
    if (gs_rig_init_gear(&consts, &state, &gear, &params, &err) != GS_OK) {
        fprintf(stderr, "init: %s: %s\n", err.parameter, err.message);
        return 1;
    }
    gs_rig_input in = {0};
    in.base_speed = GS_R(10.0);
    in.load = GS_R(1.0);
    gs_rig_output out;
    gs_rig_step(&consts, &state, &in, &out);
    gs_rig_step(&consts, &state, &in, &out);
    printf("gear rig: base torque %g N*m (expected 0.5), state %u B, constants %u B\n", (double)out.base_torque,
           (unsigned)sizeof state, (unsigned)sizeof consts);
    return (out.base_torque > GS_R(0.4999999) && out.base_torque < GS_R(0.5000001)) ? 0 : 1;
}

/* status.c - status descriptions and the library version. */
#include "gearsim/types.h"

const char *gs_status_str(gs_status status)
{
    switch (status) {
    case GS_OK:
        return "ok";
    case GS_E_NULL:
        return "a required pointer is NULL";
    case GS_E_NOT_FINITE:
        return "value is NaN or infinite";
    case GS_E_NOT_POSITIVE:
        return "value must be greater than zero";
    case GS_E_NEGATIVE:
        return "value must not be negative";
    case GS_E_EFFICIENCY_RANGE:
        return "efficiency must lie in (0, 1]";
    case GS_E_NOMINAL_EFFICIENCY:
        return "nominal efficiency must lie in (0, 1)";
    case GS_E_IDLE_TORQUE_TOO_LARGE:
        return "idle torque too large for the nominal point: teeth_ratio*idle_torque must not exceed "
               "nominal_output_torque*(1/efficiency_nominal - 1)";
    case GS_E_OPTION:
        return "value is not one of the option's values";
    case GS_E_TABLE_LENGTH:
        return "table needs at least 2 and at most GS_TABLE_MAX entries";
    case GS_E_TABLE_NOT_INCREASING:
        return "table breakpoints must be strictly increasing";
    case GS_E_TABLE_SIZE_MISMATCH:
        return "table data length differs from its breakpoints";
    case GS_E_BACKLASH_POSITION:
        return "initial backlash position must lie in [-b/2, b/2]";
    case GS_E_TRANSITION_REGION:
        return "transition region must be greater than zero";
    case GS_E_STEP_SIZE:
        return "step size must be finite and greater than zero";
    case GS_E_SUBSTEPS:
        return "contact sub-steps must lie in [0, GS_MAX_SUBSTEPS]";
    case GS_E_MAGNITUDE:
        return "value is so small that its reciprocal overflows";
    case GS_E_BREAKAWAY:
        return "breakaway friction must be 0 (none) or at least load_coulomb_friction";
    case GS_E_COMBINATION:
        return "not available with the other options: compliance needs a speed-driven base and "
               "a rigid mesh (no backlash)";
    }
    return "unknown status";
}

const char *gs_version(void)
{
    return GS_VERSION_STRING;
}

/*
 * gearsim/hil_dbc.h - the frame tables of the DBC files in hil/dbc, built
 * into the gearsim_hil library by hil/dbc_tables.py at build time (CMake).
 * The Python package makes its tables from the DBC files at run time and
 * does not have these.
 */
#ifndef GEARSIM_HIL_DBC_H
#define GEARSIM_HIL_DBC_H

#include "gearsim/hil.h"

#ifdef __cplusplus
extern "C" {
#endif

extern const gs_hil_dbc gs_hil_dbc_gear_rig; /* hil/dbc/gear_rig.dbc */
extern const gs_hil_dbc gs_hil_dbc_rack_rig; /* hil/dbc/rack_rig.dbc */

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_HIL_DBC_H */

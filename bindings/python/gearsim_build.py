"""cffi build script (API mode) of the extension module ``gearsim._gearsim``.

This file is the one place where the C declarations seen by Python live.
Enum values and ``#define`` constants are written ``...`` so that the C compiler
fills them in from ``include/gearsim``; structs end with ``...;`` so that their
layout comes from the compiler as well. The sources of ``src/`` are compiled
into the extension (double precision: ``GS_SINGLE_PRECISION`` is not defined),
so there is one copy of the physics, the C one. ``SHIM`` is the bindings' own
C (no physics): the per-step entry point of ``Rig.step``.

Used by ``setup.py`` (``cffi_modules``); can also be run directly to build the
extension in place: ``python bindings/python/gearsim_build.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from cffi import FFI

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent  # repository root: include/ and src/ live there
INCLUDE_DIR = ROOT / "include"
SRC_DIR = ROOT / "src"

CDEF = r"""
#define GS_VERSION_MAJOR ...
#define GS_VERSION_MINOR ...
#define GS_VERSION_PATCH ...
static const char *const GS_VERSION_STRING;
#define GS_TABLE_MAX ...
#define GS_MAX_SUBSTEPS ...
#define GS_RIG_INPUT_FIELDS ...
#define GS_RIG_OUTPUT_FIELDS ...

typedef double... gs_real;

typedef enum {
    GS_OK = ...,
    GS_E_NULL = ...,
    GS_E_NOT_FINITE = ...,
    GS_E_NOT_POSITIVE = ...,
    GS_E_NEGATIVE = ...,
    GS_E_EFFICIENCY_RANGE = ...,
    GS_E_NOMINAL_EFFICIENCY = ...,
    GS_E_IDLE_TORQUE_TOO_LARGE = ...,
    GS_E_OPTION = ...,
    GS_E_TABLE_LENGTH = ...,
    GS_E_TABLE_NOT_INCREASING = ...,
    GS_E_TABLE_SIZE_MISMATCH = ...,
    GS_E_BACKLASH_POSITION = ...,
    GS_E_TRANSITION_REGION = ...,
    GS_E_STEP_SIZE = ...,
    GS_E_SUBSTEPS = ...,
    GS_E_MAGNITUDE = ...
} gs_status;

const char *gs_status_str(gs_status status);

typedef struct {
    gs_status status;
    const char *parameter;
    const char *message;
    ...;
} gs_error;

typedef enum {
    GS_FRICTION_NONE = ...,
    GS_FRICTION_CONSTANT_EFFICIENCY = ...,
    GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY = ...,
    GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY = ...,
    GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY = ...
} gs_friction_model;

typedef enum {
    GS_SMOOTHING_PASSIVE = ...,
    GS_SMOOTHING_SIMSCAPE = ...
} gs_loss_smoothing;

typedef enum {
    GS_HARD_STOP_SMOOTH = ...,
    GS_HARD_STOP_FULL_UNDAMPED = ...,
    GS_HARD_STOP_FULL_DAMPED = ...
} gs_hard_stop_model;

typedef struct {
    int enabled;
    gs_hard_stop_model hard_stop_model;
    gs_real linear_backlash_m;
    gs_real base_radius_m;
    gs_real transition_region_m;
    gs_real stiffness_N_m;
    gs_real damping_N_s_m;
    gs_real initial_position_m;
    int no_pull;
    int lock_enabled;
    gs_real contact_speed_threshold_m_s;
    gs_real contact_release_force_N;
    ...;
} gs_backlash_params;

typedef struct { ...; } gs_mesh_;

/* ---- simple_gear.h */
typedef enum {
    GS_ROTATES_SAME = ...,
    GS_ROTATES_OPPOSITE = ...
} gs_output_rotation;

typedef struct {
    gs_real teeth_ratio;
    gs_output_rotation output_shaft_rotates;
    gs_friction_model friction_model;
    gs_loss_smoothing loss_smoothing;
    gs_real efficiency_const;
    gs_real power_threshold_W;
    gs_real idle_torque_Nm;
    gs_real nominal_output_torque_Nm;
    gs_real efficiency_nominal;
    gs_real speed_threshold_rad_s;
    int temperature_count;
    gs_real temperature_vector_K[...];
    gs_real efficiency_vector[...];
    int load_count;
    gs_real load_vector_Nm[...];
    gs_real efficiency_matrix[...][...];
    gs_backlash_params backlash;
    gs_real viscous_coefficients[...];
    gs_real thermal_mass_J_K;
    gs_real initial_temperature_K;
    ...;
} gs_simple_gear_params;

typedef struct { ...; } gs_simple_gear;

typedef struct {
    gs_real base_speed_rad_s;
    gs_real follower_speed_rad_s;
    gs_real follower_torque_Nm;
    gs_real heat_flow_W;
    gs_real temperature_K;
    int use_temperature_input;
    ...;
} gs_gear_ports_in;

typedef struct {
    gs_real base_torque_Nm;
    gs_real follower_torque_Nm;
    gs_real follower_speed_rad_s;
    gs_real mesh_loss_torque_Nm;
    gs_real mesh_loss_power_W;
    gs_real loss_power_W;
    gs_real temperature_K;
    gs_real backlash_position_m;
    gs_real contact_force_N;
    ...;
} gs_gear_ports_out;

gs_simple_gear_params gs_simple_gear_params_default(void);
gs_status gs_simple_gear_init(gs_simple_gear *gear, const gs_simple_gear_params *params,
                              gs_error *err);
void gs_simple_gear_reset(gs_simple_gear *gear);
void gs_simple_gear_step(gs_simple_gear *gear, gs_real dt_s, const gs_gear_ports_in *in,
                         gs_gear_ports_out *out);

/* ---- rack_pinion.h */
typedef enum {
    GS_PARAMETERIZE_PINION_RADIUS = ...,
    GS_PARAMETERIZE_TOOTH_PARAMETERS = ...
} gs_rack_parameterization;

typedef enum {
    GS_RACK_POSITIVE = ...,
    GS_RACK_NEGATIVE = ...
} gs_rack_direction;

typedef struct {
    gs_rack_parameterization parameterization;
    gs_real pinion_radius_m;
    gs_real teeth_count;
    gs_real spacing_m;
    gs_rack_direction rack_directionality;
    gs_friction_model friction_model;
    gs_loss_smoothing loss_smoothing;
    gs_real efficiency_const;
    int temperature_count;
    gs_real temperature_vector_K[...];
    gs_real efficiency_vector[...];
    gs_real power_threshold_W;
    gs_real pinion_viscous_coefficient;
    gs_real rack_viscous_coefficient;
    gs_real thermal_mass_J_K;
    gs_real initial_temperature_K;
    gs_backlash_params backlash;
    ...;
} gs_rack_pinion_params;

typedef struct { ...; } gs_rack_pinion;

typedef struct {
    gs_real pinion_speed_rad_s;
    gs_real rack_velocity_m_s;
    gs_real rack_force_N;
    gs_real heat_flow_W;
    gs_real temperature_K;
    int use_temperature_input;
    ...;
} gs_rack_ports_in;

typedef struct {
    gs_real pinion_torque_Nm;
    gs_real rack_force_N;
    gs_real rack_velocity_m_s;
    gs_real mesh_loss_force_N;
    gs_real mesh_loss_power_W;
    gs_real loss_power_W;
    gs_real temperature_K;
    gs_real backlash_position_m;
    gs_real contact_force_N;
    ...;
} gs_rack_ports_out;

gs_rack_pinion_params gs_rack_pinion_params_default(void);
gs_real gs_rack_pinion_radius(const gs_rack_pinion_params *params);
gs_status gs_rack_pinion_init(gs_rack_pinion *rp, const gs_rack_pinion_params *params,
                              gs_error *err);
void gs_rack_pinion_reset(gs_rack_pinion *rp);
void gs_rack_pinion_step(gs_rack_pinion *rp, gs_real dt_s, const gs_rack_ports_in *in,
                         gs_rack_ports_out *out);

/* ---- rig.h */
typedef enum {
    GS_BASE_SPEED_DRIVEN = ...,
    GS_BASE_TORQUE_DRIVEN = ...
} gs_base_drive;

typedef enum {
    GS_TEMPERATURE_FROM_MODEL = ...,
    GS_TEMPERATURE_FROM_INPUT = ...
} gs_temperature_source;

typedef enum {
    GS_RIG_SIMPLE_GEAR = ...,
    GS_RIG_RACK_PINION = ...
} gs_rig_block;

typedef struct {
    gs_real dt_s;
    gs_base_drive base_drive;
    gs_real base_inertia_kg_m2;
    gs_real initial_base_speed_rad_s;
    gs_real driven_inertia;
    gs_real load_coulomb_friction;
    gs_real load_coulomb_speed_threshold;
    gs_real load_offset;
    int heat_path;
    gs_real thermal_resistance_K_W;
    gs_temperature_source temperature_source;
    gs_real accel_filter_time_constant_s;
    int contact_substeps;
    ...;
} gs_rig_params;

typedef struct {
    gs_real base_speed_rad_s;
    gs_real base_torque_Nm;
    gs_real load;
    gs_real ambient_temperature_K;
    gs_real measured_temperature_K;
    ...;
} gs_rig_input;

typedef struct {
    gs_real base_torque_Nm;
    gs_real base_speed_rad_s;
    gs_real base_angle_rad;
    gs_real follower_speed;
    gs_real follower_position;
    gs_real base_port_torque_Nm;
    gs_real follower_port_torque;
    gs_real mesh_loss_power_W;
    gs_real loss_power_W;
    gs_real port_power_W;
    gs_real contact_energy_J;
    gs_real temperature_K;
    gs_real backlash_position_m;
    gs_real contact_force_N;
    gs_real follower_acceleration;
    ...;
} gs_rig_output;

typedef struct {
    gs_rig_block block;
    gs_real dt;
    int substeps;
    ...;
} gs_rig;

typedef struct {
    int contact_substeps;
    gs_real contact_h_omega_n;
    int substeps_capped;
    ...;
} gs_rig_info;

gs_rig_params gs_rig_params_default(void);
void gs_rig_get_info(const gs_rig *rig, gs_rig_info *info);
gs_status gs_rig_init_gear(gs_rig *rig, const gs_simple_gear_params *gear,
                           const gs_rig_params *params, gs_error *err);
gs_status gs_rig_init_rack(gs_rig *rig, const gs_rack_pinion_params *rack,
                           const gs_rig_params *params, gs_error *err);
void gs_rig_reset(gs_rig *rig);
void gs_rig_step(gs_rig *rig, const gs_rig_input *in, gs_rig_output *out);
void gs_rig_run(gs_rig *rig, size_t n, const gs_rig_input *in, gs_rig_output *out);

/* ---- the bindings' own C (SHIM below), for Rig.step */
typedef struct {
    gs_rig_output out;
    gs_rig *rig;
    ...;
} gspy_stepper;

int gspy_rig_step(gspy_stepper *s, double base_speed, double base_torque, double load,
                  double ambient_temperature, double measured_temperature);
"""

# C compiled into the extension beside the core (not part of the C API): a
# per-step entry point for Rig.step. One cffi call with the five inputs by value
# replaces writing them into a gs_rig_input from Python, checking them and
# calling gs_rig_step with three pointers (which cffi converts one by one).
SHIM = r"""
#include <math.h>

/* The output of the last step of one rig (first: Rig.step reads it from the
   start of the struct), and that rig (owned by the caller). */
typedef struct {
    gs_rig_output out;
    gs_rig *rig;
} gspy_stepper;

/* One gs_rig_step with these inputs into s->out; returns 0. Returns 1 without
   stepping when an input is not finite (Rig.step then finds and names it). */
static int gspy_rig_step(gspy_stepper *s, double base_speed, double base_torque, double load,
                         double ambient_temperature, double measured_temperature)
{
    gs_rig_input in = {0};
    if (!(isfinite(base_speed) && isfinite(base_torque) && isfinite(load) &&
          isfinite(ambient_temperature) && isfinite(measured_temperature)))
        return 1;
    in.base_speed_rad_s = base_speed;
    in.base_torque_Nm = base_torque;
    in.load = load;
    in.ambient_temperature_K = ambient_temperature;
    in.measured_temperature_K = measured_temperature;
    gs_rig_step(s->rig, &in, &s->out);
    return 0;
}
"""


def _path(path: Path, absolute: bool) -> str:
    # setuptools wants paths relative to setup.py (the repository root, which
    # is the working directory of a pip build); cffi's own compile() changes
    # directory and needs absolute ones.
    return path.as_posix() if absolute else path.relative_to(ROOT).as_posix()


def _compile_args() -> list[str]:
    if sys.platform == "win32":
        return ["/fp:precise"]
    # Determinism (docs/style.md 9): no FMA contraction, never -ffast-math.
    return ["-std=c99", "-ffp-contract=off", "-fno-fast-math"]


def make_builder(absolute: bool = False) -> FFI:
    """The FFI builder of gearsim._gearsim (src/*.c compiled in, double precision)."""
    sources = sorted(SRC_DIR.glob("*.c"))
    if not sources:
        raise RuntimeError(f"gearsim: no C sources found in {SRC_DIR}")
    builder = FFI()
    builder.cdef(CDEF)
    builder.set_source(
        "gearsim._gearsim",
        '#include "gearsim/gearsim.h"\n' + SHIM,
        sources=[_path(p, absolute) for p in sources],
        include_dirs=[_path(INCLUDE_DIR, absolute), _path(SRC_DIR, absolute)],
        libraries=[] if sys.platform == "win32" else ["m"],
        extra_compile_args=_compile_args(),
    )
    return builder


ffibuilder = make_builder()

if __name__ == "__main__":
    # In-place build for development: puts gearsim/_gearsim.*.so in the package.
    make_builder(absolute=True).compile(tmpdir=str(HERE), verbose=True)

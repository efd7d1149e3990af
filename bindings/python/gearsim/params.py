"""Parameter tables: program name, kind, SI unit and C field of every block and
rig parameter, declared once (docs/physics.md sections 9-11, docs/python-api.md).

This module converts user values (plain SI numbers, unit strings, lists) into
normalised Python values, writes them into the C ``*_params`` structs and reads
the C defaults back. It never re-implements a validity rule that the C core
checks; the only checks made here are those the C structs cannot express:
types, table capacity, and the lengths of tables that share one C count
(``efficiency_vector`` vs ``temperature_vector``, the shape of
``efficiency_matrix``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np

from ._lib import ffi, lib, status_message, status_name
from .errors import ModelFileError, ParameterError
from .units import UnitConversionError, to_si

__all__ = [
    "Param",
    "SIMPLE_GEAR_PARAMS",
    "RACK_PINION_PARAMS",
    "GEAR_RIG_PARAMS",
    "RACK_RIG_PARAMS",
    "BLOCKS",
    "param_units",
]

REAL = "real"  # float
VECTOR = "vector"  # list of floats (a table of up to GS_TABLE_MAX entries)
MATRIX = "matrix"  # list of rows (lists of floats)
PAIR = "pair"  # list of exactly 2 floats
OPTION = "option"  # one string of a fixed list
BOOL = "bool"
INT = "int"
OPTIONAL_REAL = "optional_real"  # float or None (absent)


@dataclass(frozen=True)
class Param:
    """One user parameter.

    name: program name (TOML key, Python keyword, error ``.parameter``).
    kind: REAL, VECTOR, MATRIX, PAIR, OPTION, BOOL, INT or OPTIONAL_REAL.
    unit: SI unit in pint syntax ("" = dimensionless); unit strings given by the
        user are converted to it.
    field: C field path in the params struct ("backlash.stiffness_N_m"), or ""
        for a parameter that lives only in Python.
    count: C field holding the length of a VECTOR ("temperature_count"), if any.
    options: (Python value, C enum constant) pairs of an OPTION.
    doc: one line for the documentation.
    """

    name: str
    kind: str
    unit: str = ""
    field: str = ""
    count: str = ""
    options: tuple[tuple[str, str], ...] = ()
    doc: str = ""

    def option_value(self, text: str) -> int:
        """C enum value of an option string (read from the compiled library)."""
        return int(getattr(lib, dict(self.options)[text]))

    def option_text(self, value: int) -> str:
        for text, const in self.options:
            if int(getattr(lib, const)) == int(value):
                return text
        raise ValueError(f"{self.name}: C value {value} has no option string")  # pragma: no cover


_FRICTION_SG = (
    ("none", "GS_FRICTION_NONE"),
    ("constant_efficiency", "GS_FRICTION_CONSTANT_EFFICIENCY"),
    ("load_dependent_efficiency", "GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY"),
    ("temperature_dependent_efficiency", "GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY"),
    ("temperature_load_dependent_efficiency", "GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY"),
)
_FRICTION_RP = (_FRICTION_SG[0], _FRICTION_SG[1], _FRICTION_SG[3])
_SMOOTHING = (("passive", "GS_SMOOTHING_PASSIVE"), ("simscape", "GS_SMOOTHING_SIMSCAPE"))
_HARD_STOP = (
    ("smooth", "GS_HARD_STOP_SMOOTH"),
    ("full_undamped", "GS_HARD_STOP_FULL_UNDAMPED"),
    ("full_damped", "GS_HARD_STOP_FULL_DAMPED"),
)


def _backlash(with_base_radius: bool) -> tuple[Param, ...]:
    params = [
        Param("backlash_enabled", BOOL, field="backlash.enabled", doc="enable backlash"),
        Param(
            "hard_stop_model",
            OPTION,
            field="backlash.hard_stop_model",
            options=_HARD_STOP,
            doc="hard-stop contact law",
        ),
        Param(
            "linear_backlash",
            REAL,
            "m",
            "backlash.linear_backlash_m",
            doc="total free travel b at the pitch line",
        ),
    ]
    if with_base_radius:
        params.append(
            Param(
                "base_radius", REAL, "m", "backlash.base_radius_m", doc="base gear pitch radius r_B"
            )
        )
    params += [
        Param(
            "transition_region",
            REAL,
            "m",
            "backlash.transition_region_m",
            doc="transition region d of the smooth model",
        ),
        Param("stiffness", REAL, "N/m", "backlash.stiffness_N_m", doc="contact stiffness K"),
        Param("damping", REAL, "N*s/m", "backlash.damping_N_s_m", doc="contact damping D"),
        Param(
            "initial_backlash_position",
            REAL,
            "m",
            "backlash.initial_position_m",
            doc="initial position x0 in [-b/2, b/2]",
        ),
        Param(
            "contact_speed_threshold",
            REAL,
            "m/s",
            "backlash.contact_speed_threshold_m_s",
            doc="static contact speed threshold (lock mode)",
        ),
        Param(
            "contact_release_force",
            REAL,
            "N",
            "backlash.contact_release_force_N",
            doc="static contact release force threshold (lock mode)",
        ),
        Param(
            "contact_no_pull",
            BOOL,
            field="backlash.no_pull",
            doc="the contact force never pulls the teeth together",
        ),
        Param(
            "contact_lock_enabled", BOOL, field="backlash.lock_enabled", doc="static contact lock"
        ),
    ]
    return tuple(params)


# The groups below mean the same in both blocks (same name, unit and C field in
# gs_simple_gear_params and gs_rack_pinion_params), so each is declared once.


def _mesh_loss(friction_options: tuple[tuple[str, str], ...]) -> tuple[Param, ...]:
    """friction_model (the block's own list of models), loss_smoothing, efficiency_const."""
    return (
        Param(
            "friction_model",
            OPTION,
            field="friction_model",
            options=friction_options,
            doc="meshing-loss model",
        ),
        Param(
            "loss_smoothing",
            OPTION,
            field="loss_smoothing",
            options=_SMOOTHING,
            doc="power-threshold smoothing law",
        ),
        Param("efficiency_const", REAL, "", "efficiency_const", doc="constant efficiency"),
    )


# The temperature-dependent efficiency table: efficiency_vector has no C count of
# its own, it shares temperature_count.
_TEMPERATURE_TABLE = (
    Param(
        "temperature_vector",
        VECTOR,
        "K",
        "temperature_vector_K",
        "temperature_count",
        doc="temperature breakpoints",
    ),
    Param(
        "efficiency_vector", VECTOR, "", "efficiency_vector", doc="efficiency at each temperature"
    ),
)

# The thermal port.
_THERMAL = (
    Param("thermal_mass", REAL, "J/K", "thermal_mass_J_K", doc="thermal mass"),
    Param("initial_temperature", REAL, "K", "initial_temperature_K", doc="initial temperature"),
)


SIMPLE_GEAR_PARAMS: tuple[Param, ...] = (
    Param("teeth_ratio", REAL, "", "teeth_ratio", doc="follower-to-base teeth ratio N_F/N_B"),
    Param(
        "output_shaft_rotates",
        OPTION,
        field="output_shaft_rotates",
        options=(("same", "GS_ROTATES_SAME"), ("opposite", "GS_ROTATES_OPPOSITE")),
        doc="follower rotation relative to the base",
    ),
    *_mesh_loss(_FRICTION_SG),
    Param("power_threshold", REAL, "W", "power_threshold_W", doc="follower power threshold"),
    Param("idle_torque", REAL, "N*m", "idle_torque_Nm", doc="input shaft torque at no load"),
    Param(
        "nominal_output_torque",
        REAL,
        "N*m",
        "nominal_output_torque_Nm",
        doc="nominal output torque",
    ),
    Param(
        "efficiency_nominal",
        REAL,
        "",
        "efficiency_nominal",
        doc="efficiency at nominal output torque",
    ),
    Param(
        "speed_threshold",
        REAL,
        "rad/s",
        "speed_threshold_rad_s",
        doc="follower angular velocity threshold",
    ),
    *_TEMPERATURE_TABLE,
    Param(
        "load_vector",
        VECTOR,
        "N*m",
        "load_vector_Nm",
        "load_count",
        doc="base-gear load breakpoints",
    ),
    Param(
        "efficiency_matrix",
        MATRIX,
        "",
        "efficiency_matrix",
        doc="efficiency, one row per temperature, one column per load",
    ),
    *_backlash(with_base_radius=True),
    Param(
        "viscous_coefficients",
        PAIR,
        "N*m*s/rad",
        "viscous_coefficients",
        doc="viscous coefficients [mu_B, mu_F]",
    ),
    *_THERMAL,
)

RACK_PINION_PARAMS: tuple[Param, ...] = (
    Param(
        "parameterization",
        OPTION,
        field="parameterization",
        options=(
            ("pinion_radius", "GS_PARAMETERIZE_PINION_RADIUS"),
            ("tooth_parameters", "GS_PARAMETERIZE_TOOTH_PARAMETERS"),
        ),
        doc="pinion radius or tooth parameters",
    ),
    Param("pinion_radius", REAL, "m", "pinion_radius_m", doc="pinion radius r_P"),
    Param("teeth_count", REAL, "", "teeth_count", doc="number of pinion teeth N_P"),
    Param("spacing", REAL, "m", "spacing_m", doc="rack tooth spacing x_R"),
    Param(
        "rack_directionality",
        OPTION,
        field="rack_directionality",
        options=(("positive", "GS_RACK_POSITIVE"), ("negative", "GS_RACK_NEGATIVE")),
        doc="rack direction for positive pinion rotation",
    ),
    *_mesh_loss(_FRICTION_RP),
    *_TEMPERATURE_TABLE,
    Param("power_threshold", REAL, "W", "power_threshold_W", doc="rack power threshold"),
    Param(
        "pinion_viscous_coefficient",
        REAL,
        "N*m*s/rad",
        "pinion_viscous_coefficient",
        doc="pinion viscous coefficient",
    ),
    Param(
        "rack_viscous_coefficient",
        REAL,
        "N*s/m",
        "rack_viscous_coefficient",
        doc="rack viscous coefficient",
    ),
    *_THERMAL,
    *_backlash(with_base_radius=False),
)


def _rig_params(
    driven: str, driven_unit: str, load_unit: str, speed_unit: str
) -> tuple[Param, ...]:
    return (
        Param(
            driven,
            REAL,
            driven_unit,
            "driven_inertia",
            doc="inertia of the follower shaft"
            if driven == "follower_inertia"
            else "mass of the rack",
        ),
        Param(
            "load_coulomb_friction",
            REAL,
            load_unit,
            "load_coulomb_friction",
            doc="constant Coulomb friction on the driven side",
        ),
        Param(
            "load_coulomb_speed_threshold",
            REAL,
            speed_unit,
            "load_coulomb_speed_threshold",
            doc="tanh smoothing speed of the driven-side Coulomb friction",
        ),
        Param(
            "load_offset",
            REAL,
            load_unit,
            "load_offset",
            doc="constant bias on the driven side (gravity, cable drag)",
        ),
        Param(
            "thermal_resistance",
            OPTIONAL_REAL,
            "K/W",
            "thermal_resistance_K_W",
            doc="housing-to-ambient thermal resistance; absent = adiabatic",
        ),
        Param(
            "ambient_temperature", REAL, "K", doc="ambient temperature used when run/step get none"
        ),
        Param(
            "base_inertia",
            REAL,
            "kg*m**2",
            "base_inertia_kg_m2",
            doc="base (pinion) shaft inertia; > 0 when torque-driven",
        ),
        Param(
            "initial_base_speed",
            REAL,
            "rad/s",
            "initial_base_speed_rad_s",
            doc="torque-driven start speed",
        ),
        Param(
            "accel_filter_time_constant",
            REAL,
            "s",
            "accel_filter_time_constant_s",
            doc="speed-driven: low-pass time constant of the base acceleration",
        ),
        Param(
            "contact_substeps",
            INT,
            field="contact_substeps",
            doc="backlash contact sub-steps per step, 0 = automatic",
        ),
        Param(
            "base_drive",
            OPTION,
            field="base_drive",
            options=(("speed", "GS_BASE_SPEED_DRIVEN"), ("torque", "GS_BASE_TORQUE_DRIVEN")),
            doc="speed-driven or torque-driven base shaft",
        ),
        *_stribeck(load_unit, speed_unit),
        *_COMPLIANCE,
        *_RIPPLE,
        *_SWITCHES,
    )


def _stribeck(load_unit: str, speed_unit: str) -> tuple[Param, ...]:
    """The Stribeck hump of the driven side's friction (driven-side units)."""
    return (
        Param(
            "load_breakaway_friction",
            REAL,
            load_unit,
            "load_breakaway_friction",
            doc="driven-side friction at rest (Stribeck); 0 = none, else >= load_coulomb_friction",
        ),
        Param(
            "load_stribeck_speed",
            REAL,
            speed_unit,
            "load_stribeck_speed",
            doc="speed over which the friction falls from breakaway to Coulomb",
        ),
    )


# The compliant base shaft and the ripple act on the base side: the same units
# in both rigs (the pinion is the base of the rack rig).
_COMPLIANCE = (
    Param(
        "compliance_stiffness",
        REAL,
        "N*m/rad",
        "compliance_stiffness_Nm_rad",
        doc="torsional stiffness of the base shaft, drive to base gear (with base_inertia 0: "
        "at the mesh); 0 = rigid",
    ),
    Param(
        "compliance_damping",
        REAL,
        "N*m*s/rad",
        "compliance_damping_Nm_s_rad",
        doc="torsional damping of the base shaft",
    ),
)

_RIPPLE = (
    Param(
        "ripple_revolution_amplitude",
        PAIR,
        "N*m",
        "ripple_revolution_amplitude_Nm",
        doc="base-side ripple amplitudes of the 1st and 2nd harmonic per revolution",
    ),
    Param(
        "ripple_revolution_phase",
        PAIR,
        "rad",
        "ripple_revolution_phase_rad",
        doc="phases of the per-revolution ripple harmonics",
    ),
    Param(
        "ripple_mesh_amplitude",
        PAIR,
        "N*m",
        "ripple_mesh_amplitude_Nm",
        doc="base-side ripple amplitudes of the 1st and 2nd harmonic per tooth mesh",
    ),
    Param(
        "ripple_mesh_phase",
        PAIR,
        "rad",
        "ripple_mesh_phase_rad",
        doc="phases of the per-tooth ripple harmonics",
    ),
    Param(
        "ripple_mesh_teeth",
        INT,
        field="ripple_mesh_teeth",
        doc="teeth of the base gear (pinion) per revolution; >= 1 with a mesh ripple",
    ),
)


# Two switches of the rig's numerics (physics.md 11), both off by default.
_SWITCHES = (
    Param(
        "load_friction_regularised",
        BOOL,
        field="load_friction_regularised",
        doc="a freely moving driven side's friction is F*tanh(4 v/load_coulomb_speed_threshold) "
        "(creeps, no stiction) instead of the set-valued Coulomb law",
    ),
    Param(
        "base_speed_ramp",
        BOOL,
        field="base_speed_ramp",
        doc="speed-driven rigid mesh: speed terms at the step's mean speed (the samples' linear "
        "ramp), so every torque is a step mean",
    ),
)


GEAR_RIG_PARAMS = _rig_params("follower_inertia", "kg*m**2", "N*m", "rad/s")
RACK_RIG_PARAMS = _rig_params("rack_mass", "kg", "N", "m/s")

#: Python-side default of the rig parameters the C rig does not hold.
PYTHON_RIG_DEFAULTS: dict[str, Any] = {"thermal_resistance": None, "ambient_temperature": 293.15}

#: Block name -> (block parameters, rig parameters, C params type, default function).
BLOCKS: dict[str, tuple[tuple[Param, ...], tuple[Param, ...], str, str]] = {
    "simple_gear": (
        SIMPLE_GEAR_PARAMS,
        GEAR_RIG_PARAMS,
        "gs_simple_gear_params",
        "gs_simple_gear_params_default",
    ),
    "rack_pinion": (
        RACK_PINION_PARAMS,
        RACK_RIG_PARAMS,
        "gs_rack_pinion_params",
        "gs_rack_pinion_params_default",
    ),
}


def units_of(specs: Iterable[Param]) -> dict[str, str]:
    """Parameter name -> SI unit (pint syntax) of the numeric parameters of specs."""
    return {p.name: p.unit for p in specs if p.kind not in (OPTION, BOOL, INT)}


def param_units(block: str) -> dict[str, str]:
    """Parameter name -> SI unit (pint syntax) of a block's block and rig parameters."""
    block_specs, rig_specs, _, _ = BLOCKS[block]
    return units_of((*block_specs, *rig_specs))


# ---------------------------------------------------------------- conversion


def _type_error(p: Param, expected: str, value: Any) -> ModelFileError:
    return ModelFileError(
        f"expected {expected}, got {type(value).__name__} {value!r}", parameter=p.name
    )


def _is_number(value: Any) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def _scalar(p: Param, value: Any) -> float:
    if _is_number(value):
        return float(value)
    if isinstance(value, str):
        try:
            result = to_si(value, p.unit)
        except UnitConversionError as exc:
            raise ParameterError(str(exc), parameter=p.name) from None
        if isinstance(result, list):
            raise _type_error(p, "a number", value)
        return result
    unit = f" (SI: {p.unit})" if p.unit else ""
    raise _type_error(p, f"a number or a unit string{unit}", value)


def _vector(p: Param, value: Any) -> list[float]:
    if isinstance(value, str):
        try:
            result = to_si(value, p.unit)
        except UnitConversionError as exc:
            raise ParameterError(str(exc), parameter=p.name) from None
        values = result if isinstance(result, list) else [result]
    elif _is_sequence(value):
        values = [_scalar(p, item) for item in _items(p, value)]
    else:
        raise _type_error(p, "a list of numbers", value)
    return values


def _is_sequence(value: Any) -> bool:
    if isinstance(value, (str, bytes, Mapping)):
        return False
    return isinstance(value, Sequence) or hasattr(value, "__array__")


def _items(p: Param, value: Any) -> list[Any]:
    if hasattr(value, "__array__") and not isinstance(value, Sequence):
        arr = np.asarray(value)
        if arr.ndim != 1:
            raise _type_error(p, "a one-dimensional list of numbers", value)
        return arr.tolist()
    return list(value)


def normalize(p: Param, value: Any) -> Any:
    """User value -> normalised Python value (SI floats, lists, str, bool, int).

    Raises ModelFileError for a wrong type, ParameterError for a value that
    cannot be stored (bad unit, unknown option, table longer than GS_TABLE_MAX).
    """
    kind = p.kind
    if kind == REAL:
        return _scalar(p, value)
    if kind == OPTIONAL_REAL:
        return None if value is None else _scalar(p, value)
    if kind == BOOL:
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        raise _type_error(p, "true or false", value)
    if kind == INT:
        if isinstance(value, Integral) and not isinstance(value, bool):
            return int(value)
        raise _type_error(p, "an integer", value)
    if kind == OPTION:
        if not isinstance(value, str):
            raise _type_error(p, "a string", value)
        allowed = [text for text, _ in p.options]
        if value not in allowed:
            raise ParameterError(
                f"{value!r} is not one of {', '.join(repr(a) for a in allowed)}",
                parameter=p.name,
                status=status_name(lib.GS_E_OPTION),
            )
        return value
    if kind in (VECTOR, PAIR):
        values = _vector(p, value)
        if kind == PAIR and len(values) != 2:
            raise ParameterError(
                f"needs exactly 2 values, got {len(values)}",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_SIZE_MISMATCH),
            )
        if len(values) > lib.GS_TABLE_MAX:
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_LENGTH)} (GS_TABLE_MAX = {lib.GS_TABLE_MAX}, "
                f"got {len(values)})",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_LENGTH),
            )
        return values
    if kind == MATRIX:
        if not _is_sequence(value):
            raise _type_error(p, "a list of rows (lists of numbers)", value)
        rows = _items_2d(p, value)
        width = {len(r) for r in rows}
        if len(width) > 1:
            raise ParameterError(
                "rows have different lengths",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_SIZE_MISMATCH),
            )
        if len(rows) > lib.GS_TABLE_MAX or (rows and len(rows[0]) > lib.GS_TABLE_MAX):
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_LENGTH)} (GS_TABLE_MAX = {lib.GS_TABLE_MAX})",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_LENGTH),
            )
        return rows
    raise AssertionError(kind)  # pragma: no cover


def _items_2d(p: Param, value: Any) -> list[list[float]]:
    if hasattr(value, "__array__") and not isinstance(value, Sequence):
        arr = np.asarray(value)
        if arr.ndim != 2:
            raise _type_error(p, "a two-dimensional list of numbers", value)
        value = arr.tolist()
    rows = []
    for row in value:
        if not _is_sequence(row):
            raise _type_error(p, "a list of rows (lists of numbers)", value)
        rows.append([_scalar(p, item) for item in _items(p, row)])
    return rows


def normalize_all(
    specs: Mapping[str, Param], values: Mapping[str, Any], what: str
) -> dict[str, Any]:
    """Normalise a mapping of user values; unknown keys raise ModelFileError."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        p = specs.get(key)
        if p is None:
            known = ", ".join(sorted(specs))
            raise ModelFileError(
                f"unknown {what} parameter {key!r} (known: {known})", parameter=str(key)
            )
        out[key] = normalize(p, value)
    return out


# ---------------------------------------------------------------- C structs


def _get_field(struct: Any, path: str) -> Any:
    obj = struct
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def _set_field(struct: Any, path: str, value: Any) -> None:
    *head, last = path.split(".")
    obj = struct
    for part in head:
        obj = getattr(obj, part)
    setattr(obj, last, value)


def read_struct(specs: Sequence[Param], struct: Any) -> dict[str, Any]:
    """C params struct -> normalised values (used for the C defaults).

    Vectors without a count of their own (efficiency_vector) take the count of
    temperature_vector; efficiency_matrix is temperature_count x load_count.
    """
    out: dict[str, Any] = {}
    counts = {p.name: int(_get_field(struct, p.count)) for p in specs if p.count}
    for p in specs:
        if not p.field:
            continue
        raw = _get_field(struct, p.field)
        if p.kind in (REAL, OPTIONAL_REAL):
            out[p.name] = float(raw)
        elif p.kind == BOOL:
            out[p.name] = bool(raw)
        elif p.kind == INT:
            out[p.name] = int(raw)
        elif p.kind == OPTION:
            out[p.name] = p.option_text(int(raw))
        elif p.kind == PAIR:
            out[p.name] = [float(raw[0]), float(raw[1])]
        elif p.kind == VECTOR:
            n = counts.get(p.name, counts.get("temperature_vector", 0))
            out[p.name] = [float(raw[i]) for i in range(n)]
        elif p.kind == MATRIX:
            rows = counts.get("temperature_vector", 0)
            cols = counts.get("load_vector", 0)
            out[p.name] = [[float(raw[i][j]) for j in range(cols)] for i in range(rows)]
    return out


def write_struct(specs: Sequence[Param], values: Mapping[str, Any], struct: Any) -> None:
    """Write normalised values into a C params struct (fields not in values keep
    their current content)."""
    for p in specs:
        if not p.field or p.name not in values:
            continue
        value = values[p.name]
        if p.kind in (REAL, OPTIONAL_REAL):
            if value is not None:
                _set_field(struct, p.field, value)
        elif p.kind in (BOOL, INT):
            _set_field(struct, p.field, int(value))
        elif p.kind == OPTION:
            _set_field(struct, p.field, p.option_value(value))
        elif p.kind in (VECTOR, PAIR):
            arr = _get_field(struct, p.field)
            for i, v in enumerate(value):
                arr[i] = v
            if p.count:
                _set_field(struct, p.count, len(value))
        elif p.kind == MATRIX:
            arr = _get_field(struct, p.field)
            for i, row in enumerate(value):
                for j, v in enumerate(row):
                    arr[i][j] = v


def block_defaults(block: str) -> dict[str, Any]:
    """Defaults of a block's parameters, read from the C core."""
    specs, _, _, default_fn = BLOCKS[block]
    return read_struct(specs, getattr(lib, default_fn)())


def rig_defaults(block: str) -> dict[str, Any]:
    """Defaults of a rig's parameters: the C core's, plus the Python-side ones."""
    _, specs, _, _ = BLOCKS[block]
    values = read_struct(specs, lib.gs_rig_params_default())
    values.update(PYTHON_RIG_DEFAULTS)
    return values


def check_table_shapes(block: str, values: Mapping[str, Any]) -> None:
    """Lengths of tables that share one C count (the C struct cannot tell).

    Checked only where the friction model uses the tables (the C core does not
    validate inactive parameters either), and only once temperature_vector and
    load_vector have a length the C core accepts, so that the C core reports
    problems of the breakpoints themselves.
    """
    model = values["friction_model"]
    n_t = len(values["temperature_vector"])
    ok_t = 2 <= n_t <= lib.GS_TABLE_MAX
    mismatch = status_name(lib.GS_E_TABLE_SIZE_MISMATCH)
    if model == "temperature_dependent_efficiency" and ok_t:
        n_e = len(values["efficiency_vector"])
        if n_e != n_t:
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_SIZE_MISMATCH)}: {n_e} efficiencies for "
                f"{n_t} temperatures",
                parameter="efficiency_vector",
                status=mismatch,
            )
    if block == "simple_gear" and model == "temperature_load_dependent_efficiency":
        n_l = len(values["load_vector"])
        matrix = values["efficiency_matrix"]
        if ok_t and 2 <= n_l <= lib.GS_TABLE_MAX:
            shape = (len(matrix), len(matrix[0]) if matrix else 0)
            if shape != (n_t, n_l):
                raise ParameterError(
                    f"{status_message(lib.GS_E_TABLE_SIZE_MISMATCH)}: {shape[0]} x {shape[1]} "
                    f"matrix for {n_t} temperatures x {n_l} loads",
                    parameter="efficiency_matrix",
                    status=mismatch,
                )


def canonical(value: Any) -> Any:
    """Hashable, exactly comparable form of a normalised value (floats by bit
    pattern, so NaN equals NaN and -0.0 differs from 0.0)."""
    if isinstance(value, float):
        return ("f", value.hex() if math.isfinite(value) else repr(value))
    if isinstance(value, (list, tuple)):
        return tuple(canonical(v) for v in value)
    if isinstance(value, Mapping):
        return tuple(sorted((k, canonical(v)) for k, v in value.items()))
    return value


def new_struct(ctype: str) -> Any:
    return ffi.new(ctype + " *")

"""Direct runs of the C rig for the FMU tests.

cffi in ABI mode over a plain shared build of the core (build/fmu/reference/
libgearsim.so, or GEARSIM_LIB), declarations taken from the public headers run
through the C preprocessor. The FMI-name to C-field mapping below is written
here independently of fmu/src/gs_fmu_model.c, so the tests cross-check it.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import cffi
import numpy as np

# ---- FMI name -> C field path ("block." = the rig's block params, "rig." = gs_rig_params)

_BACKLASH = {
    "backlash_enabled": "block.backlash.enabled",
    "hard_stop_model": "block.backlash.hard_stop_model",
    "linear_backlash": "block.backlash.linear_backlash_m",
    "transition_region": "block.backlash.transition_region_m",
    "stiffness": "block.backlash.stiffness_N_m",
    "damping": "block.backlash.damping_N_s_m",
    "initial_backlash_position": "block.backlash.initial_position_m",
    "contact_no_pull": "block.backlash.no_pull",
    "contact_lock_enabled": "block.backlash.lock_enabled",
    "contact_speed_threshold": "block.backlash.contact_speed_threshold_m_s",
    "contact_release_force": "block.backlash.contact_release_force_N",
}

_RIG = {
    "dt": "rig.dt_s",
    "base_drive": "rig.base_drive",
    "base_inertia": "rig.base_inertia_kg_m2",
    "initial_base_speed": "rig.initial_base_speed_rad_s",
    "load_coulomb_friction": "rig.load_coulomb_friction",
    "load_coulomb_speed_threshold": "rig.load_coulomb_speed_threshold",
    "load_offset": "rig.load_offset",
    "heat_path": "rig.heat_path",
    "thermal_resistance": "rig.thermal_resistance_K_W",
    "temperature_input": "rig.temperature_source",
    "accel_filter_time_constant": "rig.accel_filter_time_constant_s",
    "contact_substeps": "rig.contact_substeps",
    "load_breakaway_friction": "rig.load_breakaway_friction",
    "load_stribeck_speed": "rig.load_stribeck_speed",
    "compliance_stiffness": "rig.compliance_stiffness_Nm_rad",
    "compliance_damping": "rig.compliance_damping_Nm_s_rad",
    "ripple_revolution_amplitude": "rig.ripple_revolution_amplitude_Nm",
    "ripple_revolution_phase": "rig.ripple_revolution_phase_rad",
    "ripple_mesh_amplitude": "rig.ripple_mesh_amplitude_Nm",
    "ripple_mesh_phase": "rig.ripple_mesh_phase_rad",
    "ripple_mesh_teeth": "rig.ripple_mesh_teeth",
    "load_friction_regularised": "rig.load_friction_regularised",
    "base_speed_ramp": "rig.base_speed_ramp",
}

GEAR_FIELDS: dict[str, str] = {
    "teeth_ratio": "block.teeth_ratio",
    "output_shaft_rotates": "block.output_shaft_rotates",
    "friction_model": "block.friction_model",
    "loss_smoothing": "block.loss_smoothing",
    "efficiency_const": "block.efficiency_const",
    "power_threshold": "block.power_threshold_W",
    "idle_torque": "block.idle_torque_Nm",
    "nominal_output_torque": "block.nominal_output_torque_Nm",
    "efficiency_nominal": "block.efficiency_nominal",
    "speed_threshold": "block.speed_threshold_rad_s",
    "temperature_count": "block.temperature_count",
    "temperature_vector": "block.temperature_vector_K",
    "efficiency_vector": "block.efficiency_vector",
    "load_count": "block.load_count",
    "load_vector": "block.load_vector_Nm",
    "efficiency_matrix": "block.efficiency_matrix",
    "viscous_coefficients": "block.viscous_coefficients",
    "thermal_mass": "block.thermal_mass_J_K",
    "initial_temperature": "block.initial_temperature_K",
    "base_radius": "block.backlash.base_radius_m",
    "follower_inertia": "rig.driven_inertia",
    **_BACKLASH,
    **_RIG,
}

RACK_FIELDS: dict[str, str] = {
    "parameterization": "block.parameterization",
    "pinion_radius": "block.pinion_radius_m",
    "teeth_count": "block.teeth_count",
    "spacing": "block.spacing_m",
    "rack_directionality": "block.rack_directionality",
    "friction_model": "block.friction_model",
    "loss_smoothing": "block.loss_smoothing",
    "efficiency_const": "block.efficiency_const",
    "temperature_count": "block.temperature_count",
    "temperature_vector": "block.temperature_vector_K",
    "efficiency_vector": "block.efficiency_vector",
    "power_threshold": "block.power_threshold_W",
    "pinion_viscous_coefficient": "block.pinion_viscous_coefficient",
    "rack_viscous_coefficient": "block.rack_viscous_coefficient",
    "thermal_mass": "block.thermal_mass_J_K",
    "initial_temperature": "block.initial_temperature_K",
    "rack_mass": "rig.driven_inertia",
    **_BACKLASH,
    **_RIG,
}

FIELDS = {"gear": GEAR_FIELDS, "rack": RACK_FIELDS}

# The rig's inputs and outputs carry the names of gearsim/fields.h in every
# layer. The FMU's inputs sit under the structured prefix "inputs." (an input
# and an output are both called base_speed, and base_torque: FMI names are
# unique); its outputs carry the names as they are. INPUTS and OUTPUTS are
# read from the public header below (the members of gs_rig_input and
# gs_rig_output, in order).
INPUT_PREFIX = "inputs."

# gearsim/fields.h writes units as pint parses them; FMI spells these otherwise.
FMI_UNIT = {"N*m": "N.m", "rad/s^2": "rad/s2", "m/s^2": "m/s2"}


def fmi_unit(table_unit: str) -> str | None:
    """The FMI unit of a unit of gearsim/fields.h (None: dimensionless)."""
    if table_unit in ("", "1"):
        return None
    return FMI_UNIT.get(table_unit, table_unit)


_INDEXED = re.compile(r"^([a-z_]+)\[(\d+)(?:,(\d+))?\]$")


def split_name(name: str) -> tuple[str, tuple[int, ...]]:
    """'efficiency_matrix[2,3]' -> ('efficiency_matrix', (1, 2)) (0-based)."""
    m = _INDEXED.match(name)
    if not m:
        return name, ()
    idx = tuple(int(g) - 1 for g in m.groups()[1:] if g is not None)
    return m.group(1), idx


@functools.cache
def _preprocessed_header(repo: Path) -> str:
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise RuntimeError("a C compiler (cc) is needed to preprocess the gearsim headers")
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "stddef.h").write_text("")  # cffi knows size_t; keep the system header out
        out = subprocess.run(
            [
                cc,
                "-E",
                "-P",
                "-nostdinc",
                "-I",
                tmp,
                "-I",
                str(repo / "include"),
                "-DGS_API=",  # no visibility attribute for cffi's parser
                str(repo / "include" / "gearsim" / "gearsim.h"),
            ],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    return out


def _members(ffi: cffi.FFI, ctype: str) -> list[str]:
    """The members of a struct of the public header, in order."""
    return [name for name, _ in ffi.typeof(ctype).fields]


_HEADER = cffi.FFI()  # the declarations alone, no library needed
_HEADER.cdef(_preprocessed_header(Path(__file__).resolve().parents[2]))
# FMI input -> gs_rig_input member
INPUTS: dict[str, str] = {
    f"{INPUT_PREFIX}{field}": field for field in _members(_HEADER, "gs_rig_input")
}
# FMI outputs (= Python RigResult names = gs_rig_output members)
OUTPUTS: tuple[str, ...] = tuple(_members(_HEADER, "gs_rig_output"))


class Reference:
    """The C rig of libgearsim.so, stepped directly."""

    def __init__(self, lib_path: Path, repo: Path):
        self.ffi = cffi.FFI()
        self.ffi.cdef(_preprocessed_header(repo))
        self.lib = self.ffi.dlopen(str(lib_path))

    # -- parameters
    def default_params(self, rig: str) -> dict[str, Any]:
        lib, ffi = self.lib, self.ffi
        if rig == "gear":
            block = ffi.new("gs_simple_gear_params *", lib.gs_simple_gear_params_default())
        else:
            block = ffi.new("gs_rack_pinion_params *", lib.gs_rack_pinion_params_default())
        return {"block": block, "rig": ffi.new("gs_rig_params *", lib.gs_rig_params_default())}

    @staticmethod
    def _locate(structs: Mapping[str, Any], path: str):
        head, *rest = path.split(".")
        obj = structs[head]
        for part in rest[:-1]:
            obj = getattr(obj, part)
        return obj, rest[-1]

    def get(self, rig: str, structs: Mapping[str, Any], fmi_name: str) -> float:
        base, idx = split_name(fmi_name)
        obj, field = self._locate(structs, FIELDS[rig][base])
        value = getattr(obj, field)
        for i in idx:
            value = value[i]
        return value

    def set(self, rig: str, structs: Mapping[str, Any], fmi_name: str, value: Any) -> None:
        base, idx = split_name(fmi_name)
        obj, field = self._locate(structs, FIELDS[rig][base])
        if not idx:
            setattr(obj, field, int(value) if isinstance(value, (bool, np.bool_)) else value)
            return
        arr = getattr(obj, field)
        for i in idx[:-1]:
            arr = arr[i]
        arr[idx[-1]] = value

    def init(self, rig: str, start_values: Mapping[str, Any]):
        """Returns ((gs_rig_consts *, gs_rig_state *), gs_error *, status)."""
        structs = self.default_params(rig)
        for name, value in start_values.items():
            self.set(rig, structs, name, value)
        consts = self.ffi.new("gs_rig_consts *")
        state = self.ffi.new("gs_rig_state *")
        err = self.ffi.new("gs_error *")
        init = self.lib.gs_rig_init_gear if rig == "gear" else self.lib.gs_rig_init_rack
        status = init(consts, state, structs["block"], structs["rig"], err)
        return (consts, state), err, status

    def field_table(self, which: str) -> list[dict[str, Any]]:
        """gs_rig_input_info / gs_rig_output_info of the library: name, units, doc."""
        table = getattr(self.lib, f"gs_rig_{which}_info")
        count = getattr(self.lib, f"GS_RIG_{which.upper()}_FIELDS")
        string = self.ffi.string
        return [
            {
                "name": string(table[i].name).decode(),
                "gear_unit": string(table[i].gear_unit).decode(),
                "rack_unit": string(table[i].rack_unit).decode(),
                "doc": string(table[i].doc).decode(),
            }
            for i in range(count)
        ]

    # -- runs
    def run(
        self,
        rig: str,
        start_values: Mapping[str, Any],
        inputs: Mapping[str, np.ndarray],
        substeps: int,
    ) -> dict[str, np.ndarray]:
        """Holds inputs[k] for `substeps` steps of dt; returns the outputs after
        each group (one row per communication step)."""
        (consts, state), err, status = self.init(rig, start_values)
        if status != 0:
            raise ValueError(f"C init refused {self.ffi.string(err.parameter).decode()}")
        n = len(next(iter(inputs.values())))
        total = n * substeps
        in_arr = self.ffi.new("gs_rig_input[]", total)
        out_arr = self.ffi.new("gs_rig_output[]", total)
        fields_in = _members(self.ffi, "gs_rig_input")
        fields_out = _members(self.ffi, "gs_rig_output")
        u = np.frombuffer(self.ffi.buffer(in_arr), dtype=np.float64).reshape(total, len(fields_in))
        for name, field in INPUTS.items():
            if name in inputs:
                u[:, fields_in.index(field)] = np.repeat(
                    np.asarray(inputs[name], dtype=np.float64), substeps
                )
        self.lib.gs_rig_run(consts, state, total, in_arr, out_arr)
        y = np.frombuffer(self.ffi.buffer(out_arr), dtype=np.float64).reshape(
            total, len(fields_out)
        )
        y = y[substeps - 1 :: substeps]
        return {name: y[:, fields_out.index(name)].copy() for name in OUTPUTS}

    def leaf_fields(self, ctype: str, prefix: str = "") -> list[str]:
        """Every scalar or array leaf of a params struct, as dotted paths."""
        out = []
        for name, field in self.ffi.typeof(ctype).fields:
            t = field.type
            if t.kind == "struct":
                out += self.leaf_fields(t.cname, f"{prefix}{name}.")
            else:
                out.append(f"{prefix}{name}")
        return out

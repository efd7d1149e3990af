"""Direct runs of the C rig for the FMU tests.

cffi in ABI mode over a plain shared build of the core (build/fmu/reference/
libgearsim.so, or GEARSIM_LIB), declarations taken from the public headers run
through the C preprocessor. The FMI-name to C-field mapping is read from the
library's parameter tables (Reference.fields).
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

# ---- FMI name -> C field path ("block." = the rig's block params, "rig." = gs_rig_params):
# Reference.fields(rig), read from the library's parameter tables
# (gs_*_param_info of include/gearsim/parameters.h), which the FMU is generated
# from too. What the tests check independently of those tables: every leaf of
# the C structs (walked through cffi) is an FMI parameter, start values are
# the C defaults, and the units and variabilities named in test_fmu_rigs.py.

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

    def fields(self, rig: str) -> dict[str, str]:
        """FMI parameter name -> C field path ("block.backlash.stiffness_N_m",
        "rig.driven_inertia"), from the library's parameter tables."""
        rack = rig == "rack"
        string = self.ffi.string
        lib = self.lib
        out: dict[str, str] = {}

        def walk(table: Any, count: int, path: str) -> None:
            for i in range(count):
                e = table[i]
                member = f"{path}{string(e.member).decode()}"
                if e.kind == lib.GS_PARAM_GROUP:
                    walk(e.members, e.member_count, f"{member}.")
                elif not (rack and e.flags == lib.GS_PARAM_GEAR_ONLY):
                    out[string(e.rack_key if rack else e.key).decode()] = member

        walk(lib.gs_rig_param_info, len(lib.gs_rig_param_info), "rig.")
        if rack:
            walk(lib.gs_rack_pinion_param_info, len(lib.gs_rack_pinion_param_info), "block.")
        else:
            walk(lib.gs_simple_gear_param_info, len(lib.gs_simple_gear_param_info), "block.")
        return out

    def get(self, rig: str, structs: Mapping[str, Any], fmi_name: str) -> float:
        base, idx = split_name(fmi_name)
        obj, field = self._locate(structs, self.fields(rig)[base])
        value = getattr(obj, field)
        for i in idx:
            value = value[i]
        return value

    def set(self, rig: str, structs: Mapping[str, Any], fmi_name: str, value: Any) -> None:
        base, idx = split_name(fmi_name)
        obj, field = self._locate(structs, self.fields(rig)[base])
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

"""Rigs: a block between a driven base shaft and the driven side (follower
inertia or rack mass), the C rig of include/gearsim/rig.h (docs/physics.md
section 11): constants (gs_rig_consts, filled once by init) and a state
(gs_rig_state, all a step changes).

``Rig.step`` is the per-step call (HIL); ``Rig.run`` loops in C over numpy
arrays (gs_rig_run) and is bit-identical to the same number of steps.

The names, units and docs of the inputs, outputs and state come from the C
field tables (include/gearsim/fields.h, read by gearsim._lib at import).
"""

from __future__ import annotations

import math
import os
import struct
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from . import params as P
from ._extras import require
from ._lib import INPUT_INFO, OUTPUT_INFO, REAL_SIZE, STATE_INFO, FieldInfo, check, ffi, lib
from ._outputs import atomic_writer
from .blocks import Block, RackPinion, SimpleGear
from .errors import GearsimError, InputError, ParameterError, SubstepWarning, caller_stacklevel

__all__ = [
    "Rig",
    "GearRig",
    "RackRig",
    "RigResult",
    "RigSnapshot",
    "INPUT_NAMES",
    "OUTPUT_NAMES",
    "STATE_NAMES",
    "INPUT_FIELDS",
    "OUTPUT_FIELDS",
    "STATE_FIELDS",
    "FieldInfo",
]

#: The rig's inputs (name, gear_unit, rack_unit, doc, ...) from gs_rig_input_info.
INPUT_FIELDS: tuple[FieldInfo, ...] = INPUT_INFO
#: The rig's outputs from gs_rig_output_info.
OUTPUT_FIELDS: tuple[FieldInfo, ...] = OUTPUT_INFO
#: The rig's state from gs_rig_state_info (the block's fields first).
STATE_FIELDS: tuple[FieldInfo, ...] = STATE_INFO

#: Columns of the N x 5 input array of Rig.run_array, in order (gs_rig_input).
INPUT_NAMES: tuple[str, ...] = tuple(f.name for f in INPUT_INFO)
#: Columns of the N x 15 output array of Rig.run_array, in order (gs_rig_output).
OUTPUT_NAMES: tuple[str, ...] = tuple(f.name for f in OUTPUT_INFO)
#: Keys of Rig.state, in gs_rig_state member order.
STATE_NAMES: tuple[str, ...] = tuple(f.name for f in STATE_INFO)

_IN_COL = {f.name: f.offset // REAL_SIZE for f in INPUT_INFO}
_OUT_COL = {f.name: f.offset // REAL_SIZE for f in OUTPUT_INFO}

# Rig.step's keywords, in the order gspy_rig_step (gearsim_build.py) takes them.
_STEP_INPUTS = ("base_speed", "base_torque", "load", "ambient_temperature", "measured_temperature")
if set(_STEP_INPUTS) != set(INPUT_NAMES):  # pragma: no cover - C and bindings disagree
    raise ImportError(
        f"gearsim: the rig's inputs {INPUT_NAMES} are not Rig.step's keywords {_STEP_INPUTS}"
    )


def _described(f: FieldInfo) -> str:
    """A field's doc with its unit(s), for the RigResult properties."""
    if f.gear_unit == f.rack_unit:
        return f"{f.doc} ({f.gear_unit})"
    return f"{f.doc} ({f.gear_unit} gear rig, {f.rack_unit} rack rig)"


class RigResult(tuple):
    """Outputs of Rig.run (float64 arrays, one value per sample) or Rig.step
    (floats). Units: N*m, rad/s, rad on the base side; N*m, rad/s, rad (gear
    rig) or N, m/s, m (rack rig) on the driven side; W, J, K, m, N otherwise.
    Torques, powers and the contact force are means over the step's contact
    sub-steps; speeds, angles, positions and temperature are end-of-step values.

    Read it by attribute (``out.base_torque``) or by name (``out["base_torque"]``);
    it behaves as a read-only mapping of the FIELDS names. Internally a tuple
    in FIELDS order, so that Rig.step builds one in a fraction of a microsecond.
    """

    __slots__ = ()
    FIELDS: ClassVar[tuple[str, ...]] = OUTPUT_NAMES

    def __new__(cls, **values: Any) -> RigResult:
        missing = [n for n in OUTPUT_NAMES if n not in values]
        extra = [n for n in values if n not in _OUT_COL]
        if missing or extra:
            raise TypeError(f"RigResult needs exactly the fields {OUTPUT_NAMES}")
        return tuple.__new__(cls, [values[n] for n in OUTPUT_NAMES])

    @classmethod
    def _from_values(cls, values: tuple[Any, ...]) -> RigResult:
        """From the values in FIELDS order (no checks; for the bindings)."""
        return tuple.__new__(cls, values)

    @classmethod
    def from_array(cls, out: np.ndarray) -> RigResult:
        """Named column views of an N x 15 output array (Rig.run_array)."""
        return tuple.__new__(cls, [out[:, _OUT_COL[n]] for n in OUTPUT_NAMES])

    def to_dict(self) -> dict[str, Any]:
        return dict(zip(OUTPUT_NAMES, tuple.__iter__(self), strict=True))

    def as_array(self) -> np.ndarray:
        """The outputs as an N x 15 array (columns in FIELDS order)."""
        return np.column_stack([np.atleast_1d(v) for v in tuple.__iter__(self)])

    def _columns(self, time: Any) -> dict[str, np.ndarray]:
        """The outputs as named 1-D columns, ``time`` (s) first when given."""
        data = self.as_array()
        columns: dict[str, np.ndarray] = {}
        if time is not None:
            t = np.asarray(time, dtype=float).reshape(-1)
            if t.shape[0] != data.shape[0]:
                raise ValueError(f"time has {t.shape[0]} values for {data.shape[0]} output samples")
            columns["time"] = t
        for i, name in enumerate(OUTPUT_NAMES):
            columns[name] = data[:, i]
        return columns

    def to_csv(self, path: str | os.PathLike[str], time: Any = None) -> None:
        """Writes the outputs to a CSV file: a header of the FIELDS names
        (``time`` first when ``time``, in s, is given), one row per sample,
        SI units as in the class docstring, every value with the 17 digits
        that round-trip a double. The file is written atomically (a
        temporary file renamed over ``path``)."""
        columns = self._columns(time)
        table = np.column_stack(list(columns.values()))
        with atomic_writer(path, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(columns) + "\n")
            np.savetxt(fh, table, fmt="%.17g", delimiter=",")

    def to_dataframe(self, time: Any = None) -> Any:
        """The outputs as a pandas DataFrame, one column per FIELDS name; with
        ``time`` (s) it is the index, named ``time``. Needs pandas (the
        ``analysis`` extra)."""
        require("RigResult.to_dataframe", ["pandas"])
        import pandas as pd

        columns = self._columns(time)
        frame = pd.DataFrame(columns)
        return frame.set_index("time") if time is not None else frame

    def to_parquet(self, path: str | os.PathLike[str], time: Any = None) -> None:
        """Writes the outputs to a Parquet file (the columns of to_dataframe,
        ``time`` as a column), atomically. Needs pandas and pyarrow."""
        require("RigResult.to_parquet", ["pandas", "pyarrow"])
        frame = self.to_dataframe(time)
        if time is not None:
            frame = frame.reset_index()
        with atomic_writer(path, "wb") as fh:
            frame.to_parquet(fh, index=False)

    def __getitem__(self, name: str) -> Any:  # type: ignore[override]
        if not isinstance(name, str) or name not in _OUT_COL:
            raise KeyError(name)
        return getattr(self, name)

    def keys(self) -> tuple[str, ...]:
        return OUTPUT_NAMES

    def __iter__(self) -> Iterator[str]:  # type: ignore[override]
        return iter(OUTPUT_NAMES)

    def __len__(self) -> int:
        first = tuple.__getitem__(self, 0)
        return int(np.size(first)) if isinstance(first, np.ndarray) else 1

    def __repr__(self) -> str:
        inner = ", ".join(
            f"{n}={v!r}" for n, v in zip(OUTPUT_NAMES, tuple.__iter__(self), strict=True)
        )
        return f"RigResult({inner})"

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("RigResult is read-only")

    __eq__ = object.__eq__  # type: ignore[assignment]
    __ne__ = object.__ne__  # type: ignore[assignment]
    __hash__ = object.__hash__  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        return (RigResult._from_values, (tuple(tuple.__iter__(self)),))


def _field(index: int, doc: str) -> property:
    def get(self: RigResult) -> Any:
        return tuple.__getitem__(self, index)

    return property(get, doc=doc)


for _i, _info in enumerate(OUTPUT_INFO):
    setattr(RigResult, _info.name, _field(_i, _described(_info)))
del _i, _info


@dataclass(frozen=True)
class RigSnapshot:
    """The state of a rig (the bytes of its C gs_rig_state, which holds
    everything a step changes), for Rig.restore. Picklable. Restores into any
    rig of the same block kind: with the same parameters it continues
    bit-identically; with others it continues from this state under the new
    parameters (a re-tuned rig)."""

    block: str
    state: bytes


class Rig:
    """A block between a base shaft and the driven side (the C rig: its
    constants, filled once at construction, and its state).

    Args:
        block: a SimpleGear or a RackPinion.
        dt: fixed step (s).
        temperature_input: when True, the losses use the measured_temperature
            input instead of the thermal state.
        **rig_params: the rig parameters (listed with their units in
            help(GearRig) and help(RackRig), read from the C parameter
            tables), SI numbers or unit strings; missing ones take the
            defaults (Rig.defaults()).
    """

    def __init__(
        self,
        block: Block,
        *,
        dt: float | str = 1e-3,
        temperature_input: bool = False,
        **rig_params: Any,
    ) -> None:
        if not isinstance(block, Block):
            raise TypeError(
                f"block must be a SimpleGear or a RackPinion, got {type(block).__name__}"
            )
        kind = block.kind
        rig_specs = {p.name: p for p in P.BLOCKS[kind][1]}
        dt_value = P.normalize(P.RIG_ARGUMENT_PARAMS["dt"], dt)
        given = P.normalize_all(rig_specs, rig_params, f"{kind} rig")
        full = {**P.rig_defaults(kind), **given}
        c_params = ffi.new("gs_rig_params *")
        c_params[0] = lib.gs_rig_params_default()
        P.write_struct(P.BLOCKS[kind][1], full, c_params)
        c_params.dt_s = dt_value
        c_params.heat_path = 0 if full["thermal_resistance"] is None else 1
        c_params.temperature_source = (
            lib.GS_TEMPERATURE_FROM_INPUT if temperature_input else lib.GS_TEMPERATURE_FROM_MODEL
        )
        consts = ffi.new("gs_rig_consts *")
        state = ffi.new("gs_rig_state *")
        err = ffi.new("gs_error *")
        if kind == "simple_gear":
            status = lib.gs_rig_init_gear(consts, state, block._c_params, c_params, err)
        else:
            status = lib.gs_rig_init_rack(consts, state, block._c_params, c_params, err)

        def value_of(name: str) -> Any:  # called by check() only on failure
            return {**block.params, **full, "dt": dt_value}[name]

        check(status, err, rename=P.c_rig_names(kind), value_of=value_of)
        info = ffi.new("gs_rig_info *")
        lib.gs_rig_get_info(consts, info)
        self._substeps = int(info.contact_substeps)
        self._follower_per_base = float(info.follower_per_base)
        self._h_omega_n = float(info.contact_h_omega_n)
        self._substeps_capped = bool(info.substeps_capped)
        self._info = _info_dict(info)
        if self._substeps_capped:
            warnings.warn(
                f"backlash contact: the automatic sub-step count stopped at "
                f"{int(info.contact_substeps)} with h*omega_n = {self._h_omega_n:.3g} "
                f"> {lib.GS_AUTO_H_OMEGA_N_MAX:g} "
                f"(dt = {dt_value!r} s): the contact is stable but over-damped; lower dt "
                f"or set contact_substeps (up to {int(lib.GS_MAX_SUBSTEPS)})",
                SubstepWarning,
                stacklevel=caller_stacklevel(),
            )
        ambient = full["ambient_temperature"]
        if not (math.isfinite(ambient) and ambient > 0):
            raise ParameterError(
                f"must be a finite temperature > 0 K, got {ambient!r}",
                parameter="ambient_temperature",
                status="GS_E_NOT_POSITIVE",
            )
        self._block = block
        self._kind = kind
        self._dt = dt_value
        self._temperature_input = bool(temperature_input)
        self._given = given
        self._full = full
        # The constants are read-only after init (shared by copies); the state
        # is what a step changes (a snapshot is a copy of it).
        self._consts = consts
        self._c_rig_params = c_params  # what init took: the HIL bridge changes parameters from it
        self._state = state
        self._stepper, self._step_out = _stepper(consts, state)
        self._ambient = float(full["ambient_temperature"])
        self._speed_driven = full["base_drive"] == "speed"
        self.model: Any = None  # set by Model.rig()

    # -- description ---------------------------------------------------------
    @classmethod
    def defaults(cls, block: str = "simple_gear") -> dict[str, Any]:
        """Default rig parameters for a block ("simple_gear" or "rack_pinion")."""
        return P.rig_defaults(block)

    @property
    def kind(self) -> str:
        """ "simple_gear" or "rack_pinion"."""
        return self._kind

    @property
    def block(self) -> Block:
        """The SimpleGear or RackPinion inside."""
        return self._block

    @property
    def dt(self) -> float:
        """Fixed step (s)."""
        return self._dt

    @property
    def temperature_input(self) -> bool:
        return self._temperature_input

    @property
    def base_drive(self) -> str:
        """ "speed" or "torque"."""
        return str(self._full["base_drive"])

    @property
    def ambient_temperature(self) -> float:
        """Ambient temperature used when run/step get none (K)."""
        return self._ambient

    @property
    def params(self) -> dict[str, Any]:
        """Every rig parameter in use (given or default), SI units."""
        return dict(self._full)

    @property
    def given_params(self) -> dict[str, Any]:
        return dict(self._given)

    @property
    def substeps(self) -> int:
        """Contact sub-steps per step chosen by the C rig (1 without backlash)."""
        return self._substeps

    @property
    def follower_per_base(self) -> float:
        """Follower speed per base speed of the rigid mesh: s/g (rad/s per
        rad/s, gear rig) or s_R*r_P (m/s per rad/s, rack rig)."""
        return self._follower_per_base

    @property
    def input_units(self) -> dict[str, str]:
        """Unit of each input in this rig (pint syntax), from the C field table."""
        return {f.name: f.unit(self._kind) for f in INPUT_INFO}

    @property
    def output_units(self) -> dict[str, str]:
        """Unit of each output (RigResult field) in this rig, from the C field table."""
        return {f.name: f.unit(self._kind) for f in OUTPUT_INFO}

    @property
    def state_units(self) -> dict[str, str]:
        """Unit of each Rig.state entry in this rig ("1" for the flags)."""
        return {f.name: f.unit(self._kind) for f in STATE_INFO}

    @property
    def contact_h_omega_n(self) -> float:
        """h*omega_n of the backlash contact at the chosen sub-step (0 without
        backlash): gearsim.AUTO_H_OMEGA_N_MAX is the automatic target, about
        0.05 resolves a rebound."""
        return self._h_omega_n

    @property
    def compliance_substeps(self) -> int:
        """Sub-steps per step of the compliant base shaft (1 without compliance)."""
        return int(self._info["compliance_substeps"])

    @property
    def compliance_h_omega_n(self) -> float:
        """h*omega_c of the compliant shaft at its sub-step, omega_c = sqrt(k/J_eff)
        (0 without compliance): <= 0.2 unless the sub-step count is at its cap
        of 16; the shaft then rings (2/h)*atan(h*omega_c/2) instead of omega_c."""
        return float(self._info["compliance_h_omega_n"])

    @property
    def info(self) -> dict[str, float | int]:
        """Everything init chose (gs_rig_info, field by field): contact_substeps,
        contact_h_omega_n, substeps_capped, follower_per_base,
        compliance_substeps, compliance_h_omega_n."""
        return dict(self._info)

    @property
    def substeps_capped(self) -> bool:
        """True when the automatic sub-step count stopped at its cap with
        h*omega_n above gearsim.AUTO_H_OMEGA_N_MAX (a SubstepWarning was issued at
        construction)."""
        return self._substeps_capped

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._given.items())
        sep = ", " if args else ""
        return (
            f"{type(self).__name__}({self._block!r}, dt={self._dt!r}, "
            f"temperature_input={self._temperature_input!r}{sep}{args})"
        )

    # -- state -----------------------------------------------------------------
    @property
    def state(self) -> dict[str, float | int]:
        """The rig's state by name (STATE_NAMES, from gs_rig_state_info; units
        in state_units): temperature, backlash_position, contact_force,
        follower_torque, contact_locked (the block's), base_speed, base_angle,
        follower_speed, follower_position, base_speed_sample,
        base_acceleration, shaft_twist, started. Floats, and ints for the flags. A copy:
        writing to it does not change the rig (use snapshot/restore)."""
        buf = ffi.buffer(self._state)
        return {name: unpack(buf, offset)[0] for name, unpack, offset in _STATE_READERS}

    def reset(self) -> None:
        """Back to the initial state (speeds, angles, temperature, backlash)."""
        lib.gs_rig_reset(self._consts, self._state)

    def snapshot(self) -> RigSnapshot:
        """The state (a copy of the C gs_rig_state); restore() continues
        bit-identically."""
        return RigSnapshot(self._kind, bytes(ffi.buffer(self._state)))

    def restore(self, snapshot: RigSnapshot) -> None:
        """Restore a snapshot() of this rig or of another rig of the same block
        kind (with other parameters, the rig continues from that state under
        its own parameters)."""
        if not isinstance(snapshot, RigSnapshot):
            raise TypeError(f"expected a RigSnapshot, got {type(snapshot).__name__}")
        if snapshot.block != self._kind:
            raise GearsimError(
                f"snapshot of a {snapshot.block} rig cannot restore a {self._kind} rig"
            )
        if len(snapshot.state) != ffi.sizeof("gs_rig_state"):
            raise GearsimError(
                f"snapshot of {len(snapshot.state)} bytes, expected "
                f"{ffi.sizeof('gs_rig_state')} (another gearsim version?)"
            )
        ffi.memmove(self._state, snapshot.state, len(snapshot.state))

    def copy(self) -> Rig:
        """An independent rig with the same parameters and state (the constants,
        read-only, are shared; the state is copied)."""
        new = self.__class__.__new__(self.__class__)
        new.__dict__.update(self.__dict__)
        new._state = ffi.new("gs_rig_state *", self._state[0])
        new._stepper, new._step_out = _stepper(new._consts, new._state)
        return new

    # -- stepping --------------------------------------------------------------
    def step(
        self,
        *,
        base_speed: float | None = None,
        base_torque: float | None = None,
        load: float = 0.0,
        ambient_temperature: float | None = None,
        measured_temperature: float | None = None,
    ) -> RigResult:
        """One step of dt (gs_rig_step). Returns a RigResult of floats.

        base_speed (rad/s) is required for a speed-driven rig, base_torque (N*m)
        for a torque-driven one; load (N*m or N) defaults to 0,
        ambient_temperature (K) to the rig's, measured_temperature (K) is
        required when the rig was built with temperature_input=True.
        """
        if self._speed_driven:
            if base_speed is None:
                raise InputError("required by a speed-driven rig", parameter="base_speed")
            if base_torque is None:
                base_torque = 0.0
        else:
            if base_torque is None:
                raise InputError("required by a torque-driven rig", parameter="base_torque")
            if base_speed is None:
                base_speed = 0.0
        ambient = self._ambient if ambient_temperature is None else ambient_temperature
        if measured_temperature is None:
            if self._temperature_input:
                raise InputError(
                    "required by a rig built with temperature_input=True",
                    parameter="measured_temperature",
                )
            measured_temperature = ambient
        # Fast path: one C call converts the five values to doubles, checks that
        # they are finite and steps (gspy_rig_step, gearsim_build.py); only a
        # failure looks at each value (which names the bad input).
        try:
            bad = _step_c(
                self._stepper, base_speed, base_torque, load, ambient, measured_temperature
            )
        except (TypeError, ValueError, OverflowError):
            bad = 1
        if bad:
            _step_checked(
                self._stepper, base_speed, base_torque, load, ambient, measured_temperature
            )
        return _new_tuple(RigResult, _unpack_out(self._step_out))

    def inputs(
        self,
        *,
        base_speed: Any = None,
        base_torque: Any = None,
        load: Any = None,
        ambient_temperature: Any = None,
        measured_temperature: Any = None,
        n: int | None = None,
    ) -> np.ndarray:
        """The N x 5 input array of run_array() from named inputs (arrays of
        equal length, or scalars broadcast; n gives the length when all are
        scalars). Checks as in step()."""
        given = {
            "base_speed": base_speed,
            "base_torque": base_torque,
            "load": load,
            "ambient_temperature": ambient_temperature,
            "measured_temperature": measured_temperature,
        }
        driving = "base_speed" if self._speed_driven else "base_torque"
        if given[driving] is None:
            raise InputError(f"required by a {self.base_drive}-driven rig", parameter=driving)
        if self._temperature_input and measured_temperature is None:
            raise InputError(
                "required by a rig built with temperature_input=True",
                parameter="measured_temperature",
            )
        arrays: dict[str, np.ndarray] = {}
        length = n
        for name, value in given.items():
            if value is None:
                continue
            arr = np.asarray(value, dtype=np.float64)
            if arr.ndim > 1:
                raise InputError(f"must be one-dimensional, got shape {arr.shape}", parameter=name)
            if arr.ndim == 1:
                if length is None:
                    length = arr.shape[0]
                elif arr.shape[0] != length:
                    raise InputError(
                        f"has {arr.shape[0]} samples, expected {length}", parameter=name
                    )
            arrays[name] = arr
        if length is None:
            raise InputError("all inputs are scalars; give n (the number of steps)", parameter="n")
        if length < 0:
            raise InputError(f"must be >= 0, got {length}", parameter="n")
        out = np.zeros((length, lib.GS_RIG_INPUT_FIELDS), dtype=np.float64)
        for name, arr in arrays.items():
            out[:, _IN_COL[name]] = arr
        if ambient_temperature is None:
            out[:, _IN_COL["ambient_temperature"]] = self.ambient_temperature
        if measured_temperature is None:
            out[:, _IN_COL["measured_temperature"]] = out[:, _IN_COL["ambient_temperature"]]
        return out

    def run(
        self,
        *,
        base_speed: Any = None,
        base_torque: Any = None,
        load: Any = None,
        ambient_temperature: Any = None,
        measured_temperature: Any = None,
        n: int | None = None,
    ) -> RigResult:
        """Run len(inputs) steps in C (gs_rig_run), continuing from the current
        state. Inputs as in step(), as arrays of equal length or scalars
        broadcast. Returns a RigResult of float64 arrays."""
        inputs = self.inputs(
            base_speed=base_speed,
            base_torque=base_torque,
            load=load,
            ambient_temperature=ambient_temperature,
            measured_temperature=measured_temperature,
            n=n,
        )
        return RigResult.from_array(self.run_array(inputs))

    def run_array(self, inputs: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Low-level batch run: inputs is N x 5 (columns INPUT_NAMES, the fields
        of gs_rig_input), the result N x 15 (columns OUTPUT_NAMES). out, if
        given, must be a C-contiguous, writable float64 N x 15 array."""
        arr = np.ascontiguousarray(inputs, dtype=np.float64)
        n_in = lib.GS_RIG_INPUT_FIELDS
        if arr.ndim != 2 or arr.shape[1] != n_in:
            raise InputError(
                f"inputs must be N x {n_in}, got shape {arr.shape}", parameter="inputs"
            )
        n = arr.shape[0]
        bad = ~np.isfinite(arr)
        if bad.any():
            row, col = (int(i) for i in np.argwhere(bad)[0])
            raise InputError(
                f"non-finite value {arr[row, col]!r} at sample {row}", parameter=INPUT_NAMES[col]
            )
        shape = (n, lib.GS_RIG_OUTPUT_FIELDS)
        if out is None:
            out = np.empty(shape, dtype=np.float64)
        elif (
            out.shape != shape
            or out.dtype != np.float64
            or not out.flags.c_contiguous
            or not out.flags.writeable
        ):
            raise InputError(
                f"out must be a C-contiguous writable float64 array of shape {shape}",
                parameter="out",
            )
        if n:
            c_in = ffi.cast("gs_rig_input *", ffi.from_buffer(arr))
            c_out = ffi.cast("gs_rig_output *", ffi.from_buffer(out, require_writable=True))
            lib.gs_rig_run(self._consts, self._state, n, c_in, c_out)
        return out


# Rig.step passes the five inputs by value to gspy_rig_step (the bindings' C
# shim, gearsim_build.py), which steps into the gs_rig_output of a per-rig
# gspy_stepper; the result is read from the stepper's first bytes (out is its
# first member) in one struct.unpack_from (all-double struct, fields in column
# order = FIELDS order).
_step_c = lib.gspy_rig_step
_unpack_out = struct.Struct(f"@{lib.GS_RIG_OUTPUT_FIELDS}d").unpack_from
_new_tuple = tuple.__new__

# Rig.state: (name, unpack_from of its C type, offset) per gs_rig_state_info entry.
_STATE_READERS = tuple(
    (f.name, struct.Struct("@i" if f.is_integer else "@d").unpack_from, f.offset)
    for f in STATE_INFO
)


def _stepper(consts: Any, state: Any) -> tuple[Any, Any]:
    """A gspy_stepper for a rig's gs_rig_consts * and gs_rig_state * (which the
    caller keeps alive), and a buffer over it whose first bytes are its
    gs_rig_output."""
    stepper = ffi.new("gspy_stepper *")
    stepper.consts = consts
    stepper.state = state
    return stepper, ffi.buffer(stepper)


def _step_checked(stepper: Any, *values: Any) -> None:
    """Rig.step's slow path: convert and check each input in order, raising an
    InputError that names the first bad one; step when all are good (inputs
    the fast path's conversion refused but float() takes, such as "1.5")."""
    good = [_finite(name, value) for name, value in zip(_STEP_INPUTS, values, strict=True)]
    _step_c(stepper, *good)  # all finite floats now: the shim steps and returns 0


def _info_dict(info: Any) -> dict[str, float | int]:
    """gs_rig_info -> {field: value}, every field of the C struct (ints stay ints)."""
    values: dict[str, float | int] = {}
    for name, field in ffi.typeof("gs_rig_info").fields:
        raw = getattr(info, name)
        values[name] = (
            int(raw) if field.type.kind == "primitive" and field.type.cname == "int" else float(raw)
        )
    return values


def _finite(name: str, value: Any) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", parameter=name) from None
    if not math.isfinite(x):
        raise InputError(f"must be finite, got {value!r}", parameter=name)
    return x


def _split(
    block_cls: type[Block], block: Any, params: dict[str, Any]
) -> tuple[Block, dict[str, Any]]:
    """Block object and rig parameters from GearRig/RackRig arguments: keyword
    parameters that are block parameters go to the block."""
    block_keys = {k: v for k, v in params.items() if k in block_cls.parameter_names()}
    rig_params = {k: v for k, v in params.items() if k not in block_keys}
    if isinstance(block, block_cls):
        if block_keys:
            return block.replace(**block_keys), rig_params
        return block, rig_params
    if isinstance(block, Block):
        raise TypeError(f"{block_cls.__name__} expected, got {type(block).__name__}")
    return block_cls(**{**dict(block or {}), **block_keys}), rig_params


class GearRig(Rig):
    """Simple Gear rig: a SimpleGear between the speed- or torque-driven base
    shaft and the follower inertia.

    gear is a SimpleGear, a mapping of its parameters, or None; keyword
    parameters that are Simple Gear parameters (teeth_ratio, friction_model,
    ...) go to the gear, the others are rig parameters (see Rig):
    ``GearRig(teeth_ratio=3, follower_inertia=0.02, dt=1e-3)``.
    """

    def __init__(
        self,
        gear: SimpleGear | Mapping[str, Any] | None = None,
        *,
        dt: float | str = 1e-3,
        temperature_input: bool = False,
        **params: Any,
    ) -> None:
        block, rig_params = _split(SimpleGear, gear, params)
        super().__init__(block, dt=dt, temperature_input=temperature_input, **rig_params)


class RackRig(Rig):
    """Rack & Pinion rig: a RackPinion between the speed- or torque-driven pinion
    shaft and the rack mass.

    rack is a RackPinion, a mapping of its parameters, or None; keyword
    parameters that are Rack & Pinion parameters (pinion_radius, ...) go to the
    block, the others are rig parameters (see Rig):
    ``RackRig(pinion_radius="20 mm", rack_mass=2.0)``.
    """

    def __init__(
        self,
        rack: RackPinion | Mapping[str, Any] | None = None,
        *,
        dt: float | str = 1e-3,
        temperature_input: bool = False,
        **params: Any,
    ) -> None:
        block, rig_params = _split(RackPinion, rack, params)
        super().__init__(block, dt=dt, temperature_input=temperature_input, **rig_params)


GearRig.__doc__ = f"{GearRig.__doc__}\n    Rig parameters:\n\n{P.describe(P.GEAR_RIG_PARAMS)}\n"
RackRig.__doc__ = f"{RackRig.__doc__}\n    Rig parameters:\n\n{P.describe(P.RACK_RIG_PARAMS)}\n"

"""What a loaded measurement is: the rig's canonical columns by role
(:class:`RigSpec`), the facts of a rig-time CSV (:class:`RecordedTimeBase`),
the validated record (:class:`Measurement`) with the notes on how it was read,
and the canonical CSV it is written back as."""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..._outputs import atomic_writer
from ...columns import OPTIONAL, RIGS, RigColumns
from ...errors import caller_stacklevel
from ..errors import MeasurementError


class MeasurementWarning(UserWarning):
    """A measurement was read but something in it looks wrong (e.g. a time
    column that looks like milliseconds)."""


@dataclass(frozen=True)
class RigSpec:
    """The canonical columns of one rig (contract section 1), by role.

    Derived from :data:`gearsim.columns.RIGS`, the one definition of the
    columns, which the HIL recording uses too. driven_*: the driven side
    (follower shaft or rack), as texts name it."""

    block: str
    speed_input: str
    load_input: str
    torque_output: str
    speed_output: str
    speed_unit: str
    load_unit: str
    torque_unit: str
    driven_speed_unit: str
    driven_force_unit: str
    driven_name: str

    @classmethod
    def from_columns(cls, rig: RigColumns) -> RigSpec:
        return cls(
            block=rig.block,
            speed_input=rig.speed_input.name,
            load_input=rig.load_input.name,
            torque_output=rig.torque_output.name,
            speed_output=rig.speed_output.name,
            speed_unit=rig.speed_input.unit,
            load_unit=rig.load_input.unit,
            torque_unit=rig.torque_output.unit,
            driven_speed_unit=rig.speed_output.unit,
            driven_force_unit=rig.driven_force_unit,
            driven_name=rig.driven,
        )

    @property
    def columns(self) -> RigColumns:
        """The columns of this rig, with the rig signal each maps to."""
        return RIGS[self.block]

    @property
    def inputs(self) -> tuple[str, str]:
        return (self.speed_input, self.load_input)

    @property
    def outputs(self) -> tuple[str, str]:
        return (self.torque_output, self.speed_output)

    @property
    def required(self) -> tuple[str, ...]:
        return ("time", self.speed_input, self.load_input, self.torque_output, self.speed_output)

    def unit(self, column: str) -> str:
        """The SI unit of ``column`` ("" for a column this rig does not have)."""
        col = self.columns.column(column)
        return col.unit if col is not None else ""


RIG_SPECS: dict[str, RigSpec] = {block: RigSpec.from_columns(rig) for block, rig in RIGS.items()}


@dataclass(frozen=True)
class RecordedTimeBase:
    """What the first line of a ``gearsim hil to-csv`` CSV says about its rows.

    kind: "rig" (the rows are the instants at which a rig stepped every
    ``rig_dt`` seconds sent its outputs; the ``held`` input columns were held
    constant over each rig step, changing at the row's ``inputs_since``) or
    "wall" (resampled from a wall-clock log). steps_per_row: rig steps per row
    interval (the row step divided by rig_dt; 0 for "wall")."""

    kind: str
    rig_dt: float | None = None
    held: tuple[str, ...] = ()
    steps_per_row: int = 0

    @property
    def is_rig(self) -> bool:
        return self.kind == "rig"

    @property
    def rig_step(self) -> float:
        """rig_dt (s) of a rig-time base; a wall-clock base has none."""
        if self.rig_dt is None:
            raise ValueError(f"a time base of kind {self.kind!r} has no rig step")
        return self.rig_dt


OPTIONAL_INPUTS: tuple[str, ...] = tuple(col.name for col in OPTIONAL)


@dataclass(frozen=True)
class Measurement:
    """A validated measurement: uniform time axis and finite columns.

    time: s, strictly increasing; dt: the uniform step (s); data: canonical
    column name -> float64 array (SI units); path: where it came from (for
    messages)."""

    spec: RigSpec
    time: np.ndarray
    dt: float
    data: Mapping[str, np.ndarray]
    path: str = "<memory>"
    notes: tuple[str, ...] = field(default=())
    time_base: RecordedTimeBase | None = None
    """the to-csv first line's facts (None: a file without it)"""

    @property
    def n(self) -> int:
        return int(self.time.size)

    @property
    def block(self) -> str:
        return self.spec.block

    @property
    def has_temperature(self) -> bool:
        return "temperature" in self.data

    @property
    def has_ambient(self) -> bool:
        return "ambient_temperature" in self.data

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[name]

    def slice(self, start: int, stop: int, step: int = 1) -> Measurement:
        """Sub-measurement of samples [start:stop:step] (dt scales with step).

        Keeping every step-th row of a rig-time CSV loses what the rig applied
        between the kept rows: such a slice forgets its time base."""
        sl = slice(start, stop, step)
        return replace(
            self,
            time=self.time[sl],
            dt=self.dt * step,
            data={k: v[sl] for k, v in self.data.items()},
            time_base=self.time_base if step == 1 else None,
        )

    def with_data(self, **columns: np.ndarray) -> Measurement:
        data = dict(self.data)
        data.update({k: np.asarray(v, dtype=float) for k, v in columns.items()})
        return replace(self, data=data)

    @classmethod
    def from_arrays(
        cls, block: str, time: np.ndarray, path: str = "<memory>", **columns: np.ndarray
    ) -> Measurement:
        """Build and validate a measurement from arrays (canonical names)."""
        from .validate import validate_table  # it builds Measurements: imported here, not above

        spec = rig_spec(block)
        arrays = {"time": np.asarray(time, dtype=float)}
        arrays.update({k: np.asarray(v, dtype=float) for k, v in columns.items()})
        names = [c for c in spec.required + OPTIONAL_INPUTS if c in arrays]
        for c in spec.required:
            if c not in arrays:
                raise MeasurementError(
                    f"missing column (the {block} rig needs {', '.join(spec.required)})",
                    file=path,
                    column=c,
                )
        n = arrays["time"].size
        for c in names:
            if arrays[c].shape != (n,):
                raise MeasurementError(
                    f"has {arrays[c].size} values, time has {n}", file=path, column=c
                )
        table = np.column_stack([arrays[c] for c in names])
        return validate_table(table, names, spec, path, resample=False, line_of=lambda i: None)


def rig_spec(block: str) -> RigSpec:
    """The columns of the rig of `block`; an unknown block is an error."""
    try:
        return RIG_SPECS[block]
    except KeyError:
        raise MeasurementError(
            f"unknown rig block '{block}' (expected one of {', '.join(RIG_SPECS)})"
        ) from None


class Notes:
    """Notes on how a file was read: kept for Measurement.notes and passed on."""

    def __init__(self, shown: str, note: Callable[[str], None] | None) -> None:
        self.shown = shown
        self.note = note
        self.items: list[str] = []

    def info(self, msg: str) -> None:
        self.items.append(msg)
        if self.note is not None:
            self.note(f"{self.shown}: {msg}")

    def warn(self, msg: str) -> None:
        self.items.append(f"warning: {msg}")
        if self.note is not None:
            self.note(f"{self.shown}: warning: {msg}")
        else:
            warnings.warn(
                f"{self.shown}: {msg}", MeasurementWarning, stacklevel=caller_stacklevel()
            )


def write_measurement(path: str | os.PathLike[str], meas: Measurement, *, digits: int = 9) -> None:
    """Write a measurement as a canonical CSV (header row, %.{digits}g values)."""
    names = [*meas.spec.required, *(c for c in OPTIONAL_INPUTS if c in meas.data)]
    cols = [meas.time] + [meas.data[c] for c in names[1:]]
    arr = np.column_stack(cols)
    fmt = f"%.{digits}g"
    with atomic_writer(path, "w", newline="\n") as fh:
        fh.write(",".join(names) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt=fmt)

"""The rig-time stage: the first line ``# gearsim hil to-csv: time_base=rig
rig_dt=H held=COLUMNS`` that ``gearsim hil to-csv`` writes (docs/measurement-format.md
section 1.7), the ``inputs_since`` and ``<input>_before`` columns it requires,
and the check of the rows against it once they are validated."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..._outputs import printable
from ...columns import BEFORE_SUFFIX, INPUTS_SINCE, RIG_TIME_MARKER
from ..errors import MeasurementError
from .record import Measurement, Notes, RecordedTimeBase, RigSpec
from .sniff import Column, Layout, resolve
from .source import decode, iter_lines

MARKER = RIG_TIME_MARKER
#: How far (relative) the row step may be from a whole number of rig steps.
_SUBSTEP_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Marker:
    line: int  # 1-based line of the marker
    time_base: RecordedTimeBase


def read_marker(data: bytes, spec: RigSpec, shown: str) -> Marker | None:
    """The facts of a leading ``# gearsim hil to-csv: key=value ...`` line
    (docs/measurement-format.md section 1.7), or None when the first line is
    anything else. Unknown keys are ignored (a newer to-csv may add some)."""
    for lineno, _start, raw, _next in iter_lines(data):
        text = decode(raw).strip().lstrip("\ufeff")
        if not text:
            continue
        if not text.startswith(MARKER):
            return None
        facts: dict[str, str] = {}
        for item in text[len(MARKER) :].split():
            key, sep, value = item.partition("=")
            if not sep or not key:
                raise MeasurementError(
                    f"'{printable(item, 40)}' in the gearsim hil to-csv line is not KEY=VALUE",
                    file=shown,
                    line=lineno,
                )
            facts[key] = value
        return Marker(lineno, _time_base_of(facts, spec, shown, lineno))
    return None


def _time_base_of(facts: dict[str, str], spec: RigSpec, shown: str, line: int) -> RecordedTimeBase:
    def bad(key: str, why: str) -> MeasurementError:
        value = printable(facts.get(key, ""), 40)
        return MeasurementError(
            f"{key}={value} in the gearsim hil to-csv line {why}", file=shown, line=line
        )

    kind = facts.get("time_base")
    if kind == "wall":
        return RecordedTimeBase("wall")
    if kind != "rig":
        raise bad("time_base", "is not 'rig' or 'wall'")
    try:
        rig_dt = float(facts.get("rig_dt", ""))
    except ValueError:
        rig_dt = math.nan
    if not (math.isfinite(rig_dt) and rig_dt > 0.0):
        raise bad("rig_dt", "is not a positive number of seconds (the rig step)")
    held: list[str] = []
    for name in filter(None, (h.strip() for h in facts.get("held", "").split(","))):
        if name not in spec.inputs:
            raise bad(
                "held",
                f"names '{printable(name, 40)}', which is not an input column of the "
                f"{spec.block} rig ({', '.join(spec.inputs)})",
            )
        if name not in held:
            held.append(name)
    return RecordedTimeBase("rig", rig_dt, tuple(held))


def rig_time_columns(
    marker: Marker | None, layout: Layout, spec: RigSpec, shown: str
) -> list[Column]:
    """The ``inputs_since`` and ``<input>_before`` columns a rig-time CSV must
    have (none for a file without the first line, or in wall-clock time)."""
    if marker is None or not marker.time_base.is_rig:
        return []
    fields, line, how = layout.fields, layout.header.line, layout.how
    needed = {INPUTS_SINCE: "time"}
    needed.update({name + BEFORE_SUFFIX: name for name in marker.time_base.held})
    found: list[Column] = []
    for name, unit_of in needed.items():
        col = resolve(name, None, fields, spec=spec, shown=shown, line=line, how=how)
        if col is None:
            raise MeasurementError(
                f"missing column: the first line (line {marker.line}) says time_base=rig, "
                f"which needs the columns {', '.join(needed)} (as gearsim hil to-csv writes them)",
                file=shown,
                line=line,
                column=name,
            )
        col.unit_of = unit_of
        found.append(col)
    return found


def check_time_base(
    meas: Measurement,
    marker: Marker | None,
    notes: Notes,
    shown: str,
    line_of: Callable[[int], int],
) -> RecordedTimeBase | None:
    """The time base to keep on the measurement, once its rows are checked
    against it: a warning for a wall-clock CSV, the rig steps per row for a
    rig-time one; None for a file without the first line."""
    if marker is None:
        return None
    base = marker.time_base
    if not base.is_rig:
        notes.warn(
            "the first line says time_base=wall: this CSV was resampled from a wall-clock "
            "log and cannot reproduce the run step for step; record with 'gearsim hil run "
            "--log' (rig time) instead"
        )
        return base
    if any(n.startswith("resampled") for n in meas.notes):
        notes.warn(
            "the rig-time rows were resampled: the model is stepped once per row, not per "
            "rig step as the first line says"
        )
        return None
    ratio = meas.dt / base.rig_step
    steps = round(ratio)
    if steps < 1 or abs(ratio - steps) > _SUBSTEP_TOLERANCE * steps:
        raise MeasurementError(
            f"rig_dt={base.rig_dt!r} in the gearsim hil to-csv line does not divide the row "
            f"step {meas.dt:.9g} s into whole rig steps (ratio {ratio:.9g})",
            file=shown,
            line=marker.line,
        )
    _check_inputs_since(meas, base.rig_step, shown, line_of)
    notes.info(
        f"rig time (line {marker.line}): the model is stepped every {base.rig_dt:g} s, "
        f"{steps} steps per row"
        + (f", with {', '.join(base.held)} held as the rig applied them" if base.held else "")
    )
    return replace(base, steps_per_row=steps)


def _check_inputs_since(
    meas: Measurement, rig_dt: float, shown: str, line_of: Callable[[int], int]
) -> None:
    """Each row's inputs_since lies in the interval that ends at the row (half
    a rig step of slack for the rounding of the text)."""
    since = meas[INPUTS_SINCE]
    outside = (since < meas.time - meas.dt - 0.5 * rig_dt) | (since > meas.time + 0.5 * rig_dt)
    if outside.any():
        r = int(np.nonzero(outside)[0][0])
        raise MeasurementError(
            f"inputs_since {float(since[r])!r} s is outside the row's interval "
            f"({float(meas.time[r] - meas.dt)!r} s to {float(meas.time[r])!r} s)",
            file=shown,
            line=line_of(r),
            column=INPUTS_SINCE,
        )

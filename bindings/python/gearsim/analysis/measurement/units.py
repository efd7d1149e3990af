"""The units stage: the unit written in a header cell (``time [ms]``,
``base_speed (rpm)``) converted with pint to the SI unit of its canonical
column, or refused with the column, the unit and the way out; and the warning
for a time column without unit that steps like milliseconds."""

from __future__ import annotations

import re
import unicodedata

import numpy as np

from ..._outputs import printable
from ..errors import MeasurementError
from .record import Notes, RigSpec
from .sniff import Column, name_unit

_UNIT_SPELLINGS = (
    (re.compile(r"[·⋅×]"), "*"),
    (re.compile(r"[µμ]"), "u"),
    (re.compile(r"°\s*C\b"), "degC"),
    (re.compile(r"°\s*F\b"), "degF"),
    (re.compile(r"°"), "degree"),
    (re.compile(r"²"), "**2"),
    (re.compile(r"(?<![A-Za-z])([mkMu]?)N\s*\.?\s*m(?![A-Za-z])"), r"\1N*m"),
    (re.compile(r"(?<![A-Za-z])U\s*/\s*min(?![A-Za-z])"), "rpm"),
    (re.compile(r"(?<![A-Za-z])rpm(?![A-Za-z])", re.IGNORECASE), "rpm"),
    (re.compile(r"(?<![A-Za-z])revs?(?![A-Za-z])"), "revolution"),
    (re.compile(r"(?<![A-Za-z])sec(?![A-Za-z])"), "s"),
)


def _normalize_unit(unit: str) -> str:
    u = unicodedata.normalize("NFC", unit).strip()
    for pattern, repl in _UNIT_SPELLINGS:
        u = pattern.sub(repl, u)
    return u


def _unit_conversion(col: Column, spec: RigSpec, shown: str, line: int) -> tuple[float, float]:
    """(factor, offset) taking the header unit of `col` to the SI unit of its
    canonical column; raises naming the column, the unit and the way out."""
    from ...units import registry

    target = spec.unit(col.si_column)
    unit = col.unit or ""
    shown_unit = printable(unit, 30)
    way_out = (
        f"write a unit pint reads in the header (e.g. [{target}], [ms], [rpm], [mN*m], [degC]) "
        f"or map the column with its factor to {target}: "
        f"--column {col.canonical}='{printable(col.header, 60)}*FACTOR'"
    )
    ureg = registry()
    try:
        src = ureg.parse_units(_normalize_unit(unit))
        tgt = ureg.parse_units(target)
    except Exception:
        raise MeasurementError(
            f"unknown unit '{shown_unit}' in the header ({col.canonical} is in {target}); "
            + way_out,
            file=shown,
            line=line,
            column=col.shown,
        ) from None

    def radians(u) -> float:
        return dict(ureg.get_root_units(u)[1]._units).get("radian", 0)

    if radians(src) != radians(tgt):
        raise MeasurementError(
            f"unit '{shown_unit}' cannot be converted to {target}: "
            + (
                "it has no angle (revolutions or radians?); "
                if radians(tgt)
                else "it has an angle that the column does not; "
            )
            + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    if target == "K" and any(str(n).startswith("delta") for n in src._units):
        raise MeasurementError(
            f"unit '{shown_unit}' is a temperature difference; an absolute temperature is "
            "expected; " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    try:
        y = ureg.Quantity(np.array([0.0, 1.0]), src).to(tgt).magnitude
    except Exception:
        raise MeasurementError(
            f"unit '{shown_unit}' cannot be converted to {target} ({col.canonical}); " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        ) from None
    offset, factor = float(y[0]), float(y[1] - y[0])
    if not (np.isfinite(factor) and np.isfinite(offset)) or factor == 0.0:
        raise MeasurementError(
            f"unit '{shown_unit}' gives no usable conversion to {target}; " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    return factor, offset


def convert_units(wanted: list[Column], spec: RigSpec, shown: str, line: int, notes: Notes) -> None:
    """Sets the (factor, offset) to SI of every column with a unit in its header
    (a mapping's explicit factor wins over it); notes what was converted."""
    converted: list[str] = []
    for col in wanted:
        if col.unit is None:
            continue
        if col.explicit_factor:
            notes.info(
                f"column '{col.shown}': the mapping's factor {col.factor:g} is used, "
                f"not the header unit '{printable(col.unit, 30)}'"
            )
            continue
        col.factor, col.offset = _unit_conversion(col, spec, shown, line)
        if col.factor != 1.0 or col.offset != 0.0:
            target = spec.unit(col.si_column)
            converted.append(f"'{col.shown}' {printable(col.unit, 30)} -> {target}")
    if converted:
        notes.info("converted to SI: " + ", ".join(converted))


def to_si(table: np.ndarray, wanted: list[Column]) -> None:
    """Scales the columns of `table` (in the order of `wanted`) into SI, in place."""
    for j, col in enumerate(wanted):
        if col.factor != 1.0 or col.offset != 0.0:
            table[:, j] = table[:, j] * col.factor + col.offset


def _hz(f: float) -> str:
    for scale, unit in ((1e6, "MHz"), (1e3, "kHz"), (1.0, "Hz")):
        if f >= scale:
            return f"{f / scale:.3g} {unit}"
    return f"{f:.3g} Hz"


def check_time_scale(table: np.ndarray, wanted: list[Column], notes: Notes) -> None:
    """Warns when a time column without unit (in its header or by a mapping's
    factor) steps like milliseconds or microseconds (a median step of 0.5 or
    more: 2 Hz or slower if seconds). `table` holds the `wanted` columns."""
    names = [c.canonical for c in wanted]
    tcol = wanted[names.index("time")]
    if tcol.unit is not None or tcol.explicit_factor:
        return
    t = table[:, names.index("time")]
    if t.size < 2:
        return
    d = np.diff(t)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return
    med = float(np.median(d))
    if not (np.isfinite(med) and med >= 0.5):
        return
    name = name_unit(tcol.header)[0]
    notes.warn(
        f"time column '{tcol.shown}' has no unit and steps by {med:g} (median): "
        f"{_hz(1.0 / med)} sampling if in seconds, {_hz(1e3 / med)} if milliseconds, "
        f"{_hz(1e6 / med)} if microseconds; if it is not in seconds, write the unit in the "
        f"header ('{printable(name, 40)} [ms]' or '{printable(name, 40)} [us]')"
    )

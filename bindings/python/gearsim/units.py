"""Unit strings ("100 mm", "3000 rpm", "80 degC", "[280, 300, 320] K") to SI
numbers, through pint.

The SI unit of every parameter is declared once, in gearsim.params (the
``unit`` of each parameter spec); this module only converts. Temperatures are
absolute: "80 degC" is 353.15 K, and temperature differences (``delta_degC``)
are refused where an absolute temperature is expected. Plain numbers are SI
and never pass through here. pint is imported on first use only.

One spelling of the Simscape unit lists that pint lacks is defined as an
alias of pint's own unit: ``HP_DIN`` = pint's ``metric_horsepower`` (the
DIN 66036 "PS", 735.49875 W). The Simscape ``delta*`` temperature units are
not accepted: every temperature parameter of gearsim is absolute.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import Any

__all__ = ["registry", "parse_quantity", "to_si"]

# A number, or a bracketed list of numbers, followed by an optional unit.
_NUMBER = r"[-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|nan)"
_SCALAR_RE = re.compile(rf"^\s*({_NUMBER})\s*(.*?)\s*$", re.IGNORECASE)
_LIST_RE = re.compile(r"^\s*\[(.*)\]\s*(.*?)\s*$", re.DOTALL)

_ALIASES = ("HP_DIN = metric_horsepower",)


@lru_cache(maxsize=1)
def registry() -> Any:
    """The package's pint UnitRegistry (created on first use)."""
    import pint

    ureg = pint.UnitRegistry()
    for line in _ALIASES:
        try:
            ureg.define(line)
        except Exception:  # pragma: no cover - a newer pint may define them already
            pass
    return ureg


class UnitConversionError(ValueError):
    """A unit string could not be converted; the caller adds the parameter name."""


def _is_delta_temperature(units: Any) -> bool:
    names = [str(name) for name in getattr(units, "_units", {})]
    return any(name.startswith("delta") for name in names)


def parse_quantity(text: str) -> tuple[float | list[float], str]:
    """Split "100 mm" into (100.0, "mm") and "[1, 2] K" into ([1.0, 2.0], "K")."""
    m = _LIST_RE.match(text)
    if m:
        body, unit = m.group(1), m.group(2)
        items = [item.strip() for item in body.split(",") if item.strip()]
        try:
            values = [float(item) for item in items]
        except ValueError as exc:
            raise UnitConversionError(f"cannot read the list of numbers in {text!r}") from exc
        return values, unit
    m = _SCALAR_RE.match(text)
    if not m:
        raise UnitConversionError(f"cannot read {text!r} as a number with a unit")
    return float(m.group(1)), m.group(2)


def to_si(text: str, unit: str) -> float | list[float]:
    """Convert a unit string to the SI unit ``unit`` (pint syntax, "" for
    dimensionless). Returns a float, or a list of floats for "[...] unit"."""
    value, source = parse_quantity(text)
    ureg = registry()
    target_is_temperature = unit == "K"
    if not source:
        if unit:
            raise UnitConversionError(f"{text!r} has no unit; write a plain number for SI ({unit})")
        return value
    try:
        source_units = ureg.parse_units(source)
        target_units = ureg.parse_units(unit) if unit else ureg.dimensionless
    except Exception as exc:  # pint.UndefinedUnitError and parse errors
        raise UnitConversionError(f"unknown unit {source!r} in {text!r}") from exc
    if target_is_temperature and _is_delta_temperature(source_units):
        raise UnitConversionError(
            f"{text!r} is a temperature difference; an absolute temperature is expected"
        )
    try:
        if isinstance(value, list):
            import numpy as np

            converted = ureg.Quantity(np.asarray(value, dtype=float), source_units).to(target_units)
            return [float(v) for v in converted.magnitude]
        return float(ureg.Quantity(value, source_units).to(target_units).magnitude)
    except Exception as exc:  # pint.DimensionalityError and offset errors
        expected = unit or "dimensionless"
        raise UnitConversionError(f"cannot convert {text!r} to {expected}") from exc

"""The evidence property: every number in an evidence line is a property of
the residual (a field of the evidence), a threshold the evidence names, or a
parameter of the fitted model, and it is physically possible. Shared by the
check_effect suite (test_check_effect.py) and the property test over every
effect on the external corpus and the demo (test_truthcases.py,
test_evidence_property.py).

A number printed in the text matches a value when it equals it, or a
thousandth, a hundredth (a percentage) or a thousand times it (ms from s,
mm from m), or its magnitude, to the precision it is printed with. Whole
numbers up to 100 written without a decimal point are constants of the text
("a step of 2 x", "10 % of the peak load", "1/rev") and are not matched."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

#: a number in a text: not part of a name (pinion_torque2), a unit's power
#: (m/s^2) or a longer number
NUMBER = re.compile(r"(?<![\w.^@])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
SCALES = (1.0, 1e3, 1e2, 1e-3)


def numbers(obj: Any, skip: tuple[str, ...] = ("text", "signature")) -> Iterable[float]:
    """Every finite number in a nested structure of dicts, lists and scalars."""
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            if k not in skip:
                yield from numbers(v, skip)
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from numbers(v, skip)
    elif isinstance(obj, bool) or obj is None:
        return
    elif isinstance(obj, (int, float)):
        if math.isfinite(float(obj)):
            yield float(obj)
    else:
        try:
            import numpy as np

            for v in np.atleast_1d(np.asarray(obj, dtype=float)).ravel()[:64]:
                if math.isfinite(float(v)):
                    yield float(v)
        except (TypeError, ValueError):
            return


def _tolerance(text: str) -> float:
    """Half a unit of the last printed digit."""
    mant, _, exp = text.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (int(exp or 0) - decimals)


def unmatched_numbers(text: str, allowed: Iterable[float]) -> list[str]:
    """The numbers of `text` that match none of `allowed` (see the module
    docstring)."""
    values = [abs(v) * s for v in allowed for s in SCALES]
    out = []
    for m in NUMBER.finditer(text):
        s = m.group(0)
        x = abs(float(s))
        if "." not in s and "e" not in s.lower() and x <= 100:
            continue
        tol = _tolerance(s) + 1e-9 * x
        if not any(abs(v - x) <= tol for v in values):
            out.append(s)
    return out


def _ranges(
    ev: Mapping[str, Any], nyquist_hz: float, path: str = ""
) -> Iterable[tuple[str, float, float, float]]:
    """(key path, value, lower, upper) of every field with a physical range."""
    for key, v in ev.items():
        name = f"{path}.{key}" if path else str(key)
        if isinstance(v, Mapping):
            if "efficiency" in str(key):
                for k2, x in v.items():
                    if isinstance(x, (int, float)) and math.isfinite(x):
                        yield f"{name}.{k2}", float(x), 1e-9, 1.0
            elif "share" in str(key) or "fraction" in str(key):
                for k2, x in v.items():
                    if isinstance(x, (int, float)):
                        yield f"{name}.{k2}", float(x), 0.0, 1.0
            else:
                yield from _ranges(v, nyquist_hz, name)
            continue
        if key == "efficiency_at_temperature":
            for _, eta in v:
                yield name, float(eta), 1e-9, 1.0
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            continue
        k = str(key)
        if "correlation" in k:
            yield name, float(v), -1.0, 1.0
        elif "share" in k or "fraction" in k:
            yield name, float(v), 0.0, 1.0
        elif k == "efficiency" or k.startswith("efficiency_"):
            yield name, float(v), 1e-9, 1.0
        elif k.endswith("_hz"):
            yield name, float(v), 1e-9, nyquist_hz
        elif k in (
            "prominence",
            "concentration",
            "window_ms",
            "reversals",
            "reversal_half_time_s",
            "reversal_peak_time_s",
            "idle_loss",
            "load_slope",
            "profile_excess",
            "gap_estimate_m",
            "fitted_gap_m",
            "temperature_span_K",
        ):
            yield name, float(v), 0.0, math.inf


def assert_evidence_adds_up(
    ev: Mapping[str, Any],
    parameters: Mapping[str, Any],
    dt: float,
    why: str | None = None,
    text: str | None = None,
) -> None:
    """ev: a candidate's evidence; parameters: its fitted parameters (may
    be empty); dt: the record's sample time; text: the line shown (default
    ev["text"]); why: a reason it was not fitted, also shown."""
    line = text if text is not None else str(ev.get("text", ""))
    allowed = list(numbers(ev)) + list(numbers(parameters))
    missing = unmatched_numbers(line, allowed)
    assert not missing, f"numbers {missing} of {line!r} are no evidence field or parameter"
    for name, value, lo, hi in _ranges(ev, 0.5 / dt):
        assert lo <= value <= hi, f"{name} = {value} outside [{lo}, {hi}]: {line!r}"

"""The validate stage: the checks of the numeric table that make a
:class:`Measurement` (finite values of a sane magnitude, enough samples, time
strictly increasing on a uniform grid, or resampled onto one when asked), each
refusal one :class:`MeasurementError` naming the file, line and column."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ..errors import MeasurementError
from ..signals import describe_gap, sampling_gaps
from .record import Measurement, RigSpec

#: Largest magnitude of any value (SI units) the analysis accepts: far beyond
#: any rig (1e12 rad/s, N*m, K, s), and far below what overflows the
#: simulation and the fits (a logging or unit error, not a measurement).
MAX_MAGNITUDE = 1e12
#: Fewest samples a measurement may have.
MIN_SAMPLES = 20


def validate_table(
    table: np.ndarray,
    names: list[str],
    spec: RigSpec,
    path: str,
    *,
    resample: bool,
    max_gap: int | None = None,
    line_of,
    source_names: Mapping[str, str] | None = None,
    shown: str | None = None,
) -> Measurement:
    """Checks the table; `path` goes into the Measurement, `shown` (the
    printable file name, default `path`) into messages."""
    source_names = source_names or {}
    where = shown if shown is not None else path
    n = table.shape[0]
    _check_values(table, names, where, line_of, source_names)
    t = table[:, names.index("time")]
    tname = source_names.get("time", "time")
    if n < MIN_SAMPLES:
        raise MeasurementError(f"has {n} samples; at least {MIN_SAMPLES} are needed", file=where)
    d = _check_increasing(t, where, line_of, tname)
    data = {name: table[:, j].copy() for j, name in enumerate(names)}
    r = _grid_break(t, d)
    notes: list[str]
    if r is None:
        dt, notes = float((t[-1] - t[0]) / (n - 1)), []
    elif not resample:
        raise MeasurementError(
            f"sampling is not uniform: the step before this sample is {d[r - 1]:.6g} s, "
            "the median step "
            f"is {float(np.median(d)):.6g} s (gearsim runs at a fixed step; resample the file "
            "or pass --resample)",
            file=where,
            line=line_of(r),
            column=tname,
        )
    else:
        dt, data, notes = _resample(t, d, data, max_gap, where, line_of, tname)
    time = data.pop("time")
    return Measurement(spec=spec, time=time, dt=dt, data=data, path=path, notes=tuple(notes))


def _check_values(
    table: np.ndarray,
    names: list[str],
    where: str,
    line_of: Callable[[int], int | None],
    source_names: Mapping[str, str],
) -> None:
    """Every value finite and within MAX_MAGNITUDE; the first bad cell named."""

    def refuse_first(bad: np.ndarray, message: Callable[[float], str]) -> None:
        """Raise naming the first cell (in row order) where bad is set."""
        if bad.any():
            bad_rows, bad_cols = np.nonzero(bad)
            r, c = int(bad_rows[0]), int(bad_cols[0])
            raise MeasurementError(
                message(float(table[r, c])),
                file=where,
                line=line_of(r),
                column=source_names.get(names[c], names[c]),
            )

    refuse_first(~np.isfinite(table), lambda v: f"value {v!r} is not finite")
    refuse_first(
        np.abs(table) > MAX_MAGNITUDE,
        lambda v: (
            f"value {v:.6g} is beyond the supported magnitude "
            f"{MAX_MAGNITUDE:g} (SI units): a logging or unit error?"
        ),
    )


def _check_increasing(
    t: np.ndarray, where: str, line_of: Callable[[int], int | None], tname: str
) -> np.ndarray:
    """The steps of `t`, each one positive; the first that is not is named."""
    d = np.diff(t)
    bad = np.nonzero(d <= 0.0)[0]
    if bad.size:
        r = int(bad[0]) + 1
        raise MeasurementError(
            f"time {float(t[r])!r} s is not after the previous sample ({float(t[r - 1])!r} "
            "s); time must increase strictly",
            file=where,
            line=line_of(r),
            column=tname,
        )
    return d


def _grid_break(t: np.ndarray, d: np.ndarray) -> int | None:
    """The sample where `t` leaves a uniform grid (None: it does not): the
    first step more than half the median step off it, else the sample
    farthest from the least-squares grid t_i ~ t0 + i*dt when that is more
    than half a step."""
    n = t.size
    i = np.arange(n, dtype=float)
    dt = float((t[-1] - t[0]) / (n - 1))
    dev = t - (t[0] + i * dt)
    worst = int(np.argmax(np.abs(dev)))
    med = float(np.median(d))
    if abs(dev[worst]) > 0.5 * dt or np.any(np.abs(d - med) > 0.5 * med):
        far = np.nonzero(np.abs(d - med) > 0.5 * med)[0]
        return int(far[0]) + 1 if far.size else worst
    return None


def _resample(
    t: np.ndarray,
    d: np.ndarray,
    data: dict[str, np.ndarray],
    max_gap: int | None,
    where: str,
    line_of: Callable[[int], int | None],
    tname: str,
) -> tuple[float, dict[str, np.ndarray], list[str]]:
    """(dt, data, notes) of the columns interpolated onto a grid of the
    median step; a gap longer than `max_gap` samples is refused."""
    n = t.size
    dt = med = float(np.median(d))
    gaps = sampling_gaps(t, med)
    too_long = [g for g in gaps if max_gap and g.missing > max_gap]
    if too_long:
        g = too_long[0]
        raise MeasurementError(
            f"--resample would interpolate across {describe_gap(g)}, more than "
            f"--max-gap {max_gap} samples; cut the record there, or raise --max-gap "
            "(0: no limit)",
            file=where,
            line=line_of(g.index + 1),
            column=tname,
        )
    notes: list[str] = []
    if gaps:
        more = f" and {len(gaps) - 1} more" if len(gaps) > 1 else ""
        notes.append(f"interpolated across {describe_gap(gaps[0])}{more}")
    m = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    grid = t[0] + np.arange(m) * dt
    data = {
        name: (grid if name == "time" else np.interp(grid, t, col)) for name, col in data.items()
    }
    notes.append(
        f"resampled {n} samples onto a uniform {dt:.6g} s grid ({m} samples, linear interpolation)"
    )
    return dt, data, notes

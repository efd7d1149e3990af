"""Measurement files (docs/measurement-contract.md section 1): load, check, hold.

A measurement is loaded and checked once, at the edge; everything behind
:func:`load_measurement` works on validated, finite, uniformly sampled arrays.

Checks, each reported as a :class:`MeasurementError` naming file, line (1-based,
the header is line 1 unless blank lines precede it) and column:
missing or unreadable file, no header, a required column missing, a cell that is
not a number, NaN or infinity, time not strictly increasing, sampling that is
not uniform (a sample more than half a step away from the uniform grid; pass
``resample=True`` to interpolate onto a uniform grid instead), fewer than 20
samples. Extra columns are ignored and never parsed.

Column mapping: ``columns={"pinion_speed": "omega_rad_s"}`` reads a canonical
column from another header name; ``"name*factor"`` also scales it into SI
(``{"pinion_speed": "omega_rpm*0.10471975512"}``).
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .errors import MeasurementError

__all__ = [
    "RigSpec",
    "RIG_SPECS",
    "OPTIONAL_INPUTS",
    "Measurement",
    "load_measurement",
    "write_measurement",
    "parse_column_map",
]

MIN_SAMPLES = 20


@dataclass(frozen=True)
class RigSpec:
    """The canonical columns of one rig (contract section 1).

    driven_*: names used in texts for the driven side (follower shaft or rack)."""

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
        return {
            "time": "s",
            self.speed_input: self.speed_unit,
            self.load_input: self.load_unit,
            self.torque_output: self.torque_unit,
            self.speed_output: self.driven_speed_unit,
            "temperature": "K",
            "ambient_temperature": "K",
        }.get(column, "")


RIG_SPECS: dict[str, RigSpec] = {
    "simple_gear": RigSpec(
        block="simple_gear",
        speed_input="base_speed",
        load_input="load_torque",
        torque_output="base_torque",
        speed_output="follower_speed",
        speed_unit="rad/s",
        load_unit="N*m",
        torque_unit="N*m",
        driven_speed_unit="rad/s",
        driven_force_unit="N*m",
        driven_name="follower",
    ),
    "rack_pinion": RigSpec(
        block="rack_pinion",
        speed_input="pinion_speed",
        load_input="load_force",
        torque_output="pinion_torque",
        speed_output="rack_velocity",
        speed_unit="rad/s",
        load_unit="N",
        torque_unit="N*m",
        driven_speed_unit="m/s",
        driven_force_unit="N",
        driven_name="rack",
    ),
}

OPTIONAL_INPUTS: tuple[str, ...] = ("temperature", "ambient_temperature")


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
        """Sub-measurement of samples [start:stop:step] (dt scales with step)."""
        sl = slice(start, stop, step)
        return replace(
            self,
            time=self.time[sl],
            dt=self.dt * step,
            data={k: v[sl] for k, v in self.data.items()},
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
        spec = _spec(block)
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
        return _validate(table, names, spec, path, resample=False, line_of=lambda i: None)


def _spec(block: str) -> RigSpec:
    try:
        return RIG_SPECS[block]
    except KeyError:
        raise MeasurementError(
            f"unknown rig block '{block}' (expected one of {', '.join(RIG_SPECS)})"
        ) from None


def parse_column_map(items: list[str] | None) -> dict[str, str]:
    """['canonical=source[*factor]', ...] -> {canonical: 'source[*factor]'}."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise MeasurementError(f"column mapping '{item}' is not CANONICAL=SOURCE[*FACTOR]")
        out[key.strip()] = value.strip()
    return out


def _split_source(source: str, canonical: str) -> tuple[str, float]:
    name, star, factor = source.partition("*")
    if not star:
        return name.strip(), 1.0
    try:
        k = float(factor)
    except ValueError:
        raise MeasurementError(
            f"scale factor '{factor}' of the mapping for '{canonical}' is not a number",
            column=canonical,
        ) from None
    if not np.isfinite(k) or k == 0.0:
        raise MeasurementError(
            f"scale factor '{factor}' of the mapping for '{canonical}' must be finite and non-zero",
            column=canonical,
        )
    return name.strip(), k


def load_measurement(
    path: str | os.PathLike[str],
    block: str,
    *,
    columns: Mapping[str, str] | None = None,
    resample: bool = False,
) -> Measurement:
    """Read and check a measurement CSV for the rig of `block`
    ("simple_gear" or "rack_pinion"). See the module docstring."""
    spec = _spec(block)
    path_s = os.fspath(path)
    columns = dict(columns or {})
    for key in columns:
        if key not in spec.required + OPTIONAL_INPUTS:
            raise MeasurementError(
                f"column mapping names '{key}', which is not a column of the {block} rig "
                f"({', '.join(spec.required + OPTIONAL_INPUTS)})",
                file=path_s,
            )
    try:
        fh = open(path_s, "rb")
    except FileNotFoundError:
        raise MeasurementError("no such file", file=path_s) from None
    except IsADirectoryError:
        raise MeasurementError("is a directory, not a CSV file", file=path_s) from None
    except OSError as exc:
        raise MeasurementError(f"cannot read ({exc.strerror})", file=path_s) from None
    with fh:
        header_line = 0
        while True:
            raw = fh.readline()
            if not raw:
                raise MeasurementError("is empty (no header row)", file=path_s)
            header_line += 1
            if raw.strip():
                break
    line = _decode(raw).rstrip("\r\n")
    header = [
        h.strip().strip('"').strip("'").strip() for h in next(csv.reader([line.rstrip("\r")]))
    ]
    seen: dict[str, int] = {}
    for i, h in enumerate(header):
        if h in seen and h:
            if h in spec.required + OPTIONAL_INPUTS or h in {
                _split_source(v, k)[0] for k, v in columns.items()
            }:
                raise MeasurementError(
                    f"header names column '{h}' twice (columns {seen[h] + 1} and {i + 1})",
                    file=path_s,
                    line=header_line,
                    column=h,
                )
        seen.setdefault(h, i)

    wanted: list[tuple[str, int, float, str]] = []  # canonical, index, factor, source name
    for canonical in spec.required + OPTIONAL_INPUTS:
        source, factor = _split_source(columns.get(canonical, canonical), canonical)
        if source in seen:
            wanted.append((canonical, seen[source], factor, source))
        elif canonical in spec.required:
            mapped = f" (mapped from '{source}')" if source != canonical else ""
            have = ", ".join(h for h in header if h) or "none"
            raise MeasurementError(
                f"missing column{mapped}; the {block} rig needs {', '.join(spec.required)}; "
                f"the header has {have}",
                file=path_s,
                line=header_line,
                column=source,
            )
        elif canonical in columns:
            raise MeasurementError(
                f"mapped column '{source}' is not in the header",
                file=path_s,
                line=header_line,
                column=source,
            )

    usecols = [w[1] for w in wanted]
    names = [w[0] for w in wanted]
    table = _read_numeric_fast(path_s, usecols, header_line)
    try:
        if table is None:
            table = np.loadtxt(
                path_s,
                delimiter=",",
                usecols=usecols,
                ndmin=2,
                skiprows=header_line,
                comments=None,
                dtype=float,
                encoding="latin-1",
            )
    except (ValueError, IndexError):
        body = _read_body(path_s, header_line)
        _locate_parse_error(body, header_line, wanted, len(header), path_s)
        raise MeasurementError("cannot be parsed as CSV", file=path_s) from None
    if table.shape[0] == 0:
        raise MeasurementError("has a header but no data rows", file=path_s, line=header_line + 1)
    for j, (_c, _i, factor, _s) in enumerate(wanted):
        if factor != 1.0:
            table[:, j] *= factor

    line_cache: dict[str, list[int]] = {}

    def line_of(row: int) -> int:
        if "lines" not in line_cache:
            lines = []
            for k, ln in enumerate(_read_body(path_s, header_line).split("\n")):
                if ln.strip():
                    lines.append(header_line + 1 + k)
            line_cache["lines"] = lines
        lines = line_cache["lines"]
        return lines[row] if 0 <= row < len(lines) else header_line + 1 + row

    source_names = {w[0]: w[3] for w in wanted}
    return _validate(
        table, names, spec, path_s, resample=resample, line_of=line_of, source_names=source_names
    )


def _read_numeric_fast(path: str, usecols: list[int], header_line: int) -> np.ndarray | None:
    """The numeric table by pandas' C parser (about 3x faster than np.loadtxt on a
    million rows), or None when pandas is missing or the file is not plain
    numbers (empty cells, text, nan/inf): the np.loadtxt path then parses it
    and locates any bad cell."""
    try:
        import pandas as pd
    except ImportError:
        return None
    try:
        frame = pd.read_csv(
            path,
            header=None,
            skiprows=header_line,
            usecols=usecols,
            dtype=float,
            na_filter=False,
            engine="c",
            encoding="latin-1",
        )
    except (ValueError, TypeError, IndexError, pd.errors.ParserError, pd.errors.EmptyDataError):
        return None
    # pandas orders usecols by position; the callers expect the given order
    return frame[sorted(usecols)].to_numpy()[:, [sorted(usecols).index(c) for c in usecols]]


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _read_body(path: str, header_line: int) -> str:
    """The file's text after the header line (for locating errors only)."""
    with open(path, "rb") as fh:
        for _ in range(header_line):
            fh.readline()
        return _decode(fh.read())


def _locate_parse_error(body: str, header_line: int, wanted, ncols: int, path: str) -> None:
    """Find the first bad cell after the fast parser refused the file; raises."""
    need = max(w[1] for w in wanted)
    reader = csv.reader(io.StringIO(body))
    for row in reader:
        line = header_line + reader.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) <= need:
            missing = [w for w in wanted if w[1] >= len(row)]
            raise MeasurementError(
                f"row has {len(row)} fields, the header has {ncols}; no value for this column",
                file=path,
                line=line,
                column=missing[0][3],
            )
        for _canonical, idx, _f, source in wanted:
            cell = row[idx].strip()
            try:
                float(cell)
            except ValueError:
                shown = cell if len(cell) <= 30 else cell[:27] + "..."
                what = "is empty" if not cell else f"'{shown}' is not a number"
                raise MeasurementError(what, file=path, line=line, column=source) from None


def _validate(
    table: np.ndarray,
    names: list[str],
    spec: RigSpec,
    path: str,
    *,
    resample: bool,
    line_of,
    source_names: Mapping[str, str] | None = None,
) -> Measurement:
    source_names = source_names or {}
    n = table.shape[0]
    finite = np.isfinite(table)
    if not finite.all():
        bad_rows, bad_cols = np.nonzero(~finite)
        r, c = int(bad_rows[0]), int(bad_cols[0])
        raise MeasurementError(
            f"value {float(table[r, c])!r} is not finite",
            file=path,
            line=line_of(r),
            column=source_names.get(names[c], names[c]),
        )
    t = table[:, names.index("time")]
    tname = source_names.get("time", "time")
    if n < MIN_SAMPLES:
        raise MeasurementError(f"has {n} samples; at least {MIN_SAMPLES} are needed", file=path)
    d = np.diff(t)
    bad = np.nonzero(d <= 0.0)[0]
    if bad.size:
        r = int(bad[0]) + 1
        raise MeasurementError(
            f"time {float(t[r])!r} s is not after the previous sample ({float(t[r - 1])!r} "
            "s); time must increase strictly",
            file=path,
            line=line_of(r),
            column=tname,
        )
    # uniform grid by least squares: t_i ~ t0 + i*dt
    i = np.arange(n, dtype=float)
    dt = float((t[-1] - t[0]) / (n - 1))
    dev = t - (t[0] + i * dt)
    notes: list[str] = []
    worst = int(np.argmax(np.abs(dev)))
    data = {name: table[:, j].copy() for j, name in enumerate(names)}
    med = float(np.median(d))
    if abs(dev[worst]) > 0.5 * dt or np.any(np.abs(d - med) > 0.5 * med):
        if not resample:
            # name the first interval that breaks the grid
            far = np.nonzero(np.abs(d - med) > 0.5 * med)[0]
            r = int(far[0]) + 1 if far.size else worst
            raise MeasurementError(
                f"sampling is not uniform: the step before this sample is {d[r - 1]:.6g} s, "
                "the median step "
                f"is {med:.6g} s (gearsim runs at a fixed step; resample the file or pass "
                "--resample)",
                file=path,
                line=line_of(r),
                column=tname,
            )
        dt = med
        m = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
        grid = t[0] + np.arange(m) * dt
        data = {
            name: (grid if name == "time" else np.interp(grid, t, col))
            for name, col in data.items()
        }
        notes.append(
            f"resampled {n} samples onto a uniform {dt:.6g} s grid ({m} samples, linear "
            "interpolation)"
        )
        t = grid
    time = data.pop("time")
    return Measurement(spec=spec, time=time, dt=dt, data=data, path=path, notes=tuple(notes))


def write_measurement(path: str | os.PathLike[str], meas: Measurement, *, digits: int = 9) -> None:
    """Write a measurement as a canonical CSV (header row, %.{digits}g values)."""
    names = [*meas.spec.required, *(c for c in OPTIONAL_INPUTS if c in meas.data)]
    cols = [meas.time] + [meas.data[c] for c in names[1:]]
    arr = np.column_stack(cols)
    fmt = f"%.{digits}g"
    tmp = os.fspath(path) + ".tmp"
    with open(tmp, "w", newline="\n") as fh:
        fh.write(",".join(names) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt=fmt)
    os.replace(tmp, path)

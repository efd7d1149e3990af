"""Recording to measurement: a CAN log of a rig's commands and feedback as the
canonical CSV of docs/measurement-format.md section 1, so that
``gearsim compare|diagnose|fit`` can judge a model against a recording.

Columns: ``time, base_speed, load_torque, base_torque, follower_speed`` (gear
rig) or ``time, pinion_speed, load_force, pinion_torque, rack_velocity`` (rack
rig), plus ``temperature`` on request, as :mod:`gearsim.columns` defines them.
Where each comes from (DBC roles, derived from the rig signal of each column):

- outputs: ``out.base_torque`` and ``out.follower_speed`` (feedback);
- speed input: the measured ``out.base_speed`` (feedback) or the command
  ``cmd.base_speed``; load input: the applied ``in.load`` (feedback) or the
  command ``cmd.load``. ``source="auto"`` takes the feedback signal when the
  DBC has one: inputs and outputs then come from the same frame period. A
  command with mode Disabled counts as speed 0 and load 0; command timeouts are
  not reconstructed (prefer feedback sources);
- ``temperature`` (optional): ``out.temperature``, the measured temperature.

Resampling: a uniform grid of step ``dt`` (default: the longest cycle time of
the frames used) starting when every column has had a value and ending at the
earliest last value; the value at grid time t is the last one received at or
before t + dt/2 (hold-last; the half step absorbs the jitter between frames of
the same cycle). ``time`` is seconds since the log's first frame.

Bounds: memory follows the log's real length, never its time span. Time may
not jump between two consecutive frames by more than ``max_gap`` seconds
(default 60 s: a log mixing absolute and relative timestamps is refused,
naming the frame), and the grid may not hold more than ``max_samples`` samples
(default 5 000 000); both are refused with a :class:`RecordingError` before
anything is allocated from the time span. :func:`write_csv` writes atomically.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, TextIO

import can
import numpy as np

from .._outputs import atomic_writer, printable
from ..columns import RIGS, TEMPERATURE, Column
from ..errors import InputError
from .codec import Rejection, RigDbc
from .replay import DEFAULT_MAX_GAP, TimeCheck, read_log

__all__ = [
    "Recording",
    "log_to_measurement",
    "write_csv",
    "COLUMNS",
    "RecordingError",
    "DEFAULT_MAX_SAMPLES",
]

#: Largest number of grid samples log_to_measurement makes by default (``--max-samples``).
DEFAULT_MAX_SAMPLES = 5_000_000

#: Canonical columns per rig: (speed input, load input, torque output, speed output),
#: from gearsim.columns (the one definition, which the analysis reads with).
COLUMNS: dict[str, tuple[str, str, str, str]] = {block: rig.names for block, rig in RIGS.items()}


def _feedback_role(col: Column) -> str:
    """The DBC role of the feedback signal carrying ``col``: the rig output that
    holds it, else the rig input as the bridge applied it."""
    return f"out.{col.rig_output}" if col.rig_output else f"in.{col.rig_input}"


def _command_role(col: Column) -> str:
    """The DBC role of the command signal that sets input column ``col``."""
    return f"cmd.{col.rig_input}"


class RecordingError(InputError):
    """The log cannot be turned into a measurement (no frames of a needed
    signal, too short, too long a grid, ...). A ValueError; bad input: exit
    status 2."""


@dataclass
class Recording:
    """A measurement built from a log: canonical columns, and how."""

    block: str
    columns: dict[str, np.ndarray]
    dt: float
    sources: dict[str, str]
    """column -> "<frame>.<signal>" it was taken from"""
    frames: int = 0
    used: int = 0
    rejected: int = 0
    notes: list[str] = field(default_factory=list)

    @property
    def rows(self) -> int:
        return len(self.columns["time"])

    def info(self) -> dict[str, Any]:
        return {
            "block": self.block,
            "rows": self.rows,
            "dt": self.dt,
            "columns": list(self.columns),
            "sources": self.sources,
            "frames": self.frames,
            "frames_used": self.used,
            "frames_rejected": self.rejected,
        }


def _pick(dbc: RigDbc, col: Column, source: str) -> str:
    options = {"feedback": _feedback_role(col), "command": _command_role(col)}
    if source == "auto":
        fb = options["feedback"]
        return fb if dbc.feedback_signals(fb) else options["command"]
    if source not in options:
        raise RecordingError(
            f"unknown source {printable(repr(source))}; expected auto, feedback or command"
        )
    return options[source]


def _describe(dbc: RigDbc, role: str) -> str:
    if role.startswith("cmd."):
        if role not in dbc.command_signals:
            raise RecordingError(
                f"{printable(str(dbc.path))}: no command signal with GsRole {role!r}"
            )
        f, s = dbc.command_signals[role]
        return f"{f.name}.{s.name}"
    found = dbc.feedback_signals(role)
    if not found:
        raise RecordingError(f"{printable(str(dbc.path))}: no feedback signal with GsRole {role!r}")
    f, s = found[0]
    return f"{f.name}.{s.name}"


def log_to_measurement(
    messages: Iterable[can.Message] | str | PathLike[str],
    dbc: RigDbc,
    *,
    dt: float | None = None,
    source: str = "auto",
    temperature: bool = False,
    max_gap: float | None = DEFAULT_MAX_GAP,
    max_samples: int = DEFAULT_MAX_SAMPLES,
) -> Recording:
    """Build the canonical measurement of ``dbc.block`` from a log file (or an
    iterable of messages). See the module docstring for the rules.

    Raises RecordingError when a needed signal never appears, the DBC does not
    say which rig it is for, fewer than 2 grid points result, or more than
    ``max_samples``; a LogError (also a ValueError) when the log cannot be
    read, holds a non-finite timestamp or jumps in time by more than
    ``max_gap`` seconds (None: no limit) between two consecutive frames."""
    if isinstance(max_samples, bool) or not isinstance(max_samples, int) or max_samples < 2:
        raise RecordingError(f"max_samples must be an integer >= 2, got {max_samples!r}")
    if dt is not None and not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise RecordingError(f"dt must be a time > 0 s, got {dt!r}")
    if dbc.block is None:
        raise RecordingError(
            f"{printable(str(dbc.path))} does not name its rig (GsBlock); give the rig"
        )
    rig = RIGS[dbc.block]
    roles = {col.name: _pick(dbc, col, source) for col in rig.inputs}
    roles.update({col.name: _feedback_role(col) for col in rig.outputs})
    if temperature:
        roles[TEMPERATURE.name] = _feedback_role(TEMPERATURE)
    sources = {col: _describe(dbc, role) for col, role in roles.items()}

    name = "the log"
    check = TimeCheck(max_gap, name)
    if isinstance(messages, (str, PathLike)):
        reader = read_log(messages)
        check.name = name = reader.name
        try:
            return _measure(reader, dbc, roles, sources, check, dt, max_samples, name)
        finally:
            reader.stop()
    return _measure(messages, dbc, roles, sources, check, dt, max_samples, name)


def _measure(
    messages: Iterable[can.Message],
    dbc: RigDbc,
    roles: dict[str, str],
    sources: dict[str, str],
    check: TimeCheck,
    dt: float | None,
    max_samples: int,
    name: str,
) -> Recording:
    assert dbc.block is not None
    torque_output = RIGS[dbc.block].torque_output.name
    wanted = set(roles.values())
    series: dict[str, tuple[list[float], list[float]]] = {r: ([], []) for r in wanted}
    rec = Recording(dbc.block, {}, 0.0, sources)
    t0: float | None = None
    for msg in messages:
        t = check(msg.timestamp)
        rec.frames += 1
        if t0 is None:
            t0 = t
        if msg.is_error_frame or msg.is_remote_frame:
            continue
        key = (msg.arbitration_id, bool(msg.is_extended_id))
        frame = dbc.by_key.get(key)
        if frame is None:
            continue
        if frame.kind == "command":
            values = dbc.decode_command(frame, msg.data)
            if isinstance(values, Rejection):
                rec.rejected += 1
                continue
            if values.get("cmd.mode") == "disabled":
                values = {r: (0.0 if r != "cmd.mode" else "disabled") for r in values}
        elif frame.kind == "feedback":
            values = dbc.decode_feedback(frame, msg.data)
            if values is None:
                rec.rejected += 1
                continue
        else:
            continue
        hit = False
        for role, v in values.items():
            if role in wanted:
                ts, vs = series[role]
                ts.append(t)
                vs.append(float(v))
                hit = True
        rec.used += hit
    if t0 is None:
        raise RecordingError(f"{name}: the log holds no frames")
    missing = [f"{col} ({sources[col]})" for col, role in roles.items() if not series[role][0]]
    if missing:
        raise RecordingError(f"{name}: no frames for " + ", ".join(missing))

    if dt is None:
        cycles = []
        for role in wanted:
            if role.startswith("cmd."):
                cycles.append(dbc.command_signals[role][0].cycle_time)
            else:
                cycles.extend(f.cycle_time for f, _ in dbc.feedback_signals(role))
        cycles = [c for c in cycles if c]
        if cycles:
            dt = max(cycles)
        else:
            ts = np.asarray(series[roles[torque_output]][0])
            dt = float(np.median(np.diff(ts))) if len(ts) > 1 else 0.0
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise RecordingError(f"{name}: cannot infer a grid step (dt = {dt!r}); give --dt")
    dt = float(dt)

    arrays: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for role, (ts, vs) in series.items():
        t_arr = np.asarray(ts, dtype=np.float64)
        v_arr = np.asarray(vs, dtype=np.float64)
        if np.any(np.diff(t_arr) < 0):
            order = np.argsort(t_arr, kind="stable")
            t_arr, v_arr = t_arr[order], v_arr[order]
            rec.notes.append(f"{role}: frames out of time order, sorted")
        arrays[role] = (t_arr, v_arr)
    start = float(max(a[0][0] for a in arrays.values()))
    end = float(min(a[0][-1] for a in arrays.values()))
    # the sample count is checked as a float before anything is allocated
    ratio = (end - start) / dt + 1e-9
    if end < start:
        samples = 0.0
    elif math.isfinite(ratio):
        samples = math.floor(ratio) + 1.0
    else:
        samples = math.inf
    if not samples <= max_samples:
        raise RecordingError(
            f"{name}: {end - start:.6g} s of signals at dt = {dt:g} s would make {samples:.6g} "
            f"samples, more than the limit of {max_samples} (--max-samples); "
            "raise --dt or --max-samples"
        )
    n = int(samples)
    if n < 2:
        raise RecordingError(
            f"{name}: the signals overlap for {max(0.0, end - start):.6g} s only: "
            f"fewer than 2 samples at dt = {dt:g} s"
        )
    grid = start + dt * np.arange(n)
    cols: dict[str, np.ndarray] = {"time": np.round(grid - t0, 9)}
    for col, role in roles.items():
        t_arr, v_arr = arrays[role]
        idx = np.searchsorted(t_arr, grid + 0.5 * dt, side="right") - 1
        cols[col] = v_arr[idx]
    rec.columns = cols
    rec.dt = dt
    return rec


def write_csv(path: str | PathLike[str] | TextIO, columns: dict[str, np.ndarray]) -> None:
    """Write columns as CSV (to a path or an open text stream): one header
    row, one row per sample, shortest round-trip float text. A path is
    written atomically (a temporary file renamed over it when complete)."""
    if not isinstance(path, (str, PathLike)):
        _write_rows(path, columns)
        return
    # a temporary file beside the target, renamed over it once complete
    with atomic_writer(os.fspath(path), "w", encoding="utf-8", newline="") as fh:
        _write_rows(fh, columns)


def _write_rows(fh: TextIO, columns: dict[str, np.ndarray]) -> None:
    names = list(columns)
    fh.write(",".join(names) + "\n")
    for row in zip(*(columns[n].tolist() for n in names), strict=True):
        fh.write(",".join(repr(float(v)) for v in row) + "\n")

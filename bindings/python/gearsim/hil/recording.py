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

Time base. A recording made by the bridge (``gearsim hil run --log``,
``replay``, or any log whose frames all lie on the bridge's period grid) is
in *rig time*: each command is stamped at the start of the period that applied
it, each feedback frame at the end of the period it answers. Such a log is
converted exactly: one row per instant at which the outputs were sent
(every feedback cycle, 10 ms with the shipped DBCs), the inputs as the rig
applied them during the interval that ends at the row (zero-order hold), an
``inputs_since`` column: the time from which the row's inputs were applied,
and per input a ``<input>_before`` column: the value the rig applied before
that time (the command in effect then; 0 before the first command). A first line
``# gearsim hil to-csv: time_base=rig rig_dt=H held=COLUMNS`` tells the
analysis that the rig was stepped every H seconds with those inputs held,
so that it can step the model the same way and compare at the rows.

Any other log (stamped with a wall clock, e.g. by a test host, or converted
with an explicit ``dt``) is resampled: a uniform grid of step ``dt`` (default:
the longest cycle time of the frames used) starting when every column has had
a value and ending at the earliest last value; the value at grid time t is the
last one received at or before t + dt/2 (hold-last; the half step absorbs the
jitter between frames of the same cycle). Its first line says
``time_base=wall``, and :attr:`Recording.notes` says why such a CSV cannot
reproduce the run step for step. ``time`` is seconds since the log's first
frame in both cases.

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
from ..columns import BEFORE_SUFFIX, INPUTS_SINCE, RIG_TIME_MARKER, RIGS, TEMPERATURE, Column
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
    "INPUTS_SINCE",
    "BEFORE_SUFFIX",
    "MARKER",
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


MARKER = RIG_TIME_MARKER
#: Frame times this close (s) to the period grid count as on it: the rounding
#: of log formats (microseconds in text logs) and of epoch timestamps in doubles.
_GRID_SLACK = 2e-6


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
    time_base: str = "wall"
    """"rig": rows at the output frames' instants of a log on the bridge's
    period grid, inputs as applied; "wall": resampled (see the module doc)"""
    rig_dt: float | None = None
    """rig step (s) the inputs were held at (time base "rig")"""
    held: tuple[str, ...] = ()
    """input columns held over each row interval (time base "rig")"""

    @property
    def rows(self) -> int:
        return len(self.columns["time"])

    def marker(self) -> str:
        """The CSV's first line: how the rows were made (read by the analysis)."""
        if self.time_base != "rig":
            return f"{MARKER} time_base=wall"
        return f"{MARKER} time_base=rig rig_dt={self.rig_dt!r} held={','.join(self.held)}"

    def info(self) -> dict[str, Any]:
        return {
            "block": self.block,
            "rows": self.rows,
            "dt": self.dt,
            "time_base": self.time_base,
            "rig_dt": self.rig_dt,
            "held": list(self.held),
            "columns": list(self.columns),
            "sources": self.sources,
            "frames": self.frames,
            "frames_used": self.used,
            "frames_rejected": self.rejected,
            "notes": list(self.notes),
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
    period: float = 1e-3,
    substeps: int = 1,
) -> Recording:
    """Build the canonical measurement of ``dbc.block`` from a log file (or an
    iterable of messages). See the module docstring for the rules.

    ``period`` and ``substeps`` are those of the bridge session that made the
    log (``gearsim hil run --period --substeps``; defaults 1 ms and 1): a log on
    that period grid is converted in rig time, with ``rig_dt = period / substeps``.

    Raises RecordingError when a needed signal never appears, the DBC does not
    say which rig it is for, fewer than 2 grid points result, or more than
    ``max_samples``; a LogError (also a ValueError) when the log cannot be
    read, holds a non-finite timestamp or jumps in time by more than
    ``max_gap`` seconds (None: no limit) between two consecutive frames."""
    if isinstance(max_samples, bool) or not isinstance(max_samples, int) or max_samples < 2:
        raise RecordingError(f"max_samples must be an integer >= 2, got {max_samples!r}")
    for name, value in (("dt", dt), ("period", period)):
        if value is not None and not (
            isinstance(value, (int, float)) and math.isfinite(value) and value > 0
        ):
            raise RecordingError(f"{name} must be a time > 0 s, got {value!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
        raise RecordingError(f"substeps must be an integer >= 1, got {substeps!r}")
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
    timing = _Timing(dt, float(period), substeps, max_samples)

    name = "the log"
    check = TimeCheck(max_gap, name)
    if isinstance(messages, (str, PathLike)):
        reader = read_log(messages)
        check.name = name = reader.name
        try:
            return _measure(reader, dbc, roles, sources, check, timing, name)
        finally:
            reader.stop()
    return _measure(messages, dbc, roles, sources, check, timing, name)


@dataclass(frozen=True)
class _Timing:
    dt: float | None
    period: float
    substeps: int
    max_samples: int


@dataclass
class _Series:
    """What a log holds for the measurement: per role, the (times, values) of
    the frames that carried it; the times of the valid commands; all frame times."""

    roles: dict[str, tuple[list[float], list[float]]]
    commands: list[float] = field(default_factory=list)
    command_values: list[dict[str, Any]] = field(default_factory=list)
    """the decoded values of each valid command (Disabled: zeros)"""
    times: list[float] = field(default_factory=list)


def _measure(
    messages: Iterable[can.Message],
    dbc: RigDbc,
    roles: dict[str, str],
    sources: dict[str, str],
    check: TimeCheck,
    timing: _Timing,
    name: str,
) -> Recording:
    assert dbc.block is not None
    torque_output = RIGS[dbc.block].torque_output.name
    rec = Recording(dbc.block, {}, 0.0, sources)
    series = _read_series(messages, dbc, set(roles.values()), check, rec)
    if not series.times:
        raise RecordingError(f"{name}: the log holds no frames")
    missing = [
        f"{col} ({sources[col]})" for col, role in roles.items() if not series.roles[role][0]
    ]
    if missing:
        raise RecordingError(f"{name}: no frames for " + ", ".join(missing))
    t0 = series.times[0]
    cycle = _default_step(dbc, roles, series)
    dt = cycle if timing.dt is None else float(timing.dt)
    if not (math.isfinite(dt) and dt > 0):
        raise RecordingError(f"{name}: cannot infer a grid step (dt = {dt!r}); give --dt")
    # times relative to the first frame: a grid built on epoch seconds would
    # carry their rounding (0.24 us at 1.7e9 s) into every row
    arrays = {r: (t - t0, v) for r, (t, v) in _sorted_arrays(series, rec).items()}
    rig_time = _on_period_grid(series.times, t0, timing.period)
    if rig_time and (timing.dt is None or math.isclose(dt, cycle, rel_tol=1e-9)):
        rec.time_base = "rig"
        rec.rig_dt = timing.period / timing.substeps
        rec.held = tuple(RIGS[dbc.block].names[:2])
    elif rig_time:
        rec.notes.append(
            f"--dt {dt:g} s is not the feedback cycle ({cycle:g} s): the rows are resampled "
            "and cannot reproduce the run step for step; leave --dt out for an exact CSV"
        )
    else:
        rec.notes.append(
            f"{name}: the frames are not on a {timing.period:g} s period grid (a wall-clock "
            "log, or another --period): the rows are resampled and the model cannot "
            "reproduce the run step for step; record with 'gearsim hil run --log' (rig time) "
            "and give to-csv the run's --period and --substeps"
        )
    if rec.time_base == "rig":
        # a command stamped t acts from the period starting at t: it is what the
        # rig applied in a period that ends at t + period or later
        arrays = {
            role: (t_arr + timing.period, v) if role.startswith("cmd.") else (t_arr, v)
            for role, (t_arr, v) in arrays.items()
        }
    # rig time: the rows are the instants at which the torque output was sent
    anchor = float(arrays[roles[torque_output]][0][0]) if rec.time_base == "rig" else None
    # commands hold until the next one: they do not end the grid
    ends = [a[0][-1] for r, a in arrays.items() if not r.startswith("cmd.")]
    grid = _grid(arrays, dt, timing.max_samples, name, anchor, float(min(ends)) if ends else None)
    slack = _GRID_SLACK if rec.time_base == "rig" else 0.5 * dt
    cols: dict[str, np.ndarray] = {"time": np.round(grid, 9)}
    for col, role in roles.items():
        t_arr, v_arr = arrays[role]
        cols[col] = v_arr[np.searchsorted(t_arr, grid + slack, side="right") - 1]
    if rec.time_base == "rig":
        commands = np.asarray(series.commands, dtype=np.float64) - t0
        since = _inputs_since(commands, grid, dt, timing.period)
        cols[INPUTS_SINCE] = np.round(since, 9)
        for col in RIGS[dbc.block].inputs:
            applied = _applied_before(commands, series.command_values, _command_role(col), since)
            cols[col.name + BEFORE_SUFFIX] = applied
    rec.columns = cols
    rec.dt = dt
    return rec


def _read_series(
    messages: Iterable[can.Message],
    dbc: RigDbc,
    wanted: set[str],
    check: TimeCheck,
    rec: Recording,
) -> _Series:
    """Decode every frame of the DBC; keep the values of the wanted roles."""
    series = _Series({r: ([], []) for r in wanted})
    for msg in messages:
        t = check(msg.timestamp)
        rec.frames += 1
        series.times.append(t)
        if msg.is_error_frame or msg.is_remote_frame:
            continue
        frame = dbc.by_key.get((msg.arbitration_id, bool(msg.is_extended_id)))
        if frame is None:
            continue
        if frame.kind == "command":
            values = dbc.decode_command(frame, msg.data)
            if isinstance(values, Rejection):
                rec.rejected += 1
                continue
            if values.get("cmd.mode") == "disabled":
                values = {r: (0.0 if r != "cmd.mode" else "disabled") for r in values}
            series.commands.append(t)
            series.command_values.append(values)
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
                ts, vs = series.roles[role]
                ts.append(t)
                vs.append(float(v))
                hit = True
        rec.used += hit
    return series


def _default_step(dbc: RigDbc, roles: dict[str, str], series: _Series) -> float:
    """The longest cycle time of the frames used; without cycle times, the
    median interval of the torque output's frames."""
    cycles = []
    for role in set(roles.values()):
        if role.startswith("cmd."):
            cycles.append(dbc.command_signals[role][0].cycle_time)
        else:
            cycles.extend(f.cycle_time for f, _ in dbc.feedback_signals(role))
    cycles = [c for c in cycles if c]
    if cycles:
        return float(max(cycles))
    assert dbc.block is not None
    ts = np.asarray(series.roles[roles[RIGS[dbc.block].torque_output.name]][0])
    return float(np.median(np.diff(ts))) if len(ts) > 1 else 0.0


def _sorted_arrays(series: _Series, rec: Recording) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    arrays: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for role, (ts, vs) in series.roles.items():
        t_arr = np.asarray(ts, dtype=np.float64)
        v_arr = np.asarray(vs, dtype=np.float64)
        if np.any(np.diff(t_arr) < 0):
            order = np.argsort(t_arr, kind="stable")
            t_arr, v_arr = t_arr[order], v_arr[order]
            rec.notes.append(f"{role}: frames out of time order, sorted")
        arrays[role] = (t_arr, v_arr)
    return arrays


def _on_period_grid(times: list[float], t0: float, period: float) -> bool:
    """True when every frame lies on the period grid through the first frame:
    a log stamped in rig time (the bridge's own recording or a replay)."""
    offsets = (np.asarray(times, dtype=np.float64) - t0) / period
    slack = _GRID_SLACK / period
    return bool(np.all(np.abs(offsets - np.rint(offsets)) <= slack))


def _grid(
    arrays: dict[str, tuple[np.ndarray, np.ndarray]],
    dt: float,
    max_samples: int,
    name: str,
    anchor: float | None = None,
    end: float | None = None,
) -> np.ndarray:
    """The uniform grid from the first instant at which every column has a
    value (moved onto the grid through ``anchor`` when given) to ``end`` (by
    default the earliest last value); its size is checked before allocating."""
    start = float(max(a[0][0] for a in arrays.values()))
    if anchor is not None:
        start = anchor + math.ceil((start - anchor) / dt - _GRID_SLACK / dt) * dt
    if end is None:
        end = float(min(a[0][-1] for a in arrays.values()))
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
    return start + dt * np.arange(n)


def _applied_before(
    commands: np.ndarray, values: list[dict[str, Any]], role: str, since: np.ndarray
) -> np.ndarray:
    """Per row, the value of command role ``role`` the rig applied just before
    ``since``: that of the last command stamped earlier (a command acts from
    its stamp on); 0 before the first command (the bridge's safe state) and
    for a role no command carries (the bridge applies 0 then)."""
    carried, last = [], 0.0
    for v in values:  # commands in file order; a frame without the role keeps it
        last = float(v.get(role, last))
        carried.append(last)
    if not carried:
        return np.zeros(len(since))
    order = np.argsort(commands, kind="stable")
    times, held = commands[order], np.asarray(carried)[order]
    idx = np.searchsorted(times, since - _GRID_SLACK, side="left") - 1
    return np.where(idx >= 0, held[np.maximum(idx, 0)], 0.0)


def _inputs_since(commands: np.ndarray, grid: np.ndarray, dt: float, period: float) -> np.ndarray:
    """Per row, the time from which its inputs were applied: the last command
    applied within the row's interval (from the previous row's time to the
    start of the row's last period), else the previous row's time (the inputs
    were held over the whole interval)."""
    lower = grid - dt
    upper = grid - period
    since = lower.copy()
    if len(commands):
        commands = np.sort(commands)
        idx = np.searchsorted(commands, upper + _GRID_SLACK, side="right") - 1
        found = idx >= 0
        last = np.where(found, commands[np.maximum(idx, 0)], -np.inf)
        inside = found & (last >= lower - _GRID_SLACK)
        since[inside] = last[inside]
    return since


def write_csv(
    path: str | PathLike[str] | TextIO, columns: dict[str, np.ndarray] | Recording
) -> None:
    """Write columns as CSV (to a path or an open text stream): one header
    row, one row per sample, shortest round-trip float text. Given a
    :class:`Recording`, its :meth:`Recording.marker` line comes first. A path
    is written atomically (a temporary file renamed over it when complete)."""
    first = columns.marker() if isinstance(columns, Recording) else None
    data = columns.columns if isinstance(columns, Recording) else columns
    if not isinstance(path, (str, PathLike)):
        _write_rows(path, data, first)
        return
    # a temporary file beside the target, renamed over it once complete
    with atomic_writer(os.fspath(path), "w", encoding="utf-8", newline="") as fh:
        _write_rows(fh, data, first)


def _write_rows(fh: TextIO, columns: dict[str, np.ndarray], first: str | None) -> None:
    if first is not None:
        fh.write(first + "\n")
    names = list(columns)
    fh.write(",".join(names) + "\n")
    for row in zip(*(columns[n].tolist() for n in names), strict=True):
        fh.write(",".join(repr(float(v)) for v in row) + "\n")

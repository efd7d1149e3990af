"""The HIL bridge: a gearsim rig behind a CAN bus (docs/hil.md).

Time model. The bridge works in *frame periods* of ``period = substeps * rig.dt``
seconds. Period k covers simulated time [k*period, (k+1)*period):

1. the command frames handled since the previous period are applied (the last
   one of each command frame wins; the ones it replaced count as late);
2. the command timeout is checked; in the safe state the inputs are the safe
   values (speed-driven: base speed 0; torque-driven: motor torque 0; load 0);
3. the rig makes ``substeps`` steps of ``rig.dt`` with the held inputs;
4. every feedback frame whose cycle time divides (k+1)*period is sent,
   stamped with simulated time (k+1)*period (replay) or the wall clock (bus).

Simulated time is ``periods * period``: it advances by step count only.
:meth:`Bridge.advance` runs periods without sleeping (tests, replay);
:meth:`Bridge.run` paces the same periods against the wall clock.

Every received frame ends in exactly one of four classes (``Counters``):
used, rejected (unknown_id, bad_length, undecodable, out_of_range,
mode_mismatch), late (superseded, out_of_order, after_stop) or ignored
(feedback_id, other_dbc_frame, error_frame, remote_frame). Until the next
period applies it, a valid command is *pending*;
``rx_total == rx_used + rx_rejected + rx_late + rx_ignored + pending``.
"""

from __future__ import annotations

import copy
import math
import threading
import time
from array import array
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import can

from ..errors import GearsimError
from ..rig import INPUT_NAMES, OUTPUT_NAMES
from .codec import FrameSpec, Rejection, RigDbc

__all__ = [
    "Bridge",
    "Counters",
    "LoopStats",
    "RigTimeRecorder",
    "BridgeError",
    "REJECT_REASONS",
    "LATE_REASONS",
    "IGNORE_REASONS",
]

REJECT_REASONS = ("unknown_id", "bad_length", "undecodable", "out_of_range", "mode_mismatch")
LATE_REASONS = ("superseded", "out_of_order", "after_stop")
IGNORE_REASONS = ("feedback_id", "other_dbc_frame", "error_frame", "remote_frame")

_TWO_PI = 2.0 * math.pi
#: Spans of constant input at least this many rig steps long are run in C in
#: one call (Rig.run_array, bit-identical to Rig.step); shorter ones call Rig.step.
_BATCH_MIN_STEPS = 4


class BridgeError(GearsimError, ValueError):
    """The bridge cannot be set up as asked (period and cycle times, rig and
    DBC that do not match, ...)."""


@dataclass
class Counters:
    """What the bridge received, sent and did. ``reasons`` breaks rx_rejected,
    rx_late and rx_ignored down ("rejected.unknown_id": 3, ...);
    ``saturated`` counts clamped values per feedback signal."""

    rx_total: int = 0
    rx_used: int = 0
    rx_rejected: int = 0
    rx_late: int = 0
    rx_ignored: int = 0
    tx_frames: int = 0
    tx_errors: int = 0
    timeouts: int = 0
    """transitions into the command timeout after commands had arrived"""
    recoveries: int = 0
    """transitions out of the command timeout"""
    overruns: int = 0
    """paced run: periods that started more than one period late"""
    resyncs: int = 0
    """paced run: times the schedule was moved because the loop fell too far behind"""
    saturations: int = 0
    periods: int = 0
    steps: int = 0
    reasons: dict[str, int] = field(default_factory=dict)
    saturated: dict[str, int] = field(default_factory=dict)

    def count(self, cls: str, reason: str) -> None:
        setattr(self, f"rx_{cls}", getattr(self, f"rx_{cls}") + 1)
        key = f"{cls}.{reason}"
        self.reasons[key] = self.reasons.get(key, 0) + 1

    def as_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in self.__dict__.items() if k not in ("reasons", "saturated")}
        d["reasons"] = dict(sorted(self.reasons.items()))
        d["saturated"] = dict(sorted(self.saturated.items()))
        return d


class LoopStats:
    """Wall-clock record of a paced run: the start time of every period
    (perf_counter seconds) and its deadline."""

    def __init__(self, period: float, capacity: int = 2_000_000) -> None:
        self.period = period
        self.starts = array("d")
        self.lateness = array("d")
        self.capacity = capacity

    def record(self, start: float, deadline: float) -> None:
        if len(self.starts) < self.capacity:
            self.starts.append(start)
            self.lateness.append(start - deadline)

    def summary(self) -> dict[str, float]:
        """Period error |t[k+1] - t[k] - period| and lateness (start minus
        deadline): median, p99 and max in microseconds."""
        import numpy as np

        starts = np.frombuffer(self.starts, dtype=np.float64)
        late = np.frombuffer(self.lateness, dtype=np.float64)
        out: dict[str, float] = {"periods": float(len(starts))}
        if len(starts) > 1:
            err = np.abs(np.diff(starts) - self.period) * 1e6
            out.update(
                period_error_median_us=float(np.median(err)),
                period_error_p99_us=float(np.percentile(err, 99)),
                period_error_max_us=float(err.max()),
            )
        if len(late):
            out.update(
                lateness_median_us=float(np.median(late) * 1e6),
                lateness_p99_us=float(np.percentile(late, 99) * 1e6),
                lateness_max_us=float(late.max() * 1e6),
            )
        return out


class RigTimeRecorder:
    """Passes every frame a bridge receives and sends on to ``listener`` (e.g. a
    can.Logger) stamped in *rig time*: ``origin`` + the bridge's simulated time.

    A received frame is stamped with the start of the period that applies it,
    a sent frame with the end of the period it answers; this is the time base
    of ``replay`` (a frame at t acts on the period starting at t), so the
    recording replays to the same answers, and ``to-csv`` knows at which step
    every command took effect. The frames on the bus keep their own stamps.

        recorder = RigTimeRecorder(bridge, logger.on_message_received, time.time())
        bridge.add_listener(recorder)
    """

    def __init__(
        self, bridge: Bridge, listener: Callable[[can.Message], Any], origin: float = 0.0
    ) -> None:
        self.bridge = bridge
        self.listener = listener
        self.origin = float(origin)

    def __call__(self, msg: can.Message) -> None:
        stamped = copy.copy(msg)
        stamped.timestamp = self.origin + self.bridge.time
        self.listener(stamped)


class Bridge:
    """A rig that answers CAN commands with CAN feedback, period by period.

    Args:
        rig: a gearsim.Rig (``model.rig(dt=period / substeps)``); stepped
            with Rig.step / Rig.run.
        dbc: a RigDbc, a DBC path, or None for the DBC shipped for the rig.
        bus: a python-can bus: poll() reads it, feedback is sent on it.
        send: where feedback goes instead of (or without) a bus: a callable
            taking a can.Message (e.g. a can.Logger).
        substeps: rig steps per frame period (>= 1).
        timeout: command timeout (s), rounded to whole frame periods (>= 1).
        stamp: simulated time (s) -> timestamp of a sent frame. None: the
            wall clock (time.time()), as a bus would stamp it.
        listeners: callables given every frame received and every frame sent
            (e.g. can.Logger for a recording).
    """

    def __init__(
        self,
        rig: Any,
        dbc: RigDbc | str | Any | None = None,
        *,
        bus: can.BusABC | None = None,
        send: Callable[[can.Message], Any] | None = None,
        substeps: int = 1,
        timeout: float = 0.1,
        stamp: Callable[[float], float] | None = None,
        listeners: Iterable[Callable[[can.Message], Any]] = (),
    ) -> None:
        if not isinstance(substeps, int) or isinstance(substeps, bool) or substeps < 1:
            raise BridgeError(
                f"substeps must be an integer >= 1, got {substeps!r}", parameter="substeps"
            )
        if not isinstance(dbc, RigDbc):
            dbc = RigDbc(dbc, block=rig.kind)
        if dbc.block is not None and dbc.block != rig.kind:
            raise BridgeError(
                f"{dbc.path} is for {dbc.block}, the model is {rig.kind}", parameter="dbc"
            )
        self.rig = rig
        self.dbc = dbc
        self.bus = bus
        self._send_fn = send if send is not None else (bus.send if bus is not None else None)
        self.substeps = substeps
        self.dt = float(rig.dt)
        self.period = self.dt * substeps
        self.drive = rig.base_drive
        driving = "cmd.base_speed" if self.drive == "speed" else "cmd.base_torque"
        if driving not in dbc.command_signals:
            raise BridgeError(
                f"{dbc.path} has no command signal with GsRole {driving!r}, which a "
                f"{self.drive}-driven rig needs",
                parameter="dbc",
            )
        self._driving = driving
        if not (isinstance(timeout, (int, float)) and math.isfinite(timeout) and timeout > 0):
            raise BridgeError(f"timeout must be a time > 0 s, got {timeout!r}", parameter="timeout")
        self.timeout_periods = max(1, round(timeout / self.period))
        self.timeout = self.timeout_periods * self.period
        self._cycles: list[tuple[FrameSpec, int]] = []
        for frame in dbc.feedback:
            n = frame.cycle_time / self.period
            if abs(n - round(n)) > 1e-6 * max(1.0, n) or round(n) < 1:
                raise BridgeError(
                    f"feedback frame {frame.name}: cycle time {frame.cycle_time * 1e3:g} ms is "
                    f"not a whole number of frame periods ({self.period * 1e3:g} ms)",
                    parameter="period",
                )
            self._cycles.append((frame, int(round(n))))
        names = {
            s.role[4:]
            for f in dbc.feedback
            for s in f.signals
            if s.role and s.role.startswith("out.")
        }
        if "follower_angle" in names:
            names.discard("follower_angle")
            names.add("follower_position")
        if getattr(rig, "temperature_input", False):
            raise BridgeError(
                "the bridge steps rigs built with temperature_input=False", parameter="rig"
            )
        out_names = list(OUTPUT_NAMES)
        self._out_fields = [(n, out_names.index(n)) for n in sorted(names)]
        self._batch: Any = None
        if hasattr(rig, "run_array"):
            import numpy as np

            in_names = list(INPUT_NAMES)
            self._batch = (
                np.empty((64, len(in_names))),
                np.empty((64, len(out_names))),
                {n: i for i, n in enumerate(in_names)},
            )
        self._stamp = stamp
        self._listeners = list(listeners)
        self.counters = Counters()
        self._pending: dict[tuple[int, bool], tuple[dict[str, Any], float]] = {}
        self._held: dict[tuple[int, bool], dict[str, Any]] = {}
        self._held_ts: dict[tuple[int, bool], float] = {}
        self._last_rx: dict[tuple[int, bool], int] = {}
        self._timed_out = True
        self._ever_commanded = False
        self._status_seq: dict[tuple[int, bool], int] = {}
        self._latched_at: dict[tuple[int, bool], tuple[int, ...]] = {}
        self.state: dict[str, Any] = {
            "cmd_timeout": True,
            "safe_state": True,
            "drive_disabled": False,
        }
        self.inputs: dict[str, float] = {"base_speed": 0.0, "base_torque": 0.0, "load": 0.0}
        self.last_output: dict[str, float] = {}
        self._closed = False
        self._dirty = True
        self._stale_at = 0
        self._due_gcd = 0
        for _, cyc in self._cycles:
            self._due_gcd = math.gcd(self._due_gcd, cyc)
        self._cycle_list = [cyc for _, cyc in self._cycles]

    @classmethod
    def from_model(
        cls,
        model: Any,
        dbc: RigDbc | str | None = None,
        *,
        period: float = 1e-3,
        substeps: int = 1,
        **kwargs: Any,
    ) -> Bridge:
        """A bridge around ``model.rig(dt=period / substeps)`` (a gearsim.Model)."""
        if not (isinstance(period, (int, float)) and math.isfinite(period) and period > 0):
            raise BridgeError(f"period must be a time > 0 s, got {period!r}", parameter="period")
        if not isinstance(substeps, int) or substeps < 1:
            raise BridgeError(
                f"substeps must be an integer >= 1, got {substeps!r}", parameter="substeps"
            )
        return cls(model.rig(dt=period / substeps), dbc, substeps=substeps, **kwargs)

    # -- time --------------------------------------------------------------------
    @property
    def periods(self) -> int:
        """Frame periods completed."""
        return self.counters.periods

    @property
    def time(self) -> float:
        """Simulated time (s): periods completed times the period."""
        return self.counters.periods * self.period

    @property
    def pending(self) -> int:
        """Valid commands received and not yet applied (0 or 1 per command frame)."""
        return len(self._pending)

    # -- receiving ---------------------------------------------------------------
    def handle(self, msg: can.Message) -> str:
        """Classify one received frame; a valid command becomes pending (the
        next period applies it). Returns the class: "pending",
        "rejected.<reason>" or "ignored.<reason>"."""
        c = self.counters
        c.rx_total += 1
        for listener in self._listeners:
            listener(msg)
        if msg.is_error_frame:
            return self._count("ignored", "error_frame")
        if msg.is_remote_frame:
            return self._count("ignored", "remote_frame")
        key = (msg.arbitration_id, bool(msg.is_extended_id))
        frame = self.dbc.commands.get(key)
        if frame is None:
            if key in self.dbc.feedback_keys:
                return self._count("ignored", "feedback_id")
            if key in self.dbc.other_keys:
                return self._count("ignored", "other_dbc_frame")
            return self._count("rejected", "unknown_id")
        values = self.dbc.decode_command(frame, msg.data)
        if isinstance(values, Rejection):
            return self._count("rejected", values.reason)
        mode = values.get("cmd.mode")
        if mode is not None and mode not in ("disabled", self.drive):
            return self._count("rejected", "mode_mismatch")
        ts = float(msg.timestamp)
        held_ts = self._held_ts.get(key)
        pend = self._pending.get(key)
        if (held_ts is not None and ts < held_ts) or (pend is not None and ts < pend[1]):
            return self._count("late", "out_of_order")
        if pend is not None:
            self._count("late", "superseded")
        self._pending[key] = (values, ts)
        return "pending"

    def add_listener(self, listener: Callable[[can.Message], Any]) -> None:
        """Give ``listener`` every frame received and sent from now on."""
        self._listeners.append(listener)

    def _count(self, cls: str, reason: str) -> str:
        self.counters.count(cls, reason)
        return f"{cls}.{reason}"

    def poll(self) -> int:
        """Handle every frame waiting on the bus (never blocks). Returns how many."""
        if self.bus is None:
            return 0
        n = 0
        while True:
            msg = self.bus.recv(timeout=0.0)
            if msg is None:
                return n
            self.handle(msg)
            n += 1

    # -- stepping -----------------------------------------------------------------
    def tick(self) -> None:
        """poll() then advance(1): one frame period, no sleeping."""
        self.poll()
        self.advance(1)

    def advance(self, periods: int = 1) -> None:
        """Run ``periods`` frame periods (apply pending commands, check the
        timeout, step the rig, send the feedback that is due). Frames are not
        read from the bus here; handle() or poll() them first. Simulated time
        advances by periods * period; nothing sleeps."""
        if self._closed:
            raise BridgeError("the bridge is closed")
        remaining = int(periods)
        while remaining > 0:
            if self._pending:
                self._apply_pending()
            now = self.counters.periods
            if self._dirty or (not self._timed_out and now >= self._stale_at):
                self._update_state()
            span = remaining
            if not self._timed_out:
                # inputs stay constant until the timeout would fire
                span = min(span, self._stale_at - now)
            span = max(1, span)
            self._run_span(span)
            remaining -= span

    def _apply_pending(self) -> None:
        if not self._pending:
            return
        now = self.counters.periods
        for key, (values, ts) in self._pending.items():
            self._held[key] = values
            self._held_ts[key] = ts
            self._last_rx[key] = now
            self.counters.rx_used += 1
        self._pending.clear()
        self._ever_commanded = True
        self._dirty = True

    def _update_state(self) -> None:
        now = self.counters.periods
        stale = any(
            key not in self._last_rx or now - self._last_rx[key] > self.timeout_periods
            for key in self.dbc.commands
        )
        if stale and not self._timed_out and self._ever_commanded:
            self.counters.timeouts += 1
        elif not stale and self._timed_out and self.counters.timeouts > self.counters.recoveries:
            self.counters.recoveries += 1
        self._timed_out = stale
        self._dirty = False
        if not stale:
            # first period at which the oldest command frame is stale
            self._stale_at = min(self._last_rx.values()) + self.timeout_periods + 1
        held: dict[str, Any] = {}
        for values in self._held.values():
            held.update(values)
        disabled = not stale and held.get("cmd.mode", self.drive) == "disabled"
        safe = stale or disabled
        self.state = {"cmd_timeout": stale, "safe_state": safe, "drive_disabled": disabled}
        if safe:
            self.inputs = {"base_speed": 0.0, "base_torque": 0.0, "load": 0.0}
        elif self.drive == "speed":
            self.inputs = {
                "base_speed": held["cmd.base_speed"],
                "base_torque": 0.0,
                "load": held.get("cmd.load", 0.0),
            }
        else:
            self.inputs = {
                "base_speed": 0.0,
                "base_torque": held["cmd.base_torque"],
                "load": held.get("cmd.load", 0.0),
            }

    def _run_span(self, span: int) -> None:
        """span periods with the current inputs; feedback at the due ones."""
        c = self.counters
        inp = self.inputs
        n_steps = span * self.substeps
        fields = self._out_fields
        if n_steps >= _BATCH_MIN_STEPS and self._batch is not None:
            out = self._run_batch(n_steps)
            start = c.periods
            for j in range(span):
                c.periods = start + j + 1
                c.steps += self.substeps
                if self._due(c.periods):
                    row = out[(j + 1) * self.substeps - 1]
                    self.last_output = {f: float(row[col]) for f, col in fields}
                    self._emit()
            if not self._due(c.periods):
                row = out[n_steps - 1]
                self.last_output = {f: float(row[col]) for f, col in fields}
            return
        rig = self.rig
        driving = (
            {"base_speed": inp["base_speed"]}
            if self.drive == "speed"
            else {"base_torque": inp["base_torque"]}
        )
        substeps = self.substeps
        load = inp["load"]
        res = None
        for _ in range(span):
            for _ in range(substeps):
                res = rig.step(load=load, **driving)
            c.steps += substeps
            c.periods += 1
            if self._due(c.periods):
                self.last_output = {f: getattr(res, f) for f, _ in fields}
                self._emit()
                res = None
        if res is not None:
            self.last_output = {f: getattr(res, f) for f, _ in fields}

    def _run_batch(self, n: int) -> Any:
        """n rig steps with the current inputs in one C call (Rig.run_array,
        bit-identical to n Rig.step calls); returns the n x 15 outputs."""
        import numpy as np

        buf_in, buf_out, cols = self._batch
        if len(buf_in) < n:
            size = max(n, 2 * len(buf_in))
            buf_in = np.empty((size, buf_in.shape[1]))
            buf_out = np.empty((size, buf_out.shape[1]))
            self._batch = (buf_in, buf_out, cols)
        arr = buf_in[:n]
        ambient = self.rig.ambient_temperature
        arr[:, cols["base_speed"]] = self.inputs["base_speed"]
        arr[:, cols["base_torque"]] = self.inputs["base_torque"]
        arr[:, cols["load"]] = self.inputs["load"]
        arr[:, cols["ambient_temperature"]] = ambient
        arr[:, cols["measured_temperature"]] = ambient
        return self.rig.run_array(arr, buf_out[:n])

    def _due(self, n: int) -> bool:
        if not self._due_gcd or n % self._due_gcd:
            return False
        for cyc in self._cycle_list:
            if n % cyc == 0:
                return True
        return False

    # -- sending ------------------------------------------------------------------
    _LATCHED = ("rx_rejected", "rx_late", "saturations", "overruns", "tx_errors")
    _LATCH_FLAGS = ("cmd_rejected", "cmd_late", "fb_saturated", "overrun", "tx_error")

    def _emit(self) -> None:
        c = self.counters
        n = c.periods
        stamp = self._stamp(n * self.period) if self._stamp is not None else time.time()
        for frame, cyc in self._cycles:
            if n % cyc:
                continue
            values = self._frame_values(frame)
            data, saturated = self.dbc.encode_feedback(frame, values)
            for name in saturated:
                key = f"{frame.name}.{name}"
                c.saturated[key] = c.saturated.get(key, 0) + 1
            c.saturations += len(saturated)
            msg = can.Message(
                timestamp=stamp,
                arbitration_id=frame.frame_id,
                is_extended_id=frame.is_extended,
                data=data,
                is_rx=False,
            )
            self._send(msg)

    def _frame_values(self, frame: FrameSpec) -> dict[str, Any]:
        out = self.last_output
        c = self.counters
        values: dict[str, Any] = {}
        latched = None
        for s in frame.signals:
            role = s.role
            if role is None:
                continue
            group, _, name = role.partition(".")
            if group == "out":
                if name == "follower_angle":
                    values[role] = math.fmod(out["follower_position"], _TWO_PI) % _TWO_PI
                else:
                    values[role] = out[name]
            elif group == "in":
                values[role] = self.inputs[name]
            elif role == "status.counter":
                seq = self._status_seq.get(frame.key, 0)
                values[role] = seq
                self._status_seq[frame.key] = seq + 1
            elif group == "status":
                kind, _, what = name.partition(".")
                if kind == "count":
                    values[role] = getattr(c, what)
                elif what in self.state:
                    values[role] = self.state[what]
                else:
                    if latched is None:
                        now = tuple(getattr(c, a) for a in self._LATCHED)
                        before = self._latched_at.get(frame.key, (0,) * len(now))
                        latched = {
                            f: a > b for f, a, b in zip(self._LATCH_FLAGS, now, before, strict=True)
                        }
                        self._latched_at[frame.key] = now
                    values[role] = latched[what]
        return values

    def _send(self, msg: can.Message) -> None:
        c = self.counters
        if self._send_fn is not None:
            try:
                self._send_fn(msg)
            except can.CanError:
                c.tx_errors += 1
                return
        c.tx_frames += 1
        for listener in self._listeners:
            listener(msg)

    # -- paced loop ------------------------------------------------------------------
    def run(
        self,
        *,
        duration: float | None = None,
        stop: threading.Event | Callable[[], bool] | None = None,
        spin: float = 2e-4,
        max_lag: float = 0.1,
        stats: LoopStats | None = None,
    ) -> LoopStats:
        """Pace frame periods against the wall clock until ``duration``
        (simulated seconds) has run or ``stop`` is set.

        Between periods the loop waits in bus.recv (frames are handled as they
        arrive), then spins for the last ``spin`` seconds before the deadline.
        A period that starts more than one period late counts as an overrun;
        when the loop is more than ``max_lag`` seconds behind, the schedule
        is moved to now (a resync): simulated time then lags the wall clock
        and is never skipped. Returns the LoopStats (also when stopped)."""
        if self.bus is None:
            raise BridgeError("run() needs a bus")
        stats = stats if stats is not None else LoopStats(self.period)
        should_stop: Callable[[], bool]
        if stop is None:
            should_stop = lambda: False  # noqa: E731
        elif isinstance(stop, threading.Event):
            should_stop = stop.is_set
        else:
            should_stop = stop
        end = (
            None
            if duration is None
            else self.counters.periods + max(0, round(duration / self.period))
        )
        clock = time.perf_counter
        period = self.period
        bus = self.bus
        deadline = clock()
        while not should_stop() and (end is None or self.counters.periods < end):
            while True:
                remaining = deadline - clock()
                if remaining <= spin:
                    break
                msg = bus.recv(timeout=remaining - spin)
                if msg is not None:
                    self.handle(msg)
                if should_stop():
                    return stats
            while clock() < deadline:
                pass
            now = clock()
            stats.record(now, deadline)
            late = now - deadline
            if late > period:
                self.counters.overruns += 1
            if late > max_lag:
                self.counters.resyncs += 1
                deadline = now
            self.poll()
            self.advance(1)
            deadline += period
        return stats

    # -- end --------------------------------------------------------------------------
    def close(self) -> dict[str, Any]:
        """Stop: commands still pending never reach a step and count as late
        (after_stop). Returns summary(). Does not shut the bus down."""
        if not self._closed:
            for _ in self._pending:
                self.counters.count("late", "after_stop")
            self._pending.clear()
            self._closed = True
        return self.summary()

    def summary(self) -> dict[str, Any]:
        """Counters, simulated time and state, as plain data (JSON-ready)."""
        d = self.counters.as_dict()
        d["pending"] = len(self._pending)
        d["simulated_time"] = self.time
        d["period"] = self.period
        d["substeps"] = self.substeps
        d["timeout"] = self.timeout
        d["state"] = dict(self.state)
        return d

    def __enter__(self) -> Bridge:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

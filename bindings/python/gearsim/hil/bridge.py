"""The HIL bridge: a gearsim rig behind a CAN bus (docs/hil.md).

The bridge's semantics are the C library's (gearsim/hil.h, hil/src): the
same code as the C runner gearsim-hil, called through cffi. This module
moves frames between python-can and that library, and paces it.

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
import os
import threading
import time
from array import array
from collections.abc import Callable, Iterable
from typing import Any

import can

from .._lib import ffi, lib
from ..errors import GearsimError
from ..rig import OUTPUT_NAMES
from .codec import RigDbc
from .names import IGNORE_REASONS, LATE_REASONS, REJECT_REASONS, STATE_FLAGS, STATUS_COUNTS
from .scenario import Scenario, ScenarioError

__all__ = [
    "Bridge",
    "Counters",
    "LoopStats",
    "RigTimeRecorder",
    "BridgeError",
    "CHUNK_STEPS",
    "REJECT_REASONS",
    "LATE_REASONS",
    "IGNORE_REASONS",
]

#: One C call advances at most this many rig steps: Ctrl-C (seen between two
#: Python bytecodes) stops even a replay across a long pause promptly.
CHUNK_STEPS = 1 << 16


class BridgeError(GearsimError, ValueError):
    """The bridge cannot be set up as asked (period and cycle times, rig and
    DBC that do not match, ...)."""


class Counters:
    """What the bridge received, sent and did: a live view of the C bridge's
    counters, one attribute per counter of gearsim/hil.h: ``rx_total``,
    ``rx_used``, ``rx_rejected``, ``rx_late``, ``rx_ignored``, ``tx_frames``,
    ``tx_errors``, ``timeouts`` (transitions into the command timeout after
    commands had arrived), ``recoveries`` (out of it), ``overruns`` (paced
    run: periods that started more than one period late), ``resyncs`` (paced
    run: the schedule was moved because the loop fell too far behind),
    ``saturations``, ``periods``, ``faults`` (values and frames an injected
    fault changed), ``param_changes``, ``param_refused``, ``log_dropped``
    (the C runner's recording); and ``steps``. ``reasons`` breaks
    rx_rejected, rx_late and rx_ignored down ("rejected.unknown_id": 3, ...);
    ``saturated`` counts clamped values per feedback signal."""

    #: the counters, in the C order, then steps
    NAMES: tuple[str, ...] = (*STATUS_COUNTS, "steps")

    def __init__(self, c_counters: Any) -> None:
        self._c = c_counters
        self.saturated: dict[str, int] = {}

    def __getattr__(self, name: str) -> int:
        if name in STATUS_COUNTS:
            return int(self._c.count[STATUS_COUNTS.index(name)])
        raise AttributeError(name)

    @property
    def steps(self) -> int:
        return int(self._c.steps)

    @property
    def reasons(self) -> dict[str, int]:
        """ "class.reason" -> count, for the reasons that happened."""
        out = {}
        for i in range(1, lib.GS_HIL_REASONS):  # 0 is "pending", no class
            n = int(self._c.reasons[i])
            if n:
                out[ffi.string(lib.gs_hil_reason_name(i)).decode()] = n
        return dict(sorted(out.items()))

    def as_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {name: getattr(self, name) for name in self.NAMES}
        d["reasons"] = self.reasons
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


@ffi.def_extern()
def gspy_hil_send(context: Any, frame: Any) -> int:
    """gs_hil_config.send of every Bridge: the C bridge hands it each
    feedback frame it sends."""
    return ffi.from_handle(context)._sent(frame)


class Bridge:
    """A rig that answers CAN commands with CAN feedback, period by period.

    Args:
        rig: a gearsim.Rig (``model.rig(dt=period / substeps)``), stepped by
            the C bridge in its own C state.
        dbc: a RigDbc, a DBC path, or None for the DBC shipped for the rig.
        bus: a python-can bus: poll() reads it, feedback is sent on it.
        send: where feedback goes instead of (or without) a bus: a callable
            taking a can.Message (e.g. a can.Logger); a can.CanError it
            raises counts as a transmit error.
        substeps: rig steps per frame period (>= 1).
        timeout: command timeout (s), rounded to whole frame periods (>= 1).
        stamp: simulated time (s) -> timestamp of a sent frame. None: the
            wall clock (time.time()), as a bus would stamp it.
        listeners: callables given every frame received and every frame sent
            (e.g. can.Logger for a recording).
        scenario: a scenario file (docs/hil.md, "Scenarios"): its load
            profile, faults, parameter changes and expectations, read and run
            by the C library as the C runner does; junit() gives the verdict.
            ScenarioError (exit 2) names the file, line and key of a bad one.
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
        scenario: str | os.PathLike[str] | None = None,
    ) -> None:
        if not isinstance(substeps, int) or isinstance(substeps, bool) or substeps < 1:
            raise BridgeError(
                f"substeps must be an integer >= 1, got {substeps!r}", parameter="substeps"
            )
        if not (isinstance(timeout, (int, float)) and math.isfinite(timeout) and timeout > 0):
            raise BridgeError(f"timeout must be a time > 0 s, got {timeout!r}", parameter="timeout")
        if not isinstance(dbc, RigDbc):
            dbc = RigDbc(dbc, block=rig.kind)
        if dbc.block is not None and dbc.block != rig.kind:
            raise BridgeError(
                f"{dbc.path} is for {dbc.block}, the model is {rig.kind}", parameter="dbc"
            )
        if getattr(rig, "temperature_input", False):
            raise BridgeError(
                "the bridge steps rigs built with temperature_input=False", parameter="rig"
            )
        self.rig = rig
        self.dbc = dbc
        self.bus = bus
        self._send_fn = send if send is not None else (bus.send if bus is not None else None)
        self.substeps = substeps
        self.dt = float(rig.dt)
        self.drive = rig.base_drive
        self._stamp = stamp
        self._listeners = list(listeners)
        self._closed = False
        self._error: BaseException | None = None
        self._wall = (math.nan, 0.0)  # (simulated time, its wall-clock stamp)
        self._handle = ffi.new_handle(self)
        self._b = self._init_c(float(timeout))
        self.counters = Counters(self._b.counters)
        self._rx = ffi.new("gs_hil_frame *")
        self.scenario: Scenario | None = None
        if scenario is not None:
            self._attach(scenario)

    def _init_c(self, timeout: float) -> Any:
        """The C bridge around the rig's C constants and state."""
        rig = self.rig
        block = lib.GS_RIG_SIMPLE_GEAR if rig.kind == "simple_gear" else lib.GS_RIG_RACK_PINION
        # the DBC's table, for the rig's block when the DBC names none (checked above)
        self._table = ffi.new("gs_hil_dbc *", self.dbc.table.dbc[0])
        self._table.block = block
        config = ffi.new("gs_hil_config *")
        config.dbc = self._table
        speed = rig.base_drive == "speed"
        config.base_drive = lib.GS_BASE_SPEED_DRIVEN if speed else lib.GS_BASE_TORQUE_DRIVEN
        config.dt_s = rig.dt
        config.substeps = self.substeps
        config.timeout_s = timeout
        config.ambient_temperature_K = rig.ambient_temperature
        config.stamp_origin_s = 0.0
        config.send = lib.gspy_hil_send
        config.send_context = self._handle
        # parameter changes at run time start from the parameters the rig was built with
        if rig.kind == "simple_gear":
            config.gear_params = rig.block._c_params
        else:
            config.rack_params = rig.block._c_params
        config.rig_params = rig._c_rig_params
        b = ffi.new("gs_hil_bridge *")
        err = ffi.new("gs_hil_error *")
        if lib.gs_hil_bridge_init(b, config, block, rig._consts, rig._state, err) != lib.GS_HIL_OK:
            parameter = ffi.string(err.parameter).decode() if err.parameter != ffi.NULL else None
            message = ffi.string(err.message).decode("utf-8", "replace")
            if parameter == "dbc":
                message = f"{self.dbc.path}: {message}"
            raise BridgeError(message, parameter=parameter)
        return b

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

    # -- time and state ----------------------------------------------------------
    @property
    def period(self) -> float:
        """The frame period (s): substeps rig steps."""
        return float(self._b.period_s)

    @property
    def timeout_periods(self) -> int:
        """The command timeout in whole frame periods."""
        return int(self._b.timeout_periods)

    @property
    def timeout(self) -> float:
        """The command timeout (s), a whole number of periods."""
        return self.timeout_periods * self.period

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
        return int(lib.gs_hil_pending(self._b))

    @property
    def state(self) -> dict[str, bool]:
        """The state flags of the last period: cmd_timeout, safe_state, drive_disabled."""
        return {name: bool(self._b.flag_state[i]) for i, name in enumerate(STATE_FLAGS)}

    @property
    def inputs(self) -> dict[str, float]:
        """The inputs the rig is stepped with (after the safe-state logic)."""
        i = self._b.input
        return {"base_speed": i.base_speed, "base_torque": i.base_torque, "load": i.load}

    @property
    def last_output(self) -> dict[str, float]:
        """The rig's outputs after the last step."""
        out = self._b.output
        return {name: getattr(out, name) for name in OUTPUT_NAMES}

    # -- receiving ---------------------------------------------------------------
    def handle(self, msg: can.Message) -> str:
        """Classify one received frame; a valid command becomes pending (the
        next period applies it). Returns the class: "pending",
        "rejected.<reason>", "late.<reason>" or "ignored.<reason>"."""
        for listener in self._listeners:
            listener(msg)
        f = self._rx
        data = bytes(msg.data or b"")
        n = min(len(data), lib.GS_HIL_MAX_DATA)
        f.timestamp_s = float(msg.timestamp)
        f.id = msg.arbitration_id
        f.is_extended = bool(msg.is_extended_id)
        f.is_remote = bool(msg.is_remote_frame)
        f.is_error = bool(msg.is_error_frame)
        f.length = len(data)  # longer than classic CAN: counted as bad_length
        ffi.memmove(f.data, data, n)
        return ffi.string(lib.gs_hil_reason_name(lib.gs_hil_handle(self._b, f))).decode()

    def request_param(self, name: str, value: float) -> str:
        """Ask for a rig parameter change ("key", "key[i]" or "key[i][j]" of
        a tunable parameter; gearsim.hil.names.tunable_parameters) as a
        parameter frame would: it takes effect one period after the current
        one (docs/hil.md, "Parameters at run time"). Returns "pending", or
        the refusal (counted): "unknown_param", "bad_element", "busy", ..."""
        from .names import PARAM_RESULTS, parse_parameter

        try:
            index, element = parse_parameter(self.rig.kind, name)
        except ValueError as exc:
            raise BridgeError(str(exc), parameter="param") from None
        result = lib.gs_hil_request_param(self._b, index, element, float(value))
        return "pending" if result == lib.GS_HIL_PARAM_APPLIED else PARAM_RESULTS[result]

    @property
    def rig_params(self) -> Any:
        """The C parameters in use (gs_hil_rig_params: .block.gear or
        .block.rack, and .rig), after the changes that took effect."""
        return lib.gs_hil_params(self._b)

    # -- scenario -----------------------------------------------------------------
    def _attach(self, path: str | os.PathLike[str]) -> None:
        scenario = Scenario(path, self._table, self.rig.kind)
        err = ffi.new("gs_hil_error *")
        if lib.gs_hil_attach_scenario(self._b, scenario._c, err) != lib.GS_HIL_OK:
            raise ScenarioError(
                ffi.string(err.message).decode("utf-8", "replace"), parameter="scenario"
            )
        self.scenario = scenario  # the C bridge points into it: kept alive here

    @property
    def scenario_end(self) -> int:
        """The period count at which the scenario has run its duration (0 without one)."""
        return int(lib.gs_hil_scenario_end(self._b))

    def verdict(self) -> dict[str, int]:
        """Expectations passed, failed (an open window counts as failed once
        the bridge is closed) and still pending."""
        passed, failed, pending = (ffi.new("unsigned *") for _ in range(3))
        lib.gs_hil_verdict_counts(self._b, passed, failed, pending)
        return {"passed": int(passed[0]), "failed": int(failed[0]), "pending": int(pending[0])}

    def junit(self) -> str:
        """The scenario's verdict as JUnit XML (the C library's text: the same
        bytes as gearsim-hil --junit for the same frames). Call after close()
        for the final verdict."""
        n = lib.gs_hil_junit(self._b, ffi.NULL, 0)
        buf = ffi.new("char[]", n + 1)
        lib.gs_hil_junit(self._b, buf, n + 1)
        return ffi.string(buf).decode("utf-8", "replace")

    def add_listener(self, listener: Callable[[can.Message], Any]) -> None:
        """Give ``listener`` every frame received and sent from now on."""
        self._listeners.append(listener)

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
        chunk = max(1, CHUNK_STEPS // self.substeps)
        while remaining > 0:
            n = min(remaining, chunk)
            self._run_c(n)
            remaining -= n

    def _run_c(self, periods: int) -> None:
        """One call of gs_hil_advance; then the exception a send raised, if any."""
        lib.gs_hil_advance(self._b, periods)
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def advance_to(self, t: float) -> None:
        """Run the periods up to the first period boundary at or after
        simulated time ``t`` (within 1 us), where a replay handles a frame
        ``t`` seconds after the log's first one (gs_hil_period_at)."""
        target = int(lib.gs_hil_period_at(self._b, t))
        if target > self.periods:
            self.advance(target - self.periods)

    def period_at(self, t: float) -> int:
        """The period boundary at which a replay handles a frame t seconds
        after the log's first (gs_hil_period_at)."""
        return int(lib.gs_hil_period_at(self._b, t))

    def periods_in(self, seconds: float) -> int:
        """Whole frame periods in ``seconds`` (rounded half to even)."""
        return int(lib.gs_hil_periods_in(self._b, seconds))

    # -- sending ------------------------------------------------------------------
    def _sent(self, frame: Any) -> int:
        """A feedback frame from the C bridge: onto the bus (or ``send``) and
        to the listeners. Returns 0, or 1 for a transmit error. Any other
        exception is kept and raised when the C call returns."""
        if self._error is not None:
            return 1
        try:
            if frame.saturated:
                self._count_saturated(frame)
            msg = can.Message(
                timestamp=self._stamp_of(frame.timestamp_s),
                arbitration_id=frame.id,
                is_extended_id=bool(frame.is_extended),
                data=bytes(ffi.buffer(frame.data, frame.length)),
                is_rx=False,
            )
            if self._send_fn is not None:
                try:
                    self._send_fn(msg)
                except can.CanError:
                    return 1
            for listener in self._listeners:
                listener(msg)
            return 0
        except BaseException as exc:  # raised after the C call, not lost in cffi
            self._error = exc
            return 1

    def _count_saturated(self, frame: Any) -> None:
        """Per signal, the values the C bridge clamped (frame.saturated)."""
        spec = self.dbc.by_key[(frame.id, bool(frame.is_extended))]
        saturated = self.counters.saturated
        for s in spec.signals:
            if frame.saturated >> s.index & 1:
                key = f"{spec.name}.{s.name}"
                saturated[key] = saturated.get(key, 0) + 1

    def _stamp_of(self, simulated: float) -> float:
        if self._stamp is not None:
            return self._stamp(simulated)
        if self._wall[0] != simulated:  # one wall-clock stamp for the frames of a period
            self._wall = (simulated, time.time())
        return self._wall[1]

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
        if duration is None and self.scenario is not None:
            duration = self.scenario.duration  # a scenario runs its duration
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
        counts = self._b.counters.count
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
                counts[lib.GS_HIL_COUNT_OVERRUNS] += 1
            if late > max_lag:
                counts[lib.GS_HIL_COUNT_RESYNCS] += 1
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
            lib.gs_hil_close(self._b)
            lib.gs_hil_finish_scenario(self._b)
            self._closed = True
        return self.summary()

    def summary(self) -> dict[str, Any]:
        """Counters, simulated time and state, as plain data (JSON-ready)."""
        d = self.counters.as_dict()
        d["pending"] = self.pending
        d["simulated_time"] = self.time
        d["period"] = self.period
        d["substeps"] = self.substeps
        d["timeout"] = self.timeout
        d["state"] = dict(self.state)
        if self.scenario is not None:
            v = self.verdict()
            d["verdict"] = {"passed": v["passed"], "failed": v["failed"] + v["pending"]}
        return d

    def __enter__(self) -> Bridge:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

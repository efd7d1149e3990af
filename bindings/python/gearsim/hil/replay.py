"""Replay a recorded CAN log through the bridge, in log time (docs/hil.md).

The log (any format python-can's LogReader reads: .asc, .blf, .csv, .log,
.trc, .mf4, ...) is read in file order. A frame at log time t (seconds after the
first frame) is handled at the first period boundary k*period >= t (within
1 us, the rounding of log formats), so it acts on period k; between frames the
bridge advances without sleeping, as fast as the machine allows. The answers
(feedback frames) are stamped with the log's time base (first frame time +
simulated time) and written with python-can's Logger. The same log, model and
options give the same answers, frame for frame.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import can

from .bridge import Bridge
from .codec import RigDbc

__all__ = ["replay", "replay_messages", "read_log", "ReplayResult"]

#: A frame up to this long after a period boundary counts as at the boundary
#: (absorbs the rounding of log formats and of epoch timestamps), in seconds.
_SLACK = 1e-6


@dataclass
class ReplayResult:
    """Summary of a replay."""

    summary: dict[str, Any]
    """Bridge.summary() at the end (counters, simulated time)"""
    frames_in: int
    frames_out: int
    wall_time: float
    """seconds the replay took"""

    @property
    def frames_per_second(self) -> float:
        """Input frames replayed per wall-clock second."""
        return self.frames_in / self.wall_time if self.wall_time > 0 else math.inf

    def as_dict(self) -> dict[str, Any]:
        return {
            "frames_in": self.frames_in,
            "frames_out": self.frames_out,
            "wall_time": self.wall_time,
            "frames_per_second": self.frames_per_second,
            "counters": self.summary,
        }


def read_log(path: str | PathLike[str]) -> Iterable[can.Message]:
    """Messages of a log file (python-can LogReader, format from the suffix).
    Raises FileNotFoundError, or ValueError for an unknown suffix."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no such file")
    try:
        return can.LogReader(str(p))
    except ValueError as exc:  # unknown suffix
        raise ValueError(f"{p}: {exc}") from None


def replay_messages(
    bridge: Bridge,
    messages: Iterable[can.Message],
    *,
    tail: float = 0.0,
    origin: float | None = None,
    on_input: Callable[[can.Message], Any] | None = None,
) -> int:
    """Drive a bridge from messages in log time (see the module docstring).

    ``origin`` is the log time of simulated time 0 (default: the first
    message's timestamp); the bridge should stamp its answers with
    ``origin + t`` so that they share the log's time base. After the last frame
    the bridge runs one more period (so the last command acts) plus ``tail``
    seconds. ``on_input`` sees every message before the bridge handles it.
    Returns the number of messages."""
    period = bridge.period
    n = 0
    for msg in messages:
        if origin is None:
            origin = float(msg.timestamp)
        t = float(msg.timestamp) - origin
        k = math.ceil((t - _SLACK) / period)
        if k > bridge.periods:
            bridge.advance(k - bridge.periods)
        if on_input is not None:
            on_input(msg)
        bridge.handle(msg)
        n += 1
    bridge.advance(1 + max(0, round(tail / period)))
    return n


def replay(
    model: Any,
    log: str | PathLike[str],
    out: str | PathLike[str] | None = None,
    *,
    dbc: RigDbc | str | PathLike[str] | None = None,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.1,
    tail: float = 0.0,
    with_input: bool = False,
    on_answer: Callable[[can.Message], Any] | None = None,
) -> ReplayResult:
    """Replay ``log`` through a fresh rig of ``model`` (a gearsim.Model) and
    write the answers to ``out`` (python-can Logger; format from the suffix)
    unless it is None. ``with_input`` also writes the log's frames, so that
    the output holds commands and answers in time order. ``on_answer`` is
    called with every answer frame. The log is streamed, not loaded whole;
    wall_time covers reading, simulating and writing."""
    reader = read_log(log)
    origin: list[float] = []
    frames_out = 0
    writer: Any = None

    def answer(msg: can.Message) -> None:
        nonlocal frames_out
        frames_out += 1
        if writer is not None:
            writer.on_message_received(msg)
        if on_answer is not None:
            on_answer(msg)

    def messages() -> Iterable[can.Message]:
        for msg in reader:
            if not origin:
                origin.append(float(msg.timestamp))
            yield msg

    bridge = Bridge.from_model(
        model,
        dbc,
        period=period,
        substeps=substeps,
        timeout=timeout,
        send=answer,
        stamp=lambda t: (origin[0] if origin else 0.0) + t,
    )
    writer = can.Logger(str(out)) if out is not None else None
    on_input = writer.on_message_received if (with_input and writer is not None) else None
    start = time.perf_counter()
    try:
        n = replay_messages(bridge, messages(), tail=tail, on_input=on_input)
        summary = bridge.close()
    finally:
        if writer is not None:
            writer.stop()
        stop = getattr(reader, "stop", None)
        if stop is not None:
            stop()
    wall = time.perf_counter() - start
    return ReplayResult(summary, n, frames_out, wall)

"""Replay a recorded CAN log through the bridge, in log time (docs/hil.md).

The log (any format python-can's LogReader reads: .asc, .blf, .csv, .log,
.trc, .mf4, ..., and the formats it reads compressed with gzip: .asc.gz,
.log.gz, .csv.gz, .trc.gz, .blf.gz) is read in file order. A frame at log
time t (seconds after the first frame) is handled at the first period
boundary k*period >= t (within 1 us, the rounding of log formats; the C
library's rule, gs_hil_advance_to, which the C runner's replay follows too),
so it acts on period k; between frames the bridge advances without sleeping,
as fast as the machine allows. The answers
(feedback frames) are stamped with the log's time base (first frame time +
simulated time) and written with python-can's Logger. The same log, model and
options give the same answers, frame for frame.

Safety:

- the answers are written to a temporary file beside the target and renamed
  over it only when the replay has succeeded (:class:`AtomicLogWriter`); the
  output may not be the log (or any other input);
- time may not jump between two consecutive frames by more than ``max_gap``
  seconds (default :data:`DEFAULT_MAX_GAP`), forwards or backwards: such a
  jump (a log mixing absolute and relative timestamps, a clock step) is
  refused with a :class:`LogError` naming the frame, instead of simulating
  the jump period by period; non-finite timestamps are refused the same way;
- the bridge advances in C calls of at most :data:`CHUNK_STEPS` rig steps,
  so that Ctrl-C stops even a replay across a long pause promptly; memory
  does not grow with the time between two frames;
- a log that cannot be read (corrupt, truncated, wrong format) raises a
  :class:`LogError` naming the file and the frame.
"""

from __future__ import annotations

import contextlib
import gzip
import math
import os
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from os import PathLike
from pathlib import PurePath
from typing import Any

import can
from can.io.generic import (
    BinaryIOMessageReader,
    BinaryIOMessageWriter,
    TextIOMessageReader,
    TextIOMessageWriter,
)

from .._outputs import atomic_write_text, check_output, file_mode, printable
from ..errors import InputError
from .bridge import CHUNK_STEPS, Bridge
from .codec import RigDbc

__all__ = [
    "replay",
    "replay_messages",
    "read_log",
    "ReplayResult",
    "LogError",
    "LogMessages",
    "AtomicLogWriter",
    "log_writer_format",
    "TimeCheck",
    "DEFAULT_MAX_GAP",
    "CHUNK_STEPS",
]

#: Largest time jump (s) allowed between two consecutive frames of a log, by
#: default (``--max-gap``).
DEFAULT_MAX_GAP = 60.0


class LogError(InputError):
    """A log that cannot be read or replayed as asked: unknown or unwritable
    format, corrupt content, non-finite timestamps, a time jump over the limit,
    a replay in which no frame drove the model. Bad input: exit status 2."""


# -- reading -------------------------------------------------------------------------
class TimeCheck:
    """Checks the timestamps of consecutive frames: finite, and no jump larger
    than ``max_gap`` seconds (None: no limit) between two frames in file order.
    ``name`` names the log in the messages. Call with each frame's timestamp;
    frames are counted from 1."""

    def __init__(self, max_gap: float | None, name: str = "the log") -> None:
        if max_gap is not None and not (
            isinstance(max_gap, (int, float)) and math.isfinite(max_gap) and max_gap > 0
        ):
            raise LogError(f"max_gap must be a time > 0 s, got {max_gap!r}", parameter="max_gap")
        self.max_gap = None if max_gap is None else float(max_gap)
        self.name = name
        self.index = 0
        self.previous: float | None = None

    def __call__(self, timestamp: Any) -> float:
        self.index += 1
        try:
            t = float(timestamp)
        except (TypeError, ValueError):
            t = math.nan
        if not math.isfinite(t):
            raise LogError(
                f"{self.name}: frame {self.index}: timestamp {printable(repr(timestamp))} "
                "is not a finite number"
            )
        prev = self.previous
        if prev is not None and self.max_gap is not None and abs(t - prev) > self.max_gap:
            jump = t - prev
            raise LogError(
                f"{self.name}: frame {self.index} (counting from 1): time "
                f"{'jumps forward' if jump > 0 else 'goes back'} by {abs(jump):.6g} s "
                f"(from {prev:.6f} s to {t:.6f} s), more than the limit of "
                f"{self.max_gap:g} s (--max-gap); a log mixing absolute and relative "
                "timestamps, or a clock step? Raise --max-gap for a log with long pauses"
            )
        self.previous = t
        return t


def _open_reader(path: str) -> Any:
    """A python-can reader for ``path`` (can.LogReader: the format from the
    suffix, ``.gz`` for the format before it compressed with gzip). A
    compressed log with further dots in its name (``bench.run.1.asc.gz``),
    which can.LogReader does not take, is opened with the reader that
    python-can lists for the suffix before ``.gz``."""
    shown = printable(path)
    suffixes = [s.lower() for s in PurePath(path).suffixes]
    if not suffixes:
        raise LogError(f"{shown}: no suffix naming the log format (.asc, .blf, .log, ...)")
    fh: Any = None
    try:
        if suffixes[-1] == ".gz" and len(suffixes) > 2:
            cls = can.io.MESSAGE_READERS.get(suffixes[-2])
            if cls is None or not issubclass(cls, (TextIOMessageReader, BinaryIOMessageReader)):
                raise LogError(f"no read support for log format {printable(suffixes[-2])}")
            fh = gzip.open(path, "rt" if issubclass(cls, TextIOMessageReader) else "rb")
            return cls(fh)
        return can.LogReader(path)
    except LogError as exc:
        if fh is not None:
            fh.close()
        raise LogError(f"{shown}: {exc.detail}") from None
    except Exception as exc:  # python-can raises many kinds on a bad file or name
        if fh is not None:
            with contextlib.suppress(Exception):
                fh.close()
        if isinstance(exc, MemoryError):
            raise
        if isinstance(exc, ValueError) and "No read support" in str(exc):
            known = ", ".join(sorted(can.io.MESSAGE_READERS))
            raise LogError(
                f"{shown}: no read support for this log format (known: {known}; "
                ".gz for the compressed text logs and .blf)"
            ) from None
        raise LogError(
            f"{shown}: not a readable {printable(suffixes[-1])} log: {type(exc).__name__}: "
            f"{printable(' '.join(str(exc).split()))}"
        ) from None


class LogMessages:
    """The messages of a log file, in file order (an iterable; iterate once).

    A frame that cannot be read raises a :class:`LogError` naming the file and
    the frame (counted from 1); ``stop()`` (or the context manager) closes the
    file."""

    def __init__(self, path: str | PathLike[str]) -> None:
        self.path = os.fspath(path)
        self.name = printable(self.path)
        self._reader = _open_reader(self.path)
        self.count = 0

    def __iter__(self) -> Iterator[can.Message]:
        it = iter(self._reader)
        while True:
            try:
                msg = next(it)
            except StopIteration:
                return
            except MemoryError:
                raise
            except Exception as exc:  # corrupt or truncated file
                raise LogError(
                    f"{self.name}: cannot read frame {self.count + 1}: {type(exc).__name__}: "
                    f"{printable(' '.join(str(exc).split()))}"
                ) from None
            self.count += 1
            yield msg

    def stop(self) -> None:
        with contextlib.suppress(Exception):
            self._reader.stop()

    def __enter__(self) -> LogMessages:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()


def read_log(path: str | PathLike[str]) -> LogMessages:
    """Messages of a log file (python-can's readers, format from the suffix;
    ``.gz`` for gzip-compressed text logs). Raises FileNotFoundError, or a
    LogError (a ValueError) for an unknown suffix or an unreadable file."""
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise FileNotFoundError(f"{printable(p)}: no such file")
    return LogMessages(p)


# -- writing -------------------------------------------------------------------------
def log_writer_format(path: str | PathLike[str], option: str = "--out") -> str:
    """The python-can log format ``path`` would be written in (".asc",
    ".blf", ..., or ".asc.gz" for a compressed text log); a LogError when
    python-can cannot write it."""
    writers = can.io.MESSAGE_WRITERS
    target = os.fspath(path)
    shown = printable(target)
    suffixes = [s.lower() for s in PurePath(target).suffixes]
    known = ", ".join(sorted(writers))
    if not suffixes or target == "-":
        raise LogError(
            f"{option} {shown}: no suffix naming the log format ({known}; .gz for text logs)"
        )
    if suffixes[-1] == ".gz":
        real = suffixes[-2] if len(suffixes) >= 2 else ""
        cls = writers.get(real)
        if (
            cls is None
            or real in (".blf", ".db")
            or not issubclass(cls, (TextIOMessageWriter, BinaryIOMessageWriter))
        ):
            raise LogError(
                f"{option} {shown}: python-can cannot write {printable(real or '.gz')} compressed"
            )
        return real + ".gz"
    if suffixes[-1] not in writers:
        raise LogError(
            f"{option} {shown}: no write support for {printable(suffixes[-1])} logs ({known})"
        )
    return suffixes[-1]


class AtomicLogWriter:
    """A python-can Logger writing to a temporary file beside ``path`` (same
    format suffix); :meth:`commit` closes it and renames it over ``path``,
    :meth:`abort` closes and removes it. As a context manager: commit when
    the block succeeds, abort otherwise."""

    def __init__(self, path: str | PathLike[str], option: str = "--out") -> None:
        self.path = os.fspath(path)
        fmt = log_writer_format(self.path, option)
        directory = os.path.dirname(os.path.abspath(self.path))
        fd, self.tmp = tempfile.mkstemp(prefix=".gearsim-tmp-", suffix=fmt, dir=directory)
        self._done = False
        try:
            # the permissions of the file replaced, or of a new file (not mkstemp's 0600)
            os.fchmod(fd, file_mode(self.path))
            os.close(fd)
            fd = -1
            self.writer = can.Logger(self.tmp)
        except BaseException as exc:
            with contextlib.suppress(OSError):
                if fd >= 0:
                    os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(self.tmp)
            self._done = True
            if isinstance(exc, (ValueError, ImportError, NotImplementedError)):
                raise LogError(
                    f"{option} {printable(self.path)}: cannot write this log format: "
                    f"{printable(' '.join(str(exc).split()))}"
                ) from None
            raise

    def on_message_received(self, msg: can.Message) -> None:
        self.writer.on_message_received(msg)

    __call__ = on_message_received

    def commit(self) -> None:
        """Close the log and rename it over the target."""
        if self._done:
            return
        self._done = True
        try:
            self.writer.stop()
            os.replace(self.tmp, self.path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(self.tmp)
            raise

    def abort(self) -> None:
        """Close the log and remove it; the target is left as it was."""
        if self._done:
            return
        self._done = True
        with contextlib.suppress(Exception):
            self.writer.stop()
        with contextlib.suppress(OSError):
            os.unlink(self.tmp)

    def __enter__(self) -> AtomicLogWriter:
        return self

    def __exit__(self, exc_type: Any, *exc: Any) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.abort()


# -- replay --------------------------------------------------------------------------
@dataclass
class ReplayResult:
    """Summary of a replay."""

    summary: dict[str, Any]
    """Bridge.summary() at the end (counters, simulated time)"""
    frames_in: int
    frames_out: int
    wall_time: float
    """seconds the replay took"""
    junit: str | None = None
    """the scenario's verdict as JUnit XML (None without a scenario)"""

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


def _check_tail(tail: Any) -> None:
    if not (isinstance(tail, (int, float)) and math.isfinite(tail) and tail >= 0):
        raise LogError(f"tail must be a time >= 0 s, got {tail!r}", parameter="tail")


def replay_messages(
    bridge: Bridge,
    messages: Iterable[can.Message],
    *,
    tail: float = 0.0,
    origin: float | None = None,
    on_input: Callable[[can.Message], Any] | None = None,
    max_gap: float | None = DEFAULT_MAX_GAP,
    name: str = "the log",
) -> int:
    """Drive a bridge from messages in log time (see the module docstring).

    ``origin`` is the log time of simulated time 0 (default: the first
    message's timestamp); the bridge should stamp its answers with
    ``origin + t`` so that they share the log's time base. After the last frame
    the bridge runs one more period (so the last command acts) plus ``tail``
    seconds. ``on_input`` sees every message before the bridge handles it.
    A timestamp that is not finite, or that jumps by more than ``max_gap``
    seconds from the previous frame (None: no limit), raises a LogError
    (``name`` names the log). Returns the number of messages."""
    _check_tail(tail)
    check = TimeCheck(max_gap, name)
    n = 0
    end = bridge.scenario_end
    for msg in messages:
        ts = check(msg.timestamp)
        if origin is None:
            origin = ts
        if end and bridge.period_at(ts - origin) > end:
            break  # after the scenario's end: the run it describes is over
        bridge.advance_to(ts - origin)
        if on_input is not None:
            on_input(msg)
        bridge.handle(msg)
        n += 1
    if not end:
        bridge.advance(1 + bridge.periods_in(tail))  # the last command acts, then the tail
    elif end > bridge.periods:
        bridge.advance(end - bridge.periods)  # a scenario: its duration, as a live run
    return n


def _nothing_used(name: str, n: int, summary: dict[str, Any], bridge: Bridge) -> str:
    if n == 0:
        return f"{name}: the log holds no frames; nothing to replay"
    reasons = ", ".join(f"{k} {v}" for k, v in summary.get("reasons", {}).items()) or "none"
    rig = f"model {bridge.rig.kind}, DBC {printable(os.path.basename(str(bridge.dbc.path)))}"
    if summary.get("rx_rejected", 0) == n:
        return (
            f"{name}: all {n} frames were rejected ({reasons}); no command drove the "
            f"model ({rig}): a log of another rig, or the wrong --model or --dbc?"
        )
    return (
        f"{name}: none of the {n} frames was a command the model could use "
        f"({reasons}; {rig}): a log without commands, or the wrong --model or --dbc?"
    )


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
    max_gap: float | None = DEFAULT_MAX_GAP,
    require_used: bool = False,
    scenario: str | PathLike[str] | None = None,
    junit: str | PathLike[str] | None = None,
) -> ReplayResult:
    """Replay ``log`` through a fresh rig of ``model`` (a gearsim.Model) and
    write the answers to ``out`` (python-can Logger; format from the suffix)
    unless it is None. ``with_input`` also writes the log's frames, so that
    the output holds commands and answers in time order. ``on_answer`` is
    called with every answer frame. The log is streamed, not loaded whole;
    wall_time covers reading, simulating and writing.

    ``out`` is checked before anything is read (it may not be the log, nor
    lie in a missing or unwritable directory, and its format must be one
    python-can writes) and is written atomically: on any failure the previous
    file (or none) is left in place. ``max_gap``: see :func:`replay_messages`.
    ``require_used``: raise a LogError (and write nothing) when no frame of
    the log was a command the model used (a log of another rig, ...).
    ``scenario``: a scenario file run on the replay (the C runner's rule:
    the replay goes on to the scenario's end); ``junit``: where its verdict
    goes (atomically), which is then also ``ReplayResult.junit``."""
    if out is not None:
        check_output(
            out, [log, dbc if not isinstance(dbc, RigDbc) else None, scenario], option="--out"
        )
        log_writer_format(out)
    if junit is not None:
        check_output(junit, [log, scenario, out], option="--junit")
    TimeCheck(max_gap)  # validates max_gap before any work
    _check_tail(tail)
    reader = read_log(log)
    writer: AtomicLogWriter | None = None
    try:
        origin: list[float] = []
        frames_out = 0

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
            scenario=scenario,
        )
        writer = AtomicLogWriter(out) if out is not None else None
        on_input = writer.on_message_received if (with_input and writer is not None) else None
        start = time.perf_counter()
        n = replay_messages(
            bridge, messages(), tail=tail, on_input=on_input, max_gap=max_gap, name=reader.name
        )
        summary = bridge.close()
        if require_used and summary.get("rx_used", 0) == 0:
            raise LogError(_nothing_used(reader.name, n, summary, bridge))
        if writer is not None:
            writer.commit()
        verdict = bridge.junit() if bridge.scenario is not None else None
        if junit is not None and verdict is not None:
            atomic_write_text(junit, verdict)
        wall = time.perf_counter() - start
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        reader.stop()
    return ReplayResult(summary, n, frames_out, wall, verdict)

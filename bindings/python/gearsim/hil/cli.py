"""``gearsim hil``: run the bridge on a CAN bus, replay a log, turn a log into a
measurement CSV (docs/hil.md).

    gearsim hil run    --model M.toml [-i IFACE] [-c CHANNEL] [-b BITRATE] [--dbc F] ...
    gearsim hil run    --model M.toml --runner c [-i socketcan -c CHANNEL | -i candump] ...
    gearsim hil replay LOG --model M.toml [-o ANSWERS.asc] [--dbc F] ...
    gearsim hil to-csv LOG (--rig gear|rack | --dbc F | --model M.toml) -o DATA.csv ...
    gearsim hil dbc    gear|rack [-o FILE]

Hooked into the ``gearsim`` command by gearsim/cli.py through
:func:`add_subparsers`; :func:`main` runs it standalone
(``python -m gearsim.hil``). ``run`` takes the bus from python-can's own
configuration (can.util.load_config: the options, then CAN_INTERFACE,
CAN_CHANNEL, CAN_BITRATE, CAN_CONFIG, then ~/.canrc and the other files);
with nothing configured it exits with status 2 and says how.

Exit status: 0 success, 2 bad input (one line on standard error, no
traceback), 1 internal failure (one line; the traceback only with
GEARSIM_DEBUG set), 130 interrupted, 141 when standard output is a pipe
closed by its reader (``... -o - | head``; nothing printed). Without the hil
extra (python-can, cantools) every command exits with status 2 and one line
naming it: ``pip install 'gearsim[hil]'``. ``--json`` prints exactly one JSON
object on standard output.

Outputs (``-o``, ``--log``) are checked before any work starts (not an input of
the command, not a directory, in a writable directory, a log format python-can
writes) and written atomically: to a temporary file beside the target, renamed
over it only on success. Messages echo user data through ``printable``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

from .._extras import EXTRAS, missing_extra, require
from .._outputs import (
    atomic_write_bytes,
    check_output,
    one_line,
    printable,
    say,
    stdout_to_devnull,
)
from ..cli import EXIT_BROKEN_PIPE, EXIT_INTERRUPTED
from ..errors import GearsimError, InputError

__all__ = ["add_subparsers", "build_parser", "main", "run_args"]

_DESCRIPTION = "HIL bridge: a gearsim rig behind a CAN bus (docs/hil.md)"


class _InputError(InputError):
    """Bad input: exit status 2 with one line."""


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on standard error and exit 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {one_line(message)}\n")
        raise SystemExit(2)


def _show(path: Any) -> str:
    """A path for a message: escaped, cut only when absurdly long (a user
    must see which file was meant, however deep the directory)."""
    return printable(os.fspath(path), limit=1000)


# -- parser -------------------------------------------------------------------------
def _timing_options(p: argparse.ArgumentParser, period_help: str, substeps_help: str) -> None:
    """--period (s) and --substeps: the bridge's timing, the same defaults for
    a run and for reading what a run recorded."""
    p.add_argument("--period", type=float, default=1e-3, metavar="S", help=period_help)
    p.add_argument("--substeps", type=int, default=1, metavar="N", help=substeps_help)


def _model_options(p: argparse.ArgumentParser, model_required: bool = True) -> None:
    p.add_argument(
        "--model",
        required=model_required,
        metavar="MODEL.toml",
        help="model file (docs/measurement-format.md section 2)",
    )
    p.add_argument(
        "--dbc",
        metavar="FILE",
        help="DBC of the rig (default: the one shipped for the model's block)",
    )
    _timing_options(
        p,
        period_help="frame period in seconds (default 0.001: 1 kHz)",
        substeps_help="rig steps per frame period (default 1; rig dt = period / N)",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=0.1,
        metavar="S",
        help="command timeout in seconds before the safe state (default 0.1)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object on standard output")


def _gap_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--max-gap",
        type=float,
        default=None,
        metavar="S",
        help="refuse a log whose time jumps by more than S seconds between two frames "
        "(mixed absolute and relative timestamps, clock steps; default 60)",
    )


def _fill(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="hil_command", metavar="{run,replay,to-csv,dbc}")
    sub.required = True

    p = sub.add_parser(
        "run",
        help="serve the model on a CAN bus, paced by the wall clock",
        description="Step the model at a fixed period on a python-can bus: hold the "
        "last command, send feedback at the DBC cycle times. Ctrl-C stops cleanly "
        "and prints the counters.",
    )
    p.add_argument(
        "-i",
        "--interface",
        help="python-can interface (socketcan, virtual, udp_multicast, pcan, ...; default: "
        "python-can's configuration: CAN_INTERFACE, ~/.canrc, ...)",
    )
    p.add_argument(
        "-c", "--channel", help="channel (default: python-can's configuration, CAN_CHANNEL)"
    )
    p.add_argument(
        "-b",
        "--bitrate",
        type=int,
        help="bit/s, for interfaces that set it (socketcan: set with ip link; default: "
        "python-can's configuration, CAN_BITRATE)",
    )
    p.add_argument(
        "--can-config",
        metavar="FILE",
        help="python-can configuration file to read instead of the default ones "
        "(~/can.conf, /etc/can.conf, ~/.can, ~/.canrc)",
    )
    p.add_argument(
        "--can-context",
        metavar="NAME",
        help="section of the python-can configuration to use (default: [default]; "
        "environment: CAN_INTERFACE_NAME, ...)",
    )
    p.add_argument(
        "--runner",
        choices=("python", "c"),
        default="python",
        help="python: this process paces the model (default); c: start the C runner "
        "gearsim-hil (docs/hil-runner.md)",
    )
    p.add_argument(
        "--print-command",
        action="store_true",
        help="with --runner c: write the runner's parameter file and print the command "
        "line instead of running it",
    )
    p.add_argument(
        "--runner-params",
        metavar="FILE",
        help="with --runner c: where to write the runner's parameter file "
        "(default: a temporary file; with --print-command: MODEL.hil-params in "
        "the working directory)",
    )
    _model_options(p)
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="stop after S seconds of simulated time (default: until Ctrl-C)",
    )
    p.add_argument(
        "--log", metavar="FILE", help="record every frame received and sent (python-can Logger)"
    )
    p.add_argument(
        "--log-time",
        choices=("rig", "wall"),
        default="rig",
        help="timestamps of --log: rig (default: session start + simulated time, the "
        "period that applied or sent each frame; replays and converts exactly) or wall "
        "(the frames' own stamps)",
    )
    p.add_argument(
        "--spin",
        type=float,
        default=2e-4,
        metavar="S",
        help="busy-wait the last S seconds before each period (default 0.0002; 0: sleep only)",
    )
    p.add_argument(
        "--max-lag",
        type=float,
        default=0.1,
        metavar="S",
        help="behind the wall clock by more than S seconds, move the schedule instead of "
        "catching up (default 0.1)",
    )

    p = sub.add_parser(
        "replay",
        help="drive the model from a recorded log, in log time",
        description="Replay a CAN log (.asc, .blf, .csv, .log, .trc, ... as python-can's "
        "LogReader reads them) through the model, deterministically and as fast as "
        "possible; write the answers as a log.",
    )
    p.add_argument("log", metavar="LOG", help="recorded log")
    p.add_argument(
        "-o", "--out", metavar="FILE", help="answers log (python-can Logger, format from suffix)"
    )
    _model_options(p)
    p.add_argument(
        "--tail",
        type=float,
        default=0.0,
        metavar="S",
        help="keep running S seconds after the last frame (default 0)",
    )
    p.add_argument("--with-input", action="store_true", help="also write the log's frames to --out")
    _gap_option(p)

    p = sub.add_parser(
        "to-csv",
        help="turn a log of commands and feedback into a measurement CSV",
        description="Convert a log holding a rig's commands and feedback into the "
        "canonical CSV of docs/measurement-format.md, resampled on a uniform grid "
        "with hold-last, for gearsim compare|diagnose|fit.",
    )
    p.add_argument("log", metavar="LOG", help="recorded log")
    p.add_argument(
        "-o", "--out", required=True, metavar="DATA.csv", help="CSV to write ('-': stdout)"
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--rig", choices=("gear", "rack"), help="use the DBC shipped for this rig")
    g.add_argument(
        "--model", metavar="MODEL.toml", help="use the DBC shipped for this model's block"
    )
    p.add_argument(
        "--dbc", metavar="FILE", help="DBC of the recording (names its rig with GsBlock)"
    )
    p.add_argument(
        "--dt",
        type=float,
        metavar="S",
        help="grid step in seconds (default: longest cycle time of the frames used)",
    )
    _timing_options(
        p,
        period_help="frame period of the run that made the log (default 0.001, as hil run)",
        substeps_help="rig steps per period of that run (default 1, as hil run)",
    )
    p.add_argument(
        "--source",
        choices=("auto", "feedback", "command"),
        default="auto",
        help="inputs from the feedback (measured/applied) or the commands (default auto)",
    )
    p.add_argument(
        "--temperature",
        action="store_true",
        help="add the measured temperature column (out.temperature)",
    )
    _gap_option(p)
    p.add_argument(
        "--max-samples",
        type=int,
        default=None,
        metavar="N",
        help="refuse a grid of more than N samples (default 5000000)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object on standard output")

    p = sub.add_parser(
        "dbc",
        help="print the path of a shipped DBC, or copy it",
        description="The DBC shipped for a rig: its path, or a copy with -o.",
    )
    p.add_argument("rig", choices=("gear", "rack"))
    p.add_argument("-o", "--out", metavar="FILE", help="copy it here")


def build_parser(prog: str = "gearsim hil") -> argparse.ArgumentParser:
    """The standalone parser of ``gearsim hil``."""
    parser = _Parser(prog=prog, description=_DESCRIPTION)
    _fill(parser)
    return parser


def add_subparsers(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``hil`` on the subparsers of the ``gearsim`` command.

    Sets ``func`` to :func:`run_args` (call ``args.func(args)`` and exit with
    its return value). Returns the ``hil`` parser."""
    parser = subparsers.add_parser(
        "hil", help="HIL bridge on CAN: run, replay, to-csv", description=_DESCRIPTION
    )
    _fill(parser)
    parser.set_defaults(func=run_args)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``gearsim hil`` run standalone; returns the exit status."""
    args = build_parser().parse_args(argv)
    return run_args(args)


# -- commands ------------------------------------------------------------------------
def run_args(args: argparse.Namespace) -> int:
    """Run the parsed ``hil`` command; returns the exit status (0, 1, 2, 130
    or 141). Nothing escapes as a traceback unless GEARSIM_DEBUG is set."""
    handlers = {"run": _cmd_run, "replay": _cmd_replay, "to-csv": _cmd_to_csv, "dbc": _cmd_dbc}
    prog = f"gearsim hil {args.hil_command}"
    _quiet_python_can()
    try:
        # every command decodes or encodes through python-can and cantools (the
        # DBC module imports both): checked here, before any input is read
        require(f"'{prog}'", EXTRAS["hil"])
        status = handlers[args.hil_command](args)
        sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
        return status
    except BrokenPipeError:
        stdout_to_devnull()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt:
        say(f"{prog}: interrupted")
        return EXIT_INTERRUPTED
    except (GearsimError, ValueError, OSError) as exc:
        # bad input: missing or unreadable files, a log or DBC that does not fit,
        # options out of range, a bus that does not open, a full disk, ...
        say(f"{prog}: error: {one_line(exc)}")
        return 2
    except Exception as exc:  # internal failure: one line, the traceback on request
        missing = missing_extra(exc, f"'{prog}'")
        if missing is not None:  # the hil extra (or a part of it) is not installed
            say(f"gearsim: {missing}")
            return 2
        if os.environ.get("GEARSIM_DEBUG"):
            raise
        say(
            f"{prog}: internal error: {type(exc).__name__}: {one_line(exc)} "
            "(set GEARSIM_DEBUG=1 for the traceback)"
        )
        return 1


def _quiet_python_can() -> None:
    """python-can logs what it meets in a log or on a bus (e.g. "Unknown
    compression method" in a damaged .blf) through the logging module, which
    without a configured handler prints each record on stderr: a second line
    beside the command's own one-line result. The command reports what went
    wrong itself, so python-can's records are dropped here; GEARSIM_DEBUG
    keeps them."""
    if os.environ.get("GEARSIM_DEBUG"):
        return
    import logging

    log = logging.getLogger("can")
    log.addHandler(logging.NullHandler())
    log.propagate = False


def _load_model(path: str) -> Any:
    import gearsim

    if not Path(path).is_file():
        raise _InputError(f"{_show(path)}: no such model file")
    return gearsim.Model.load(path)


def _dbc_for(args: argparse.Namespace, block: str | None) -> Any:
    from .codec import RigDbc

    if args.dbc is not None and not Path(args.dbc).is_file():
        raise _InputError(f"{_show(args.dbc)}: no such DBC file")
    return RigDbc(args.dbc, block=block)


def _emit(args: argparse.Namespace, data: dict[str, Any], text: list[str]) -> None:
    if getattr(args, "json", False):
        print(json.dumps(data, sort_keys=False))
    else:
        for line in text:
            print(line)


def _counter_lines(summary: dict[str, Any]) -> list[str]:
    from .bridge import Counters

    # the counters in their order, pending beside the rx classes it
    # completes (rx_total = used + rejected + late + ignored + pending)
    keys = list(Counters.NAMES)
    keys.insert(keys.index("rx_ignored") + 1, "pending")
    lines = [
        f"simulated time   {summary['simulated_time']:.6f} s "
        f"({summary['periods']} periods of {summary['period'] * 1e3:g} ms)"
    ]
    lines += [f"{k:<16} {summary[k]}" for k in keys if k in summary]
    for k, v in summary.get("reasons", {}).items():
        lines.append(f"  {k:<22} {v}")
    for k, v in summary.get("saturated", {}).items():  # DBC names: user data
        lines.append(f"  saturated {printable(k):<28} {v}")
    state = summary.get("state", {})
    lines.append("state            " + ", ".join(f"{k}={int(bool(v))}" for k, v in state.items()))
    return lines


def _check_timing(args: argparse.Namespace) -> None:
    for name in ("period", "timeout"):
        v = getattr(args, name)
        if not (v > 0 and v < float("inf")):
            raise _InputError(f"--{name} must be a time > 0 s, got {v!r}")
    if args.substeps < 1:
        raise _InputError(f"--substeps must be >= 1, got {args.substeps}")


def _max_gap(args: argparse.Namespace) -> float:
    from .replay import DEFAULT_MAX_GAP

    v = DEFAULT_MAX_GAP if args.max_gap is None else args.max_gap
    if not (math.isfinite(v) and v > 0):
        raise _InputError(f"--max-gap must be a time > 0 s, got {v!r}")
    return v


def _inputs(args: argparse.Namespace, *names: str) -> list[str | None]:
    return [getattr(args, n, None) for n in names]


_NO_BUS_CONFIGURED = (
    "no CAN interface configured: give -i/--interface and -c/--channel (e.g. -i socketcan "
    "-c can0), set CAN_INTERFACE and CAN_CHANNEL, or write them in python-can's "
    "configuration file ~/.canrc ([default] interface = socketcan, channel = can0)"
)


def _bus_config(args: argparse.Namespace) -> dict[str, Any]:
    """The bus settings through python-can's own loader: the options given on
    the command line, then the environment (CAN_INTERFACE, CAN_CHANNEL,
    CAN_BITRATE, CAN_CONFIG), then the configuration files (--can-config, or
    ~/can.conf, /etc/can.conf, ~/.can, ~/.canrc)."""
    import can
    from can.exceptions import CanInterfaceNotImplementedError

    given = {
        key: value
        for key, value in (
            ("interface", args.interface),
            ("channel", args.channel),
            ("bitrate", args.bitrate),
        )
        if value is not None
    }
    if args.can_config is not None and not Path(args.can_config).is_file():
        raise _InputError(f"{_show(args.can_config)}: no such python-can configuration file")
    try:
        return dict(
            can.util.load_config(path=args.can_config, config=given, context=args.can_context)
        )
    except CanInterfaceNotImplementedError as exc:
        # python-can reports a missing interface as the unknown interface "None"
        if "interface" not in given and '"None"' in str(exc):
            raise _InputError(_NO_BUS_CONFIGURED) from None
        raise _InputError(f"cannot open CAN bus: {one_line(exc)}") from None
    except (ValueError, TypeError) as exc:  # a CAN_CONFIG that is not JSON, a bad port, ...
        raise _InputError(f"python-can configuration: {one_line(exc)}") from None


def _where(config: dict[str, Any]) -> str:
    return f"{printable(str(config.get('interface')))}:{printable(str(config.get('channel')))}"


def _open_bus(config: dict[str, Any]) -> Any:
    import can

    try:
        return can.Bus(ignore_config=True, **config)
    except (can.CanError, OSError, ValueError, TypeError, ImportError, NotImplementedError) as exc:
        raise _InputError(f"cannot open CAN bus {_where(config)}: {one_line(exc)}") from None


def _check_run_options(args: argparse.Namespace) -> None:
    _check_timing(args)
    if args.duration is not None and not args.duration >= 0:
        raise _InputError(f"--duration must be >= 0 s, got {args.duration!r}")
    if not args.max_lag > 0:
        raise _InputError(f"--max-lag must be > 0 s, got {args.max_lag!r}")
    if args.runner != "c":
        for option in ("print_command", "runner_params"):
            if getattr(args, option):
                raise _InputError(f"--{option.replace('_', '-')} needs --runner c")


def _cmd_run(args: argparse.Namespace) -> int:
    from .bridge import Bridge, RigTimeRecorder

    _check_run_options(args)
    if args.runner == "c":
        return _run_c_runner(args)
    if args.log is not None:
        from .replay import log_writer_format

        check_output(args.log, _inputs(args, "model", "dbc", "can_config"), option="--log")
        log_writer_format(args.log, option="--log")
    model = _load_model(args.model)
    dbc = _dbc_for(args, model.block)
    config = _bus_config(args)
    where = _where(config)
    bus = _open_bus(config)
    logger = None
    stop = threading.Event()
    previous: dict[int, Any] = {}
    done = False

    def on_signal(signum: int, frame: Any) -> None:
        stop.set()

    try:
        bridge = Bridge.from_model(
            model, dbc, period=args.period, substeps=args.substeps, timeout=args.timeout, bus=bus
        )
        if args.log is not None:
            from .replay import AtomicLogWriter

            logger = AtomicLogWriter(args.log, option="--log")
            record = logger.on_message_received
            # rig time: the session's start on the wall clock + simulated time
            bridge.add_listener(
                record if args.log_time == "wall" else RigTimeRecorder(bridge, record, time.time())
            )
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                previous[sig] = signal.signal(sig, on_signal)
            except ValueError:  # not the main thread
                pass
        feedback = ", ".join(f"{printable(f.name)}@{f.cycle_time * 1e3:g}ms" for f in dbc.feedback)
        print(
            f"gearsim hil run: {model.block} ({printable(args.model)}) on {where}, "
            f"period {bridge.period * 1e3:g} ms x {bridge.substeps} substep(s), timeout "
            f"{bridge.timeout * 1e3:g} ms; feedback {feedback}; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        stats = bridge.run(
            duration=args.duration, stop=stop, spin=max(0.0, args.spin), max_lag=args.max_lag
        )
        summary = bridge.close()
        done = True
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        try:
            # the recording replaces --log only when the session ended normally
            if logger is not None and done:
                logger.commit()
            elif logger is not None:
                logger.abort()
        finally:
            bus.shutdown()
    timing = stats.summary()
    summary["loop"] = timing
    lines = _counter_lines(summary)
    if "period_error_median_us" in timing:
        lines.append(
            f"period error     median {timing['period_error_median_us']:.1f} us, "
            f"p99 {timing['period_error_p99_us']:.1f} us, "
            f"max {timing['period_error_max_us']:.1f} us"
        )
        lines.append(
            f"start lateness   median {timing['lateness_median_us']:.1f} us, "
            f"p99 {timing['lateness_p99_us']:.1f} us, max {timing['lateness_max_us']:.1f} us"
        )
    _emit(args, summary, lines)
    return 0


_BUILD_RUNNER = (
    "the C runner gearsim-hil is not built: build it with CMake (on by default on Linux: "
    "cmake -S . -B build -DGEARSIM_BUILD_HIL=ON && cmake --build build --target gearsim-hil; "
    "docs/hil-runner.md)"
)


def _runner_transport(args: argparse.Namespace) -> dict[str, Any]:
    """The C runner's transport: candump text on standard input and output
    (``-i candump``), or SocketCAN from python-can's configuration."""
    if args.interface == "candump":
        return {"transport": "candump"}
    config = _bus_config(args)
    if config.get("interface") != "socketcan":
        raise _InputError(
            f"the C runner speaks SocketCAN or candump text on its standard input and output, "
            f"not {_where(config)}: give -i socketcan -c CHANNEL or -i candump "
            "(docs/hil-runner.md)"
        )
    return {"transport": "socketcan", "channel": config.get("channel") or "can0"}


def _runner_command(runner: Any, params: str, args: argparse.Namespace) -> list[str]:
    """The runner's command line for this run (gearsim.hil.runner.live_command)."""
    cmd = runner.live_command(
        params,
        period=args.period,
        substeps=args.substeps,
        timeout=args.timeout,
        duration=args.duration,
        spin_us=round(max(0.0, args.spin) * 1e6),
        json=args.json,
        **_runner_transport(args),
    )
    return [str(part) for part in cmd]


def _run_c_runner(args: argparse.Namespace) -> int:
    """``hil run --runner c``: write the model as the runner's parameter file
    and start gearsim-hil (or print its command line)."""
    import shlex
    import subprocess
    import tempfile

    try:
        from . import runner
    except ImportError:
        raise _InputError(
            "this installation has no C runner support (gearsim.hil.runner)"
        ) from None
    if args.log is not None or args.dbc is not None:
        raise _InputError("--log and --dbc are options of the Python bridge (--runner python)")
    if runner.find_runner() is None:
        raise _InputError(_BUILD_RUNNER)
    model = _load_model(args.model)
    if args.print_command:
        params = args.runner_params or f"{Path(args.model).stem}.hil-params"
        check_output(params, _inputs(args, "model", "can_config"), option="--runner-params")
        runner.write_params(model, params)
        print(shlex.join(_runner_command(runner, params, args)))
        return 0
    with tempfile.TemporaryDirectory(prefix="gearsim-hil-") as tmp:
        params = args.runner_params or os.path.join(tmp, "model.hil-params")
        if args.runner_params:
            check_output(params, _inputs(args, "model", "can_config"), option="--runner-params")
        runner.write_params(model, params)
        cmd = _runner_command(runner, params, args)
        # Ctrl-C reaches the runner too (same process group); it stops cleanly and
        # prints its counters, so this process only waits for it
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            return subprocess.call(cmd)
        finally:
            signal.signal(signal.SIGINT, previous)


def _cmd_replay(args: argparse.Namespace) -> int:
    from .replay import log_writer_format, replay

    _check_timing(args)
    if not (math.isfinite(args.tail) and args.tail >= 0):
        raise _InputError(f"--tail must be a time >= 0 s, got {args.tail!r}")
    max_gap = _max_gap(args)
    if args.out is not None:
        check_output(args.out, _inputs(args, "log", "model", "dbc"), option="--out")
        log_writer_format(args.out, option="--out")
    if not Path(args.log).is_file():
        raise _InputError(f"{_show(args.log)}: no such log file")
    model = _load_model(args.model)
    dbc = _dbc_for(args, model.block)
    # the answers go to a temporary file, renamed over --out at the end; a
    # replay in which no frame drove the model is refused (exit 2, nothing written)
    result = replay(
        model,
        args.log,
        args.out,
        dbc=dbc,
        period=args.period,
        substeps=args.substeps,
        timeout=args.timeout,
        tail=args.tail,
        with_input=args.with_input,
        max_gap=max_gap,
        require_used=True,
    )
    data = result.as_dict()
    lines = [
        f"replayed {result.frames_in} frames, answered {result.frames_out} frames in "
        f"{result.wall_time:.3f} s ({result.frames_per_second:.0f} input frames/s)"
    ]
    if args.out:
        lines.append(f"answers written to {_show(args.out)}")
    lines += _counter_lines(result.summary)
    _emit(args, data, lines)
    return 0


def _cmd_to_csv(args: argparse.Namespace) -> int:
    from .codec import block_name
    from .recording import DEFAULT_MAX_SAMPLES, log_to_measurement, write_csv

    if args.dt is not None and not (math.isfinite(args.dt) and args.dt > 0):
        raise _InputError(f"--dt must be a time > 0 s, got {args.dt!r}")
    if not (math.isfinite(args.period) and args.period > 0):
        raise _InputError(f"--period must be a time > 0 s, got {args.period!r}")
    if args.substeps < 1:
        raise _InputError(f"--substeps must be >= 1, got {args.substeps}")
    max_gap = _max_gap(args)
    max_samples = DEFAULT_MAX_SAMPLES if args.max_samples is None else args.max_samples
    if max_samples < 2:
        raise _InputError(f"--max-samples must be >= 2, got {max_samples}")
    out = check_output(args.out, _inputs(args, "log", "model", "dbc"), option="--out")
    if not Path(args.log).is_file():
        raise _InputError(f"{_show(args.log)}: no such log file")
    block = None
    if args.rig:
        block = block_name(args.rig)
    elif args.model:
        block = _load_model(args.model).block
    if args.dbc is None and block is None:
        raise _InputError("give --rig, --model or --dbc")
    dbc = _dbc_for(args, block)
    rec = log_to_measurement(
        args.log,
        dbc,
        dt=args.dt,
        source=args.source,
        temperature=args.temperature,
        max_gap=max_gap,
        max_samples=max_samples,
        period=args.period,
        substeps=args.substeps,
    )
    for note in rec.notes:  # e.g. why this CSV cannot reproduce the run step for step
        say(f"gearsim hil to-csv: warning: {one_line(note)}")
    if out == "-":
        write_csv(sys.stdout, rec)
        return 0
    write_csv(out, rec)  # atomic: a temporary file renamed over --out
    info = rec.info()
    info["out"] = out
    held = f", inputs held at the rig step {rec.rig_dt:g} s" if rec.time_base == "rig" else ""
    lines = [
        f"wrote {rec.rows} rows every {rec.dt:g} s ({', '.join(rec.columns)}) to {_show(out)} "
        f"({rec.time_base} time{held})"
    ]
    lines += [f"  {col:<16} from {printable(src)}" for col, src in rec.sources.items()]
    _emit(args, info, lines)
    return 0


def _cmd_dbc(args: argparse.Namespace) -> int:
    from .codec import shipped_dbc

    path = shipped_dbc(args.rig)
    if args.out is None:
        print(_show(path))
        return 0
    out = check_output(args.out, [path], option="--out")
    data = path.read_bytes()
    if out == "-":
        sys.stdout.write(data.decode("utf-8"))
        return 0
    atomic_write_bytes(out, data)
    print(_show(out))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

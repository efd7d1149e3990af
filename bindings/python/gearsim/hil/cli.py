"""``gearsim hil``: run the bridge on a CAN bus, replay a log, turn a log into a
measurement CSV (docs/hil.md).

    gearsim hil run    --model M.toml [-i socketcan] [-c can0] [-b 500000] [--dbc F] ...
    gearsim hil replay LOG --model M.toml [-o ANSWERS.asc] [--dbc F] ...
    gearsim hil to-csv LOG (--rig gear|rack | --dbc F | --model M.toml) -o DATA.csv ...
    gearsim hil dbc    gear|rack [-o FILE]

Hooked into the ``gearsim`` command by gearsim/cli.py through
:func:`add_subparsers`; :func:`main` runs it standalone
(``python -m gearsim.hil``). Exit status: 0 success, 2 bad input (one line on
standard error, no traceback), 1 internal failure. ``--json`` prints exactly
one JSON object on standard output.
"""

from __future__ import annotations

import argparse
import json
import shutil
import signal
import sys
import threading
import traceback
from dataclasses import fields
from pathlib import Path
from typing import Any

__all__ = ["add_subparsers", "build_parser", "main", "run_args"]

_DESCRIPTION = "HIL bridge: a gearsim rig behind a CAN bus (docs/hil.md)"


class _InputError(Exception):
    """Bad input: exit status 2 with one line."""


# -- parser -------------------------------------------------------------------------
def _model_options(p: argparse.ArgumentParser, model_required: bool = True) -> None:
    p.add_argument(
        "--model",
        required=model_required,
        metavar="MODEL.toml",
        help="model file (docs/measurement-contract.md section 2)",
    )
    p.add_argument(
        "--dbc",
        metavar="FILE",
        help="DBC of the rig (default: the one shipped for the model's block)",
    )
    p.add_argument(
        "--period",
        type=float,
        default=1e-3,
        metavar="S",
        help="frame period in seconds (default 0.001: 1 kHz)",
    )
    p.add_argument(
        "--substeps",
        type=int,
        default=1,
        metavar="N",
        help="rig steps per frame period (default 1; rig dt = period / N)",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=0.1,
        metavar="S",
        help="command timeout in seconds before the safe state (default 0.1)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object on standard output")


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
        default="socketcan",
        help="python-can interface (socketcan, virtual, udp_multicast, pcan, ...; "
        "default socketcan)",
    )
    p.add_argument("-c", "--channel", default="can0", help="channel (default can0)")
    p.add_argument(
        "-b",
        "--bitrate",
        type=int,
        default=500000,
        help="bit/s, for interfaces that set it (socketcan: set with ip link; default 500000)",
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

    p = sub.add_parser(
        "to-csv",
        help="turn a log of commands and feedback into a measurement CSV",
        description="Convert a log holding a rig's commands and feedback into the "
        "canonical CSV of docs/measurement-contract.md, resampled on a uniform grid "
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
    parser = argparse.ArgumentParser(prog=prog, description=_DESCRIPTION)
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
    """Run the parsed ``hil`` command; returns the exit status (0, 1 or 2)."""
    handlers = {"run": _cmd_run, "replay": _cmd_replay, "to-csv": _cmd_to_csv, "dbc": _cmd_dbc}
    try:
        return handlers[args.hil_command](args)
    except _InputError as exc:
        print(f"gearsim hil {args.hil_command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"gearsim hil {args.hil_command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # internal failure: say so, keep the traceback for reports
        from ..errors import GearsimError

        if isinstance(
            exc, (GearsimError, ValueError, FileNotFoundError, IsADirectoryError, PermissionError)
        ):
            print(f"gearsim hil {args.hil_command}: error: {exc}", file=sys.stderr)
            return 2
        traceback.print_exc()
        print(f"gearsim hil {args.hil_command}: internal error: {exc}", file=sys.stderr)
        return 1


def _load_model(path: str) -> Any:
    import gearsim

    if not Path(path).is_file():
        raise _InputError(f"{path}: no such model file")
    return gearsim.Model.load(path)


def _dbc_for(args: argparse.Namespace, block: str | None) -> Any:
    from .codec import RigDbc

    if args.dbc is not None and not Path(args.dbc).is_file():
        raise _InputError(f"{args.dbc}: no such DBC file")
    return RigDbc(args.dbc, block=block)


def _emit(args: argparse.Namespace, data: dict[str, Any], text: list[str]) -> None:
    if getattr(args, "json", False):
        print(json.dumps(data, sort_keys=False))
    else:
        for line in text:
            print(line)


def _counter_lines(summary: dict[str, Any]) -> list[str]:
    from .bridge import Counters

    # the Counters fields in their order, pending beside the rx classes it
    # completes (rx_total = used + rejected + late + ignored + pending)
    keys = [f.name for f in fields(Counters) if f.name not in ("reasons", "saturated")]
    keys.insert(keys.index("rx_ignored") + 1, "pending")
    lines = [
        f"simulated time   {summary['simulated_time']:.6f} s "
        f"({summary['periods']} periods of {summary['period'] * 1e3:g} ms)"
    ]
    lines += [f"{k:<16} {summary[k]}" for k in keys if k in summary]
    for k, v in summary.get("reasons", {}).items():
        lines.append(f"  {k:<22} {v}")
    for k, v in summary.get("saturated", {}).items():
        lines.append(f"  saturated {k:<28} {v}")
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


def _cmd_run(args: argparse.Namespace) -> int:
    import can

    from .bridge import Bridge

    _check_timing(args)
    if args.duration is not None and not args.duration >= 0:
        raise _InputError(f"--duration must be >= 0 s, got {args.duration!r}")
    if not args.max_lag > 0:
        raise _InputError(f"--max-lag must be > 0 s, got {args.max_lag!r}")
    model = _load_model(args.model)
    dbc = _dbc_for(args, model.block)
    try:
        bus = can.Bus(interface=args.interface, channel=args.channel, bitrate=args.bitrate)
    except (can.CanError, OSError, ValueError, ImportError, NotImplementedError) as exc:
        raise _InputError(f"cannot open CAN bus {args.interface}:{args.channel}: {exc}") from None
    logger = None
    stop = threading.Event()
    previous: dict[int, Any] = {}

    def on_signal(signum: int, frame: Any) -> None:
        stop.set()

    try:
        listeners = []
        if args.log:
            try:
                logger = can.Logger(args.log)
            except ValueError as exc:  # unknown suffix
                raise _InputError(f"{args.log}: {exc}") from None
            listeners.append(logger.on_message_received)
        bridge = Bridge.from_model(
            model,
            dbc,
            period=args.period,
            substeps=args.substeps,
            timeout=args.timeout,
            bus=bus,
            listeners=listeners,
        )
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                previous[sig] = signal.signal(sig, on_signal)
            except ValueError:  # not the main thread
                pass
        feedback = ", ".join(f"{f.name}@{f.cycle_time * 1e3:g}ms" for f in dbc.feedback)
        print(
            f"gearsim hil run: {model.block} ({args.model}) on {args.interface}:{args.channel}, "
            f"period {bridge.period * 1e3:g} ms x {bridge.substeps} substep(s), timeout "
            f"{bridge.timeout * 1e3:g} ms; feedback {feedback}; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        stats = bridge.run(
            duration=args.duration, stop=stop, spin=max(0.0, args.spin), max_lag=args.max_lag
        )
        summary = bridge.close()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if logger is not None:
            logger.stop()
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


def _cmd_replay(args: argparse.Namespace) -> int:
    from .replay import replay

    _check_timing(args)
    if not Path(args.log).is_file():
        raise _InputError(f"{args.log}: no such log file")
    model = _load_model(args.model)
    dbc = _dbc_for(args, model.block)
    # an unknown log suffix is a ValueError: run_args reports it as bad input
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
    )
    data = result.as_dict()
    lines = [
        f"replayed {result.frames_in} frames, answered {result.frames_out} frames in "
        f"{result.wall_time:.3f} s ({result.frames_per_second:.0f} input frames/s)"
    ]
    if args.out:
        lines.append(f"answers written to {args.out}")
    lines += _counter_lines(result.summary)
    _emit(args, data, lines)
    return 0


def _cmd_to_csv(args: argparse.Namespace) -> int:
    from .codec import block_name
    from .recording import RecordingError, log_to_measurement, write_csv

    if not Path(args.log).is_file():
        raise _InputError(f"{args.log}: no such log file")
    block = None
    if args.rig:
        block = block_name(args.rig)
    elif args.model:
        block = _load_model(args.model).block
    if args.dbc is None and block is None:
        raise _InputError("give --rig, --model or --dbc")
    dbc = _dbc_for(args, block)
    try:
        rec = log_to_measurement(
            args.log, dbc, dt=args.dt, source=args.source, temperature=args.temperature
        )
    except RecordingError as exc:
        raise _InputError(f"{args.log}: {exc}") from None
    if args.out == "-":
        write_csv(sys.stdout, rec.columns)
        return 0
    write_csv(args.out, rec.columns)
    info = rec.info()
    info["out"] = args.out
    lines = [f"wrote {rec.rows} rows every {rec.dt:g} s ({', '.join(rec.columns)}) to {args.out}"]
    lines += [f"  {col:<16} from {src}" for col, src in rec.sources.items()]
    _emit(args, info, lines)
    return 0


def _cmd_dbc(args: argparse.Namespace) -> int:
    from .codec import shipped_dbc

    path = shipped_dbc(args.rig)
    if args.out:
        shutil.copyfile(path, args.out)
        print(args.out)
    else:
        print(path)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

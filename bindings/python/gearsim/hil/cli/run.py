"""``gearsim hil run --model M.toml``: serve the model on a CAN bus, paced by the
wall clock (docs/hil.md, "Choosing the bus"). The bus comes from python-can's
own configuration (can.util.load_config: the options, then CAN_INTERFACE,
CAN_CHANNEL, CAN_BITRATE, CAN_CONFIG, then ~/.canrc and the other files); with
nothing configured the command exits with status 2 and says how. ``--runner
c`` hands the run to the C runner instead (run_c.py)."""

from __future__ import annotations

import argparse
import errno
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ..._outputs import check_output, one_line, printable, say
from . import run_c
from .common import (
    HilInputError,
    check_scenario_options,
    check_timing,
    counter_lines,
    dbc_for,
    emit,
    inputs,
    load_model,
    model_options,
    scenario_options,
    verdict_status,
)

NAME = "run"

NO_BUS_CONFIGURED = (
    "no CAN interface configured: give -i/--interface and -c/--channel (e.g. -i socketcan "
    "-c can0), set CAN_INTERFACE and CAN_CHANNEL, or write them in python-can's "
    "configuration file ~/.canrc ([default] interface = socketcan, channel = can0)"
)
#: What -i virtual does not do, said before a run on it.
VIRTUAL_WARNING = (
    "-i virtual is python-can's in-process bus: only buses of this process share it, so a "
    "host in another process (examples/hil/host.py, candump, ...) neither reaches the rig "
    "nor hears it; across processes use -i udp_multicast -c 239.74.163.2, or SocketCAN"
)
#: The hint after python-can's error, by errno, for the socketcan interface.
SOCKETCAN_HINTS = {
    errno.EAFNOSUPPORT: "this kernel has no AF_CAN; load it with modprobe can_raw, or use "
    "another interface (-i udp_multicast -c 239.74.163.2 works without it)",
    errno.ENODEV: "no such CAN interface; ip link show lists them (docs/hil.md, "
    '"SocketCAN on a real rig", brings one up)',
}


def _bus_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "-i",
        "--interface",
        help="python-can interface (socketcan, udp_multicast, pcan, virtual (this process "
        "only), ...; default: python-can's configuration: CAN_INTERFACE, ~/.canrc, ...)",
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


def _session_options(p: argparse.ArgumentParser) -> None:
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


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        NAME,
        help="serve the model on a CAN bus, paced by the wall clock",
        description="Step the model at a fixed period on a python-can bus: hold the "
        "last command, send feedback at the DBC cycle times. Ctrl-C stops cleanly "
        "and prints the counters.",
    )
    _bus_options(p)
    run_c.runner_options(p)
    model_options(p)
    _session_options(p)
    scenario_options(p)


# -- the bus ------------------------------------------------------------------------
def bus_config(args: argparse.Namespace) -> dict[str, Any]:
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
        raise HilInputError(f"{printable(args.can_config)}: no such python-can configuration file")
    try:
        return dict(
            can.util.load_config(path=args.can_config, config=given, context=args.can_context)
        )
    except CanInterfaceNotImplementedError as exc:
        # python-can reports a missing interface as the unknown interface "None"
        if "interface" not in given and '"None"' in str(exc):
            raise HilInputError(NO_BUS_CONFIGURED) from None
        raise HilInputError(f"cannot open CAN bus: {one_line(exc)}") from None
    except (ValueError, TypeError) as exc:  # a CAN_CONFIG that is not JSON, a bad port, ...
        raise HilInputError(f"python-can configuration: {one_line(exc)}") from None


def where(config: dict[str, Any]) -> str:
    return f"{printable(str(config.get('interface')))}:{printable(str(config.get('channel')))}"


def _errno_of(exc: BaseException) -> int | None:
    while exc is not None:
        if isinstance(getattr(exc, "errno", None), int):
            return exc.errno  # type: ignore[no-any-return]
        exc = exc.__cause__ or exc.__context__  # type: ignore[assignment]
    return None


def open_bus(config: dict[str, Any]) -> Any:
    import can

    try:
        return can.Bus(ignore_config=True, **config)
    except (can.CanError, OSError, ValueError, TypeError, ImportError, NotImplementedError) as exc:
        message = f"cannot open CAN bus {where(config)}: {one_line(exc)}"
        socketcan = config.get("interface") == "socketcan"
        hint = SOCKETCAN_HINTS.get(_errno_of(exc)) if socketcan else None
        raise HilInputError(f"{message} ({hint})" if hint else message) from None


# -- the run --------------------------------------------------------------------------
def _check_options(args: argparse.Namespace) -> None:
    check_timing(args)
    check_scenario_options(args)
    if args.duration is not None and not args.duration >= 0:
        raise HilInputError(f"--duration must be >= 0 s, got {args.duration!r}")
    if not args.max_lag > 0:
        raise HilInputError(f"--max-lag must be > 0 s, got {args.max_lag!r}")
    if args.runner != "c":
        for option in ("print_command", "runner_params", "runner_path"):
            if getattr(args, option):
                raise HilInputError(f"--{option.replace('_', '-')} needs --runner c")


def execute(args: argparse.Namespace) -> int:
    _check_options(args)
    if args.runner == "c":
        return run_c.execute(args)
    if args.log is not None:
        from ..replay import log_writer_format

        check_output(
            args.log, inputs(args, "model", "dbc", "can_config", "scenario"), option="--log"
        )
        log_writer_format(args.log, option="--log")
    if args.junit is not None:
        check_output(
            args.junit,
            inputs(args, "model", "dbc", "can_config", "scenario", "log"),
            option="--junit",
        )
    model = load_model(args.model)
    dbc = dbc_for(args, model.block)
    config = bus_config(args)
    if config.get("interface") == "virtual":
        say(f"gearsim hil run: warning: {VIRTUAL_WARNING}")
    bus = open_bus(config)
    summary, stats, verdict = _serve(args, model, dbc, bus, where(config))
    if args.junit is not None and verdict is not None:
        from ..._outputs import atomic_write_text

        atomic_write_text(args.junit, verdict)
    timing = stats.summary()
    summary["loop"] = timing
    lines = counter_lines(summary)
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
    emit(args, summary, lines)
    return verdict_status(summary)


def _serve(
    args: argparse.Namespace, model: Any, dbc: Any, bus: Any, on: str
) -> tuple[dict, Any, str | None]:
    """The paced session on an open bus (shut down at the end): returns the
    bridge's summary, the loop timing and the scenario's verdict (JUnit XML,
    None without a scenario). SIGINT and SIGTERM stop it at the next period;
    --log keeps its recording when the session ends normally."""
    from ..bridge import Bridge, RigTimeRecorder
    from ..replay import AtomicLogWriter

    logger = None
    stop = threading.Event()
    previous: dict[int, Any] = {}
    done = False
    try:
        bridge = Bridge.from_model(
            model,
            dbc,
            period=args.period,
            substeps=args.substeps,
            timeout=args.timeout,
            bus=bus,
            scenario=args.scenario,
        )
        if args.log is not None:
            logger = AtomicLogWriter(args.log, option="--log")
            record = logger.on_message_received
            # rig time: the session's start on the wall clock + simulated time
            bridge.add_listener(
                record if args.log_time == "wall" else RigTimeRecorder(bridge, record, time.time())
            )
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                previous[sig] = signal.signal(sig, lambda signum, frame: stop.set())
            except ValueError:  # not the main thread
                pass
        feedback = ", ".join(f"{printable(f.name)}@{f.cycle_time * 1e3:g}ms" for f in dbc.feedback)
        print(
            f"gearsim hil run: {model.block} ({printable(args.model)}) on {on}, "
            f"period {bridge.period * 1e3:g} ms x {bridge.substeps} substep(s), timeout "
            f"{bridge.timeout * 1e3:g} ms; feedback {feedback}; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        stats = bridge.run(
            duration=args.duration, stop=stop, spin=max(0.0, args.spin), max_lag=args.max_lag
        )
        summary = bridge.close()
        verdict = bridge.junit() if bridge.scenario is not None else None
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
    return summary, stats, verdict

"""``gearsim hil run --runner c``: the model written as the C runner's parameter
file, and gearsim-hil started on it (or its command line printed). Which
runner: --runner-path, $GEARSIM_HIL_RUNNER, the installed one, or the build
docs/hil-runner.md gives (build/hil/gearsim-hil); the command says which it
took (gearsim.hil.runner.locate_runner)."""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from ..._outputs import check_output, say
from .common import HilInputError, inputs, load_model, show


def runner_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--runner",
        choices=("python", "c"),
        default="python",
        help="python: this process paces the model (default); c: start the C runner "
        "gearsim-hil (docs/hil-runner.md)",
    )
    p.add_argument(
        "--runner-path",
        metavar="FILE",
        help="with --runner c: the gearsim-hil to start (default: $GEARSIM_HIL_RUNNER, "
        "gearsim-hil on PATH, then build/hil/gearsim-hil of the source tree)",
    )
    p.add_argument(
        "--print-command",
        action="store_true",
        help="with --runner c: write the runner's parameter file and print the command "
        "line instead of running it",
    )
    p.add_argument(
        "--listen",
        metavar="HOST:PORT",
        default="127.0.0.1:29536",
        help="with --runner c -i socketcand: where the runner's socketcand server listens "
        "(default 127.0.0.1:29536)",
    )
    p.add_argument(
        "--runner-params",
        metavar="FILE",
        help="with --runner c: where to write the runner's parameter file "
        "(default: a temporary file; with --print-command: MODEL.hil-params in "
        "the working directory)",
    )


def _transport(args: argparse.Namespace) -> dict[str, Any]:
    """The C runner's transport: candump text on standard input and output
    (``-i candump``), or SocketCAN from python-can's configuration."""
    from .run import bus_config, where

    if args.interface == "candump":
        return {"transport": "candump"}
    if args.interface == "socketcand":
        return {"transport": "socketcand", "channel": args.channel or "can0", "listen": args.listen}
    config = bus_config(args)
    if config.get("interface") != "socketcan":
        raise HilInputError(
            f"the C runner speaks SocketCAN or candump text on its standard input and output, "
            f"not {where(config)}: give -i socketcan -c CHANNEL or -i candump "
            "(docs/hil-runner.md)"
        )
    return {"transport": "socketcan", "channel": config.get("channel") or "can0"}


def _command(runner: Any, path: Path, params: str, args: argparse.Namespace) -> list[str]:
    """The runner's command line for this run (gearsim.hil.runner.live_command)."""
    campaign = []
    for option in ("scenario", "junit", "log"):
        value = getattr(args, option, None)
        if value is not None:
            campaign += [f"--{option}", os.fspath(value)]
    cmd = runner.live_command(
        params,
        period=args.period,
        substeps=args.substeps,
        timeout=args.timeout,
        duration=args.duration,
        spin_us=round(max(0.0, args.spin) * 1e6),
        json=args.json,
        runner=path,
        **_transport(args),
    )
    return [str(part) for part in cmd] + campaign


def _choose(runner: Any, explicit: str | None) -> tuple[Path, str]:
    """The runner to start, and the line that says which and where it was found."""
    choice = runner.locate_runner(explicit)  # RunnerError: exit 2, with how to build one
    precision = runner.runner_precision(choice.path)
    if precision is None:
        raise HilInputError(f"{show(choice.path)} ({choice.how}): does not run")
    note = (
        ""
        if precision == "double"
        else "; float: its answers are not bit-identical to the Python bridge's"
    )
    which = f"gearsim hil run: C runner {show(choice.path)} ({choice.how}, {precision}{note})"
    return choice.path, which


def execute(args: argparse.Namespace) -> int:
    from .. import runner

    if args.dbc is not None:
        raise HilInputError("--dbc is an option of the Python bridge (--runner python)")
    if args.log is not None and not args.log.lower().endswith(".log"):
        raise HilInputError(f"--log {show(args.log)}: the C runner records candump .log files")
    if args.log is not None:
        check_output(args.log, inputs(args, "model", "can_config", "scenario"), option="--log")
    if args.junit is not None:
        check_output(
            args.junit, inputs(args, "model", "can_config", "scenario", "log"), option="--junit"
        )
    path, which = _choose(runner, args.runner_path)
    model = load_model(args.model)
    if args.print_command:
        params = args.runner_params or f"{Path(args.model).stem}.hil-params"
        check_output(params, inputs(args, "model", "can_config"), option="--runner-params")
        cmd = _command(runner, path, params, args)
        runner.write_params(model, params)
        say(which)  # after every check: a refused run stays one line
        print(shlex.join(cmd))
        return 0
    with tempfile.TemporaryDirectory(prefix="gearsim-hil-") as tmp:
        params = args.runner_params or os.path.join(tmp, "model.hil-params")
        if args.runner_params:
            check_output(params, inputs(args, "model", "can_config"), option="--runner-params")
        cmd = _command(runner, path, params, args)
        runner.write_params(model, params)
        say(which)
        # Ctrl-C reaches the runner too (same process group); it stops cleanly and
        # prints its counters, so this process only waits for it
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            return subprocess.call(cmd)
        finally:
            signal.signal(signal.SIGINT, previous)

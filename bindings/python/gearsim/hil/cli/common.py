"""What the ``gearsim hil`` subcommands share: the option groups, the one-line
input error, messages that show paths, the model and DBC loaders, and the
counter report."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

from ..._outputs import one_line, printable
from ...errors import InputError


class HilInputError(InputError):
    """Bad input: exit status 2 with one line."""


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on standard error and exit 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {one_line(message)}\n")
        raise SystemExit(2)


def show(path: Any) -> str:
    """A path for a message: escaped, cut only when absurdly long (a user
    must see which file was meant, however deep the directory)."""
    return printable(os.fspath(path), limit=1000)


# -- option groups ------------------------------------------------------------------
def timing_options(p: argparse.ArgumentParser, period_help: str, substeps_help: str) -> None:
    """--period (s) and --substeps: the bridge's timing, the same defaults for
    a run and for reading what a run recorded."""
    p.add_argument("--period", type=float, default=1e-3, metavar="S", help=period_help)
    p.add_argument("--substeps", type=int, default=1, metavar="N", help=substeps_help)


def model_options(p: argparse.ArgumentParser) -> None:
    """--model, --dbc, the bridge's timing, --timeout, --json: what a run and a
    replay of the model take."""
    p.add_argument(
        "--model",
        required=True,
        metavar="MODEL.toml",
        help="model file (docs/measurement-format.md section 2; examples/hil/gear_model.toml)",
    )
    p.add_argument(
        "--dbc",
        metavar="FILE",
        help="DBC of the rig (default: the one shipped for the model's block)",
    )
    timing_options(
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
    json_option(p)


#: Exit status of a run or replay whose scenario failed an expectation (the
#: C runner's too): the run itself went through; its verdict says no.
EXIT_VERDICT_FAILED = 3


def scenario_options(p: argparse.ArgumentParser) -> None:
    """--scenario and --junit: a test campaign on the run (docs/hil.md, "Scenarios")."""
    p.add_argument(
        "--scenario",
        metavar="S.toml",
        help="scenario file: load profile, faults, parameter changes and expectations "
        "(docs/hil.md, Scenarios); a run lasts its duration; exit status 3 when an "
        "expectation fails",
    )
    p.add_argument(
        "--junit",
        metavar="VERDICT.xml",
        help="write the scenario's verdict as JUnit XML (one test case per expectation)",
    )


def check_scenario_options(args: argparse.Namespace) -> None:
    if getattr(args, "junit", None) is not None and getattr(args, "scenario", None) is None:
        raise HilInputError("--junit needs --scenario (the verdict is the scenario's)")
    if args.scenario is not None and not Path(args.scenario).is_file():
        raise HilInputError(f"{show(args.scenario)}: no such scenario file")


def verdict_status(summary: dict[str, Any]) -> int:
    """0, or EXIT_VERDICT_FAILED when the summary's verdict has failures."""
    verdict = summary.get("verdict")
    return EXIT_VERDICT_FAILED if verdict and verdict.get("failed") else 0


def json_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object on standard output")


def gap_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--max-gap",
        type=float,
        default=None,
        metavar="S",
        help="refuse a log whose time jumps by more than S seconds between two frames "
        "(mixed absolute and relative timestamps, clock steps; default 60)",
    )


# -- checks and loaders ---------------------------------------------------------------
def check_timing(args: argparse.Namespace) -> None:
    for name in ("period", "timeout"):
        v = getattr(args, name)
        if not (v > 0 and v < float("inf")):
            raise HilInputError(f"--{name} must be a time > 0 s, got {v!r}")
    if args.substeps < 1:
        raise HilInputError(f"--substeps must be >= 1, got {args.substeps}")


def max_gap(args: argparse.Namespace) -> float:
    from ..replay import DEFAULT_MAX_GAP

    v = DEFAULT_MAX_GAP if args.max_gap is None else args.max_gap
    if not (math.isfinite(v) and v > 0):
        raise HilInputError(f"--max-gap must be a time > 0 s, got {v!r}")
    return v


def inputs(args: argparse.Namespace, *names: str) -> list[str | None]:
    """The files the options ``names`` give (None where not given)."""
    return [getattr(args, n, None) for n in names]


def load_model(path: str) -> Any:
    import gearsim

    if not Path(path).is_file():
        raise HilInputError(f"{show(path)}: no such model file")
    return gearsim.Model.load(path)


def dbc_for(args: argparse.Namespace, block: str | None) -> Any:
    from ..codec import RigDbc

    if args.dbc is not None and not Path(args.dbc).is_file():
        raise HilInputError(f"{show(args.dbc)}: no such DBC file")
    return RigDbc(args.dbc, block=block)


# -- output ---------------------------------------------------------------------------
def emit(args: argparse.Namespace, data: dict[str, Any], text: list[str]) -> None:
    """One JSON object with --json, else the text lines."""
    if getattr(args, "json", False):
        print(json.dumps(data, sort_keys=False))
    else:
        for line in text:
            print(line)


def counter_lines(summary: dict[str, Any]) -> list[str]:
    """A bridge summary as text: the counters, the reasons, the saturated
    signals and the state."""
    from ..bridge import Counters

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
    verdict = summary.get("verdict")
    if verdict is not None:
        lines.append(f"verdict          {verdict['passed']} passed, {verdict['failed']} failed")
    return lines

"""``gearsim hil to-csv LOG -o DATA.csv``: a log of a rig's commands and feedback
as the measurement CSV of docs/measurement-format.md (docs/hil.md,
"Recording to measurement")."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from ..._outputs import check_output, one_line, printable, say
from .common import (
    HilInputError,
    dbc_for,
    emit,
    gap_option,
    inputs,
    json_option,
    load_model,
    max_gap,
    show,
    timing_options,
)

NAME = "to-csv"


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        NAME,
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
    timing_options(
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
    gap_option(p)
    p.add_argument(
        "--max-samples",
        type=int,
        default=None,
        metavar="N",
        help="refuse a grid of more than N samples (default 5000000)",
    )
    json_option(p)


def _check(args: argparse.Namespace) -> None:
    if args.dt is not None and not (math.isfinite(args.dt) and args.dt > 0):
        raise HilInputError(f"--dt must be a time > 0 s, got {args.dt!r}")
    if not (math.isfinite(args.period) and args.period > 0):
        raise HilInputError(f"--period must be a time > 0 s, got {args.period!r}")
    if args.substeps < 1:
        raise HilInputError(f"--substeps must be >= 1, got {args.substeps}")


def execute(args: argparse.Namespace) -> int:
    from ..codec import block_name
    from ..recording import DEFAULT_MAX_SAMPLES, log_to_measurement, write_csv

    _check(args)
    gap = max_gap(args)
    max_samples = DEFAULT_MAX_SAMPLES if args.max_samples is None else args.max_samples
    if max_samples < 2:
        raise HilInputError(f"--max-samples must be >= 2, got {max_samples}")
    out = check_output(args.out, inputs(args, "log", "model", "dbc"), option="--out")
    if not Path(args.log).is_file():
        raise HilInputError(f"{show(args.log)}: no such log file")
    block = None
    if args.rig:
        block = block_name(args.rig)
    elif args.model:
        block = load_model(args.model).block
    if args.dbc is None and block is None:
        raise HilInputError("give --rig, --model or --dbc")
    rec = log_to_measurement(
        args.log,
        dbc_for(args, block),
        dt=args.dt,
        source=args.source,
        temperature=args.temperature,
        max_gap=gap,
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
        f"wrote {rec.rows} rows every {rec.dt:g} s ({', '.join(rec.columns)}) to {show(out)} "
        f"({rec.time_base} time{held})"
    ]
    lines += [f"  {col:<16} from {printable(src)}" for col, src in rec.sources.items()]
    emit(args, info, lines)
    return 0

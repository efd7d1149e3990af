"""``gearsim hil replay LOG --model M.toml``: a recorded log drives the model in
log time; the answers as a log (docs/hil.md, "Replay")."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..._outputs import check_output
from .common import (
    HilInputError,
    check_scenario_options,
    check_timing,
    counter_lines,
    dbc_for,
    emit,
    gap_option,
    inputs,
    load_model,
    max_gap,
    model_options,
    scenario_options,
    show,
    verdict_status,
)

NAME = "replay"


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        NAME,
        help="drive the model from a recorded log, in log time",
        description="Replay a CAN log (.asc, .blf, .csv, .log, .trc, ... as python-can's "
        "LogReader reads them) through the model, deterministically and as fast as "
        "possible; write the answers as a log.",
    )
    p.add_argument("log", metavar="LOG", help="recorded log")
    p.add_argument(
        "-o", "--out", metavar="FILE", help="answers log (python-can Logger, format from suffix)"
    )
    model_options(p)
    p.add_argument(
        "--tail",
        type=float,
        default=0.0,
        metavar="S",
        help="keep running S seconds after the last frame (default 0)",
    )
    p.add_argument("--with-input", action="store_true", help="also write the log's frames to --out")
    gap_option(p)
    scenario_options(p)


def execute(args: argparse.Namespace) -> int:
    from ..replay import log_writer_format, replay

    check_timing(args)
    check_scenario_options(args)
    if not (math.isfinite(args.tail) and args.tail >= 0):
        raise HilInputError(f"--tail must be a time >= 0 s, got {args.tail!r}")
    gap = max_gap(args)
    if args.out is not None:
        check_output(args.out, inputs(args, "log", "model", "dbc"), option="--out")
        log_writer_format(args.out, option="--out")
    if not Path(args.log).is_file():
        raise HilInputError(f"{show(args.log)}: no such log file")
    model = load_model(args.model)
    dbc = dbc_for(args, model.block)
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
        max_gap=gap,
        require_used=True,
        scenario=args.scenario,
        junit=args.junit,
    )
    lines = [
        f"replayed {result.frames_in} frames, answered {result.frames_out} frames in "
        f"{result.wall_time:.3f} s ({result.frames_per_second:.0f} input frames/s)"
    ]
    if args.out:
        lines.append(f"answers written to {show(args.out)}")
    if args.junit:
        lines.append(f"verdict written to {show(args.junit)}")
    lines += counter_lines(result.summary)
    emit(args, result.as_dict(), lines)
    return verdict_status(result.summary)

"""``gearsim report DATA.csv --model MODEL.toml --out DIR [--rounds N]
[--json]``: rounds of diagnose -> add the best effect, drawn into PNG files and
one HTML page in DIR."""

from __future__ import annotations

import argparse
import os

from ..._outputs import printable
from .common import (
    check_out,
    common_options,
    count,
    emit_json,
    input_filter,
    load,
    print_warnings,
    progress,
    validation_kwargs,
    validation_options,
    write_model_atomic,
)

NAME = "report"
HELP = "draw compare / diagnose / fit rounds into PNG files and one HTML page"
#: The fits use scipy.optimize; the figures are drawn with matplotlib.
REQUIRES: tuple[str, ...] = ("scipy", "matplotlib")


def configure(p: argparse.ArgumentParser) -> None:
    common_options(p)
    p.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="directory for report.html and the PNG files (created if missing, in an existing "
        "directory; files of the same name in it are replaced, inputs never)",
    )
    validation_options(p)
    p.add_argument(
        "--rounds",
        type=count(0),
        default=3,
        metavar="N",
        help="at most N rounds of diagnose -> add the best effect when it helps, before "
        "drawing (default 3; 0: the model as is)",
    )
    p.add_argument("--title", default=None, help="title of the HTML page")
    p.add_argument(
        "--save-models", action="store_true", help="also write model-round-K.toml for each round"
    )


def execute(args: argparse.Namespace) -> int:
    from ..report import FIGURES, conclusion, run_rounds, write_report

    files = [f"{name}.png" for name in FIGURES] + ["report.html"]
    if args.save_models:
        files += [f"model-round-{i}.toml" for i in range(args.rounds + 2)]
    check_out(args, directory=True, files=files)  # before anything is read
    say = progress(args)
    filt = input_filter(args.input_filter)
    model, meas = load(args, filt)
    rounds = run_rounds(
        model, meas, rounds=args.rounds, input_filter=filt, progress=say, **validation_kwargs(args)
    )
    paths = write_report(
        args.out,
        meas,
        rounds,
        title=args.title or f"gearsim report: {os.path.basename(args.data)}",
        progress=say,
    )
    if args.save_models:
        for i, r in enumerate(rounds):
            write_model_atomic(r.model, os.path.join(args.out, f"model-round-{i}.toml"))
    summary = {
        "report": paths["html"],
        "images": paths["images"],
        "rounds": [
            {
                "round": i,
                "effect": r.effect,
                "nrmse": r.compare.nrmse,
                "estimation_nrmse": r.estimation_nrmse,
                "validation_nrmse": r.validation_nrmse,
                "warnings": [dict(w) for w in (r.fit.warnings if r.fit else [])],
            }
            for i, r in enumerate(rounds)
        ],
        "conclusion": conclusion(rounds),
    }
    if args.json:
        emit_json(summary)
    else:
        for s in summary["rounds"]:
            print(
                f"round {s['round']}: {s['effect'] or 'model as given':34s} nrmse "
                f"{s['nrmse']:.4f}, validation {s['validation_nrmse']:.4f}"
            )
            print_warnings(s["warnings"])
        if summary["conclusion"]:
            print(summary["conclusion"])
        print(f"wrote {printable(paths['html'], limit=200)}")
    return 0

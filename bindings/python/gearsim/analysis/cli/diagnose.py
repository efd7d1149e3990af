"""``gearsim diagnose DATA.csv --model MODEL.toml [--json]``: rank the physical
effects the model lacks, each with its evidence and its error after a fit."""

from __future__ import annotations

import argparse
from typing import Any

from .common import (
    common_options,
    count,
    emit_json,
    g4,
    input_filter,
    load,
    print_warnings,
    progress,
    validation_kwargs,
    validation_options,
)

NAME = "diagnose"
HELP = "rank the physical effects the model lacks, with evidence"
#: The fits use scipy.optimize.
REQUIRES: tuple[str, ...] = ("scipy",)


def configure(p: argparse.ArgumentParser) -> None:
    common_options(p)
    validation_options(p)
    p.add_argument(
        "--top",
        type=count(1),
        default=None,
        metavar="N",
        help="fit only the N best candidates by screening (default: every candidate the "
        "screening does not rule out)",
    )
    p.add_argument(
        "--no-fit", action="store_true", help="screening only (fast; errors after are estimates)"
    )


def execute(args: argparse.Namespace) -> int:
    from ..diagnose import diagnose

    say = progress(args)
    filt = input_filter(args.input_filter)
    model, meas = load(args, filt)
    res = diagnose(
        model,
        meas,
        input_filter=filt,
        top=args.top,
        fit=not args.no_fit,
        progress=say,
        **validation_kwargs(args),
    )
    if args.json:
        emit_json(res.to_json())
    else:
        _print_diagnose(res)
    return 0


def _param_text(parameters: dict) -> str:
    def one(v: Any) -> str:
        return "[" + ", ".join(g4(x) for x in v) + "]" if isinstance(v, list) else g4(v)

    return ", ".join(f"{k}={one(v)}" for k, v in parameters.items())


def _print_diagnose(res) -> None:
    val = res.validation
    held = (
        f"validation on {100 * val.fraction:.0f} % held out (blocks "
        f"{', '.join(map(str, val.blocks))} of 10)"
        if val.enabled
        else "validation off: judged on the whole record"
    )
    print(
        f"baseline nrmse {res.baseline_nrmse:.4f}, validation nrmse "
        f"{res.validation_baseline_nrmse:.4f}, score {res.baseline_score:.1f}; {held}"
    )
    print(f"re-estimating the present parameters alone: nrmse {res.reestimate_nrmse:.4f}")
    fails = res.baseline.failing_regimes
    from ..regimes import FAILING_RATIO

    print(
        f"failing regimes (>= {FAILING_RATIO:g}x the overall error): "
        + (", ".join(f"{r['regime']} ({r['worst_ratio']:.2f}x)" for r in fails) or "none")
    )
    print(
        f"\n{'rank':4s} {'effect':34s} {'score':>11s} {'method':>18s} {'nrmse after':>11s} "
        f"{'validation':>10s} {'helps':>5s}  parameters"
    )
    for i, c in enumerate(res.candidates, 1):
        method = "fit" if c.method == "fit" else "screening estimate"
        print(
            f"{i:4d} {c.effect:34s} {c.score:11.1f} {method:>18s} {c.nrmse_after:11.4f} "
            f"{c.validation_nrmse_after:10.4f} {'yes' if c.helps else 'no':>5s}  "
            f"{_param_text(c.parameters)}"
        )
        if c.tied_with:
            print(f"{'':5s}within the noise of: {', '.join(c.tied_with)} (simpler listed first)")
        if c.evidence.get("text"):
            print(f"{'':5s}evidence: {c.evidence['text']}")
    print("(sorted by score, lower is better; screening estimates follow the fitted candidates)")
    if res.skipped:
        print("\nnot candidates: " + "; ".join(f"{k} ({v})" for k, v in res.skipped.items()))
    if res.warnings:
        print()
    print_warnings(res.warnings)
    print(f"\n{res.conclusion}")

"""``gearsim fit DATA.csv --model MODEL.toml --add EFFECT [--out NEW.toml]
[--json]`` (or ``--refit``): add one effect to the model and fit it, or re-fit
every effect it has; the model written atomically, never over an input."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..._outputs import printable
from .common import (
    check_out,
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
    write_model_atomic,
)

NAME = "fit"
HELP = "add one effect to the model and fit it"
#: The fits use scipy.optimize.
REQUIRES: tuple[str, ...] = ("scipy",)


def configure(p: argparse.ArgumentParser) -> None:
    from ..effects import EFFECT_NAMES

    common_options(p)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument(
        "--add",
        metavar="EFFECT",
        help=f"effect to add: {', '.join(EFFECT_NAMES)}",
    )
    what.add_argument(
        "--refit",
        action="store_true",
        help="add nothing: re-fit together every effect the model has (the final round after "
        "adding them one at a time)",
    )
    p.add_argument(
        "--out",
        metavar="NEW.toml",
        help="write the model with the effect added and fitted, or re-fitted (atomically, after "
        "the fit, also when it is not accepted; never over DATA.csv or MODEL.toml)",
    )
    validation_options(p)
    p.add_argument(
        "--max-samples",
        type=count(1),
        metavar="N",
        help="use at most N residual samples per fit, spread evenly over the whole record "
        "(default 40000; the simulation always runs over all of it)",
    )


def execute(args: argparse.Namespace) -> int:
    from .. import fit, refit
    from ..effects import get_effect

    if args.out is not None:
        check_out(args)  # before anything is read, not after minutes of work
    say = progress(args)
    filt = input_filter(args.input_filter)
    # an unknown / inapplicable effect: exit 2 before any work
    check = _refit_check if args.refit else (lambda m: get_effect(args.add, m))
    model, meas = load(args, filt, check=check)
    if args.refit:
        res = refit(
            model,
            meas,
            input_filter=filt,
            max_samples=args.max_samples,
            progress=say,
            **validation_kwargs(args),
        )
    else:
        res = fit(
            model,
            meas,
            args.add,
            input_filter=filt,
            max_samples=args.max_samples,
            progress=say,
            **validation_kwargs(args),
        )
    if not res.accepted:  # one line, whatever the output format
        print(f"gearsim fit: {res.verdict}", file=sys.stderr)
    if args.out is not None:
        write_model_atomic(res.model, args.out)
        say(f"wrote {printable(args.out, limit=200)}")
    if args.json:
        out = res.to_json()
        if args.out:
            out["out"] = args.out
        emit_json(out)
    else:
        _print_fit(res)
    return 0


def _refit_check(model: Any) -> None:
    from ..effects import present_effects
    from ..errors import EffectError

    if not present_effects(model):
        raise EffectError(
            "--refit: the model has no effect of docs/measurement-format.md section 3 to re-fit",
            parameter="--refit",
        )


def _print_fit(res) -> None:
    print(
        f"effect {res.effect}: nrmse {res.nrmse_before:.4f} -> {res.nrmse_after:.4f} "
        f"({res.evaluations} simulations, {res.seconds:.1f} s, {res.fit_samples} samples, "
        f"{res.fit_points} residual points spread over them)"
    )
    print(f"{'parameter':28s} {'value':>12s} {'std':>10s} {'before':>12s}  role")
    for f in res.fitted:
        before = "" if f["before"] is None else g4(f["before"])
        print(
            f"{f['name']:28s} {g4(f['value']):>12s} {g4(f['std']):>10s} {before:>12s}  {f['role']}"
        )
    for name, m in res.outputs_after.items():
        print(f"  {name}: nrmse {res.outputs_before[name].nrmse:.4f} -> {m.nrmse:.4f}")
    where = "held-out blocks" if res.validation.enabled else "whole record (validation off)"
    print(
        f"  validation ({where}): nrmse {res.validation_nrmse_before:.4f} -> "
        f"{res.validation_nrmse_after:.4f}"
    )
    print_warnings(res.warnings)
    for n in res.notes:
        print(f"note: {n}")
    print(res.verdict)

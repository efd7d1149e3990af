"""The analysis subcommands of ``gearsim``: compare, diagnose, fit, report.

A thin shell over gearsim.analysis: parse arguments, load and check the model
and the measurement (all input is checked before anything is written), call
the function, print a table or exactly one JSON object on stdout. Progress
goes to stderr (silence it with --quiet), never into the JSON.

Outputs (``fit --out``, ``report --out``) are checked by
:func:`gearsim._outputs.check_output` first thing in the handler, before any
input is read: an empty path, an input of the command, a directory where a
file is wanted (or the reverse), a missing or unwritable directory end the
command at once with exit status 2. Every file is written atomically
(:func:`gearsim._outputs.atomic_writer`) and only after the work succeeded.

Options that would silently give a wrong answer are refused: an
``--input-filter`` cut-off at or above the Nyquist frequency of the data,
negative or fractional counts (``--rounds``, ``--top``, ``--max-samples``,
``--max-gap``). The loader's notes on how the data was read or changed
(separator, units, ``--resample``) and its warnings are printed on stderr, one
line each, even with --quiet.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Iterable
from typing import Any

from .._outputs import OutputPathError, atomic_write_text, check_output, printable

__all__ = ["register"]

FORMAT_DOC = "docs/measurement-format.md"
#: Default of --max-gap: longest run of missing samples --resample fills.
DEFAULT_MAX_GAP = 10


# ---------------------------------------------------------------- shared


def _count(minimum: int):
    """argparse type: a whole number >= minimum (a negative or fractional
    count is refused, not clamped)."""

    def parse(text: str) -> int:
        try:
            value = int(str(text).strip(), 10)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be a whole number >= {minimum}, got '{printable(text)}'"
            ) from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {minimum}, got {value}")
        return value

    parse.__name__ = f"whole number >= {minimum}"
    return parse


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", metavar="DATA.csv", help=f"measurement CSV (columns: {FORMAT_DOC})")
    p.add_argument(
        "--model", required=True, metavar="MODEL.toml", help=f"model file ({FORMAT_DOC})"
    )
    p.add_argument("--json", action="store_true", help="print exactly one JSON object on stdout")
    p.add_argument(
        "--column",
        action="append",
        metavar="CANONICAL=SOURCE[*FACTOR]",
        default=[],
        help="read a canonical column from another header name, optionally scaled into SI "
        "(repeatable), e.g. --column pinion_speed=omega_rpm*0.104719755",
    )
    p.add_argument(
        "--resample",
        action="store_true",
        help="interpolate non-uniformly sampled data onto a uniform grid instead of refusing "
        "it (what was filled is said on stderr)",
    )
    p.add_argument(
        "--max-gap",
        type=_count(0),
        default=DEFAULT_MAX_GAP,
        metavar="N",
        help="with --resample: refuse to interpolate across a gap of more than N missing "
        f"samples (default {DEFAULT_MAX_GAP}); 0 fills every gap",
    )
    p.add_argument(
        "--input-filter",
        default="auto",
        metavar="auto|none|HZ",
        help="zero-phase low-pass on the measured inputs before they drive the rig: 'auto' "
        "(cut-off from each input's spectrum, default), 'none', or a cut-off in Hz below the "
        "Nyquist frequency 0.5/dt of the data",
    )
    p.add_argument("--quiet", action="store_true", help="no progress messages on stderr")


def _fraction(text: str) -> float:
    """argparse type: a held-out fraction in (0, 0.5]."""
    try:
        value = float(str(text).strip())
    except ValueError:
        value = float("nan")
    if not (0.0 < value <= 0.5):
        raise argparse.ArgumentTypeError(f"must be a fraction in (0, 0.5], got '{printable(text)}'")
    return value


_fraction.__name__ = "fraction in (0, 0.5]"


def _validation_args(p: argparse.ArgumentParser) -> None:
    from .scoring import DEFAULT_FRACTION

    p.add_argument(
        "--no-validation",
        action="store_true",
        help="estimate on the whole record and judge on it too (default: hold out "
        "contiguous blocks and judge effects on them)",
    )
    p.add_argument(
        "--validation-fraction",
        type=_fraction,
        default=DEFAULT_FRACTION,
        metavar="F",
        help=f"share of the record held out for validation, in (0, 0.5] (default "
        f"{DEFAULT_FRACTION:g}: 3 of 10 contiguous blocks)",
    )


def _validation(args: argparse.Namespace) -> dict[str, Any]:
    return {"validation": not args.no_validation, "validation_fraction": args.validation_fraction}


def _print_warnings(warnings: list[dict]) -> None:
    for w in warnings:
        print(f"warning: {w['text']}")


def _progress(args: argparse.Namespace):
    if getattr(args, "quiet", False):
        return lambda msg: None
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        sys.stderr.write(f"[{time.perf_counter() - t0:6.2f} s] {msg}\n")
        sys.stderr.flush()

    return say


def _input_filter(value: str):
    from .errors import MeasurementError

    v = str(value).strip().lower()
    if v == "auto":
        return "auto"
    if v in ("none", "off", "0"):
        return None
    try:
        hz = float(v)
    except ValueError:
        raise MeasurementError(
            f"--input-filter must be auto, none or a frequency in Hz, got '{printable(value)}'"
        ) from None
    if not (hz > 0 and math.isfinite(hz)):
        raise MeasurementError(
            f"--input-filter must be a positive frequency in Hz, got '{printable(value)}'"
        )
    return hz


def _check_cutoff(filt: Any, meas: Any, text: str) -> None:
    """A fixed cut-off at or above the Nyquist frequency filters nothing
    (zero_phase_lowpass returns the signal as is): refuse it."""
    from .errors import MeasurementError

    if not isinstance(filt, float):
        return
    nyquist = 0.5 / meas.dt
    if filt >= nyquist:
        raise MeasurementError(
            f"--input-filter {printable(text)} Hz is at or above the Nyquist frequency "
            f"{nyquist:.6g} Hz of {printable(meas.path)} (0.5/dt, dt = {meas.dt:.6g} s): it "
            "would filter nothing; give a cut-off below it, or none"
        )


def _check_magnitudes(model: Any, path: str) -> None:
    """The analysis simulates and fits: a model parameter beyond the supported
    magnitude (1e12 in SI units, as for measured values) overflows the
    simulation or the fit's scaling. The C core accepts any finite value whose
    reciprocal fits (docs/hardening.md, L1); the analysis refuses with the key."""
    from ..errors import ModelFileError
    from .measurement import MAX_MAGNITUDE

    for section, params in (("block", model.block_params), ("rig", model.rig_params)):
        for key, value in params.items():
            values = value if isinstance(value, (list, tuple)) else [value]
            flat = [v for row in values for v in (row if isinstance(row, (list, tuple)) else [row])]
            for v in flat:
                number = isinstance(v, (int, float)) and not isinstance(v, bool)
                if number and abs(v) > MAX_MAGNITUDE:
                    raise ModelFileError(
                        f"{key} = {v:g} ([{section}]) is beyond the supported magnitude "
                        f"{MAX_MAGNITUDE:g} (SI units)",
                        file=printable(path, limit=200),
                        parameter=key,
                    )


def _load(args: argparse.Namespace, filt: Any = None, check: Any = None):
    """Model and measurement, both checked (exit 2 on any problem), the fixed
    --input-filter cut-off checked against the data's Nyquist frequency, and
    check(model) if given. The loader's notes are printed on stderr only once
    every check passed: a refusal stays one line."""
    from ..errors import ModelFileError
    from .measurement import load_measurement, parse_column_map
    from .modelkit import load_model

    if not os.path.exists(args.model):
        raise ModelFileError("no such file", file=printable(args.model, limit=200))
    model = load_model(args.model)  # the Model plus its [analysis] table
    _check_magnitudes(model, args.model)
    notes: list[str] = []  # how the file was read or changed, and warnings
    meas = load_measurement(
        args.data,
        model.block,
        columns=parse_column_map(args.column),
        resample=args.resample,
        max_gap=args.max_gap,
        note=notes.append,
    )
    _check_cutoff(filt, meas, args.input_filter)
    if check is not None:
        check(model)
    for text in notes:  # said even with --quiet: they change what the data means
        sys.stderr.write(f"gearsim {args._command}: note: {printable(text, limit=600)}\n")
    return model, meas


def _check_out(
    args: argparse.Namespace, *, directory: bool = False, files: Iterable[str] = ()
) -> str:
    """check_output on --out before any work; for a directory, also each file
    the command will write in it (none may be an input or a directory)."""
    inputs = [args.data, args.model]
    if args.out is not None and str(args.out).strip() == "-":
        raise OutputPathError(
            f"--out -: gearsim {args._command} cannot write to standard output; name a "
            + ("directory" if directory else "file"),
            parameter="--out",
        )
    out = check_output(args.out, inputs, option="--out", directory=directory)
    if directory and os.path.isdir(out):
        for name in files:
            check_output(os.path.join(out, name), inputs, option="--out", probe=False)
    return out


def _clean(obj: Any) -> Any:
    """JSON-safe: numpy scalars to float, non-finite floats to None."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def _emit_json(obj: dict) -> None:
    sys.stdout.write(json.dumps(_clean(obj), allow_nan=False) + "\n")
    sys.stdout.flush()


def _write_model_atomic(model: Any, path: str) -> None:
    """The model's TOML, written atomically; a failure (the directory went
    away, the disk is full) is one line naming the file."""
    try:
        atomic_write_text(path, model.dumps())
    except OSError as exc:
        raise OutputPathError(
            f"--out {printable(path)}: cannot write ({exc.strerror or exc})", parameter="--out"
        ) from None


def _g(x: Any) -> str:
    try:
        return f"{float(x):.4g}"
    except (TypeError, ValueError):
        return str(x)


# ---------------------------------------------------------------- compare


def _compare_args(p: argparse.ArgumentParser) -> None:
    _common(p)


def _print_compare(res) -> None:
    meas = res.meas
    print(
        f"{printable(meas.path, limit=200)}: {meas.n} samples, dt = {meas.dt:.6g} s; "
        f"model block {meas.block}"
    )
    print(
        f"{'output':16s} {'nrmse':>8s} {'fit %':>7s} {'rmse':>10s} "
        f"{'max |err|':>10s} {'at t (s)':>9s}"
    )
    for name, m in res.outputs.items():
        print(
            f"{name:16s} {m.nrmse:8.4f} {m.fit_percent:7.2f} {m.rmse:10.4g} "
            f"{m.max_abs:10.4g} {m.t_max_abs:9.4g}"
        )
    print(f"{'overall':16s} {res.nrmse:8.4f} {100 * (1 - res.nrmse):7.2f}")
    _print_regimes(res)


def _print_regimes(res) -> None:
    if not res.regimes:
        return
    from .regimes import FAILING_RATIO

    outs = list(res.outputs)
    floors = ", ".join(
        f"{o} {_g(res.regimes[0]['outputs'][o].get('noise_floor', float('nan')))}" for o in outs
    )
    print(
        "\nerror by regime (rms residual in the regime / std of the output; x = ratio to "
        f"overall; a regime fails at >= {FAILING_RATIO:g}x and >= {FAILING_RATIO:g}x the noise "
        f"floor: {floors}):"
    )
    print(f"{'regime':20s} {'share':>6s} " + " ".join(f"{o:>22s}" for o in outs))
    for r in res.regimes:
        cells = []
        for o in outs:
            e = r["outputs"][o]
            cells.append(f"{_g(e['nrmse']):>10s} ({_g(e['ratio']):>5s}x)   ")
        flag = f"  <- fails (>= {FAILING_RATIO:g}x)" if r["failing"] else ""
        print(f"{r['regime']:20s} {100 * r['fraction']:5.1f}% " + " ".join(cells) + flag)


def _compare(args: argparse.Namespace) -> int:
    from .compare import compare

    say = _progress(args)
    filt = _input_filter(args.input_filter)
    model, meas = _load(args, filt)
    say(f"compare: {meas.n} samples")
    res = compare(model, meas, input_filter=filt)
    if args.json:
        _emit_json(res.to_json())
    else:
        _print_compare(res)
    return 0


# ---------------------------------------------------------------- diagnose


def _diagnose_args(p: argparse.ArgumentParser) -> None:
    _common(p)
    _validation_args(p)
    p.add_argument(
        "--top",
        type=_count(1),
        default=None,
        metavar="N",
        help="fit only the N best candidates by screening (default: every candidate the "
        "screening does not rule out)",
    )
    p.add_argument(
        "--no-fit", action="store_true", help="screening only (fast; errors after are estimates)"
    )


def _param_text(parameters: dict) -> str:
    def one(v: Any) -> str:
        return "[" + ", ".join(_g(x) for x in v) + "]" if isinstance(v, list) else _g(v)

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
    from .regimes import FAILING_RATIO

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
    _print_warnings(res.warnings)
    print(f"\n{res.conclusion}")


def _diagnose(args: argparse.Namespace) -> int:
    from .diagnose import diagnose

    say = _progress(args)
    filt = _input_filter(args.input_filter)
    model, meas = _load(args, filt)
    res = diagnose(
        model,
        meas,
        input_filter=filt,
        top=args.top,
        fit=not args.no_fit,
        progress=say,
        **_validation(args),
    )
    if args.json:
        _emit_json(res.to_json())
    else:
        _print_diagnose(res)
    return 0


# ---------------------------------------------------------------- fit


def _fit_args(p: argparse.ArgumentParser) -> None:
    from .effects import EFFECT_NAMES

    _common(p)
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
    _validation_args(p)
    p.add_argument(
        "--max-samples",
        type=_count(1),
        metavar="N",
        help="use at most N residual samples per fit, spread evenly over the whole record "
        "(default 40000; the simulation always runs over all of it)",
    )


def _print_fit(res) -> None:
    print(
        f"effect {res.effect}: nrmse {res.nrmse_before:.4f} -> {res.nrmse_after:.4f} "
        f"({res.evaluations} simulations, {res.seconds:.1f} s, {res.fit_samples} samples, "
        f"{res.fit_points} residual points spread over them)"
    )
    print(f"{'parameter':28s} {'value':>12s} {'std':>10s} {'before':>12s}  role")
    for f in res.fitted:
        before = "" if f["before"] is None else _g(f["before"])
        print(
            f"{f['name']:28s} {_g(f['value']):>12s} {_g(f['std']):>10s} {before:>12s}  {f['role']}"
        )
    for name, m in res.outputs_after.items():
        print(f"  {name}: nrmse {res.outputs_before[name].nrmse:.4f} -> {m.nrmse:.4f}")
    where = "held-out blocks" if res.validation.enabled else "whole record (validation off)"
    print(
        f"  validation ({where}): nrmse {res.validation_nrmse_before:.4f} -> "
        f"{res.validation_nrmse_after:.4f}"
    )
    _print_warnings(res.warnings)
    for n in res.notes:
        print(f"note: {n}")
    print(res.verdict)


def _refit_check(model: Any) -> None:
    from .effects import present_effects
    from .errors import EffectError

    if not present_effects(model):
        raise EffectError(
            "--refit: the model has no effect of docs/measurement-format.md section 3 to re-fit",
            parameter="--refit",
        )


def _fit(args: argparse.Namespace) -> int:
    from . import fit, refit
    from .effects import get_effect

    if args.out is not None:
        _check_out(args)  # before anything is read, not after minutes of work
    say = _progress(args)
    filt = _input_filter(args.input_filter)
    # an unknown / inapplicable effect: exit 2 before any work
    check = _refit_check if args.refit else (lambda m: get_effect(args.add, m))
    model, meas = _load(args, filt, check=check)
    if args.refit:
        res = refit(
            model,
            meas,
            input_filter=filt,
            max_samples=args.max_samples,
            progress=say,
            **_validation(args),
        )
    else:
        res = fit(
            model,
            meas,
            args.add,
            input_filter=filt,
            max_samples=args.max_samples,
            progress=say,
            **_validation(args),
        )
    if not res.accepted:  # one line, whatever the output format
        print(f"gearsim fit: {res.verdict}", file=sys.stderr)
    if args.out is not None:
        _write_model_atomic(res.model, args.out)
        say(f"wrote {printable(args.out, limit=200)}")
    if args.json:
        out = res.to_json()
        if args.out:
            out["out"] = args.out
        _emit_json(out)
    else:
        _print_fit(res)
    return 0


# ---------------------------------------------------------------- report


def _report_args(p: argparse.ArgumentParser) -> None:
    _common(p)
    p.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="directory for report.html and the PNG files (created if missing, in an existing "
        "directory; files of the same name in it are replaced, inputs never)",
    )
    _validation_args(p)
    p.add_argument(
        "--rounds",
        type=_count(0),
        default=3,
        metavar="N",
        help="at most N rounds of diagnose -> add the best effect when it helps, before "
        "drawing (default 3; 0: the model as is)",
    )
    p.add_argument("--title", default=None, help="title of the HTML page")
    p.add_argument(
        "--save-models", action="store_true", help="also write model-round-K.toml for each round"
    )


def _report(args: argparse.Namespace) -> int:
    from .report import FIGURES, conclusion, run_rounds, write_report

    files = [f"{name}.png" for name in FIGURES] + ["report.html"]
    if args.save_models:
        files += [f"model-round-{i}.toml" for i in range(args.rounds + 2)]
    _check_out(args, directory=True, files=files)  # before anything is read
    say = _progress(args)
    filt = _input_filter(args.input_filter)
    model, meas = _load(args, filt)
    rounds = run_rounds(
        model, meas, rounds=args.rounds, input_filter=filt, progress=say, **_validation(args)
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
            _write_model_atomic(r.model, os.path.join(args.out, f"model-round-{i}.toml"))
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
        _emit_json(summary)
    else:
        for s in summary["rounds"]:
            print(
                f"round {s['round']}: {s['effect'] or 'model as given':34s} nrmse "
                f"{s['nrmse']:.4f}, validation {s['validation_nrmse']:.4f}"
            )
            _print_warnings(s["warnings"])
        if summary["conclusion"]:
            print(summary["conclusion"])
        print(f"wrote {printable(paths['html'], limit=200)}")
    return 0


#: Modules (of the analysis extra) each command cannot run without, checked
#: before it starts. compare needs none: without pandas it reads CSV with the
#: csv module, and zstandard is asked for only by a .zst file (one line naming
#: the extra). The fits use scipy.optimize; report draws with matplotlib.
REQUIRES: dict[str, tuple[str, ...]] = {
    "compare": (),
    "diagnose": ("scipy",),
    "fit": ("scipy",),
    "report": ("scipy", "matplotlib"),
}


def register(subparsers: argparse._SubParsersAction) -> None:
    from ..cli import add_command

    add_command(
        subparsers,
        "compare",
        "simulate a model on a measurement and report its error",
        _compare_args,
        _compare,
        requires=REQUIRES["compare"],
    )
    add_command(
        subparsers,
        "diagnose",
        "rank the physical effects the model lacks, with evidence",
        _diagnose_args,
        _diagnose,
        requires=REQUIRES["diagnose"],
    )
    add_command(
        subparsers,
        "fit",
        "add one effect to the model and fit it",
        _fit_args,
        _fit,
        requires=REQUIRES["fit"],
    )
    add_command(
        subparsers,
        "report",
        "draw compare / diagnose / fit rounds into PNG files and one HTML page",
        _report_args,
        _report,
        requires=REQUIRES["report"],
    )

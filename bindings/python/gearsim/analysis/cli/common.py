"""What the analysis subcommands share: the options every one of them takes,
the checked loading of the model and the measurement, the check of ``--out``
before any work, the progress lines, and the one JSON object on stdout."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Iterable
from typing import Any

from ..._outputs import OutputPathError, atomic_write_text, check_output, printable

FORMAT_DOC = "docs/measurement-format.md"
#: Default of --max-gap: longest run of missing samples --resample fills.
DEFAULT_MAX_GAP = 10


def count(minimum: int):
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


def common_options(p: argparse.ArgumentParser) -> None:
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
        type=count(0),
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


def fraction(text: str) -> float:
    """argparse type: a held-out fraction in (0, 0.5]."""
    try:
        value = float(str(text).strip())
    except ValueError:
        value = float("nan")
    if not (0.0 < value <= 0.5):
        raise argparse.ArgumentTypeError(f"must be a fraction in (0, 0.5], got '{printable(text)}'")
    return value


fraction.__name__ = "fraction in (0, 0.5]"


def validation_options(p: argparse.ArgumentParser) -> None:
    from ..scoring import DEFAULT_FRACTION

    p.add_argument(
        "--no-validation",
        action="store_true",
        help="estimate on the whole record and judge on it too (default: hold out "
        "contiguous blocks and judge effects on them)",
    )
    p.add_argument(
        "--validation-fraction",
        type=fraction,
        default=DEFAULT_FRACTION,
        metavar="F",
        help=f"share of the record held out for validation, in (0, 0.5] (default "
        f"{DEFAULT_FRACTION:g}: 3 of 10 contiguous blocks)",
    )


def validation_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    return {"validation": not args.no_validation, "validation_fraction": args.validation_fraction}


def print_warnings(warnings: list[dict]) -> None:
    for w in warnings:
        print(f"warning: {w['text']}")


def progress(args: argparse.Namespace):
    if getattr(args, "quiet", False):
        return lambda msg: None
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        sys.stderr.write(f"[{time.perf_counter() - t0:6.2f} s] {msg}\n")
        sys.stderr.flush()

    return say


def input_filter(value: str):
    from ..errors import MeasurementError

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
    from ..errors import MeasurementError

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
    from ...errors import ModelFileError
    from ..measurement import MAX_MAGNITUDE

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


def load(args: argparse.Namespace, filt: Any = None, check: Any = None):
    """Model and measurement, both checked (exit 2 on any problem), the fixed
    --input-filter cut-off checked against the data's Nyquist frequency, and
    check(model) if given. The loader's notes are printed on stderr only once
    every check passed: a refusal stays one line."""
    from ...errors import ModelFileError
    from ..measurement import load_measurement, parse_column_map
    from ..modelkit import load_model

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


def check_out(
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


def emit_json(obj: dict) -> None:
    sys.stdout.write(json.dumps(_clean(obj), allow_nan=False) + "\n")
    sys.stdout.flush()


def write_model_atomic(model: Any, path: str) -> None:
    """The model's TOML, written atomically; a failure (the directory went
    away, the disk is full) is one line naming the file."""
    try:
        atomic_write_text(path, model.dumps())
    except OSError as exc:
        raise OutputPathError(
            f"--out {printable(path)}: cannot write ({exc.strerror or exc})", parameter="--out"
        ) from None


def g4(x: Any) -> str:
    """x with 4 significant digits, or as text when it is not a number."""
    try:
        return f"{float(x):.4g}"
    except (TypeError, ValueError):
        return str(x)

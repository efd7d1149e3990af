"""``gearsim fleet``: the analysis over a fleet of logs on Dask.

    gearsim fleet DIR|GLOB --model MODEL.toml --out OUT --add EFFECT[,EFFECT...]
    gearsim fleet --manifest UNITS.csv --model MODEL.toml --out OUT --diagnose
                  [--scheduler tcp://host:8786 | --workers N] [--json] [--quiet]

A thin shell over gearsim.fleet.run_fleet (docs/fleet.md). Every input is
checked before any work: a missing directory, a glob that matches nothing, a
bad manifest row, a bad model, an unknown effect, an --out that holds an
input end the command with exit status 2 and one line. A log that cannot be
analysed does not: its unit gets an error row and the run goes on (exit 0).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

from .._outputs import printable

__all__ = ["register", "REQUIRES"]

#: what the command cannot run without: the fits (scipy), the report
#: (matplotlib), the cluster (dask, distributed) and the Parquet file (pyarrow)
REQUIRES = ("scipy", "matplotlib", "dask", "distributed", "pyarrow")


def _count(minimum: int):
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


def _positive(text: str) -> float:
    try:
        value = float(str(text).strip())
    except ValueError:
        value = math.nan
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"must be a positive number, got '{printable(text)}'")
    return value


_positive.__name__ = "positive number"


def _fraction(text: str) -> float:
    try:
        value = float(str(text).strip())
    except ValueError:
        value = math.nan
    if not (0.0 < value <= 0.5):
        raise argparse.ArgumentTypeError(f"must be a fraction in (0, 0.5], got '{printable(text)}'")
    return value


_fraction.__name__ = "fraction in (0, 0.5]"


def _configure(p: argparse.ArgumentParser) -> None:
    from ..analysis import EFFECT_NAMES
    from .population import THRESHOLD

    src = p.add_argument_group("the logs (one of)")
    src.add_argument(
        "source",
        nargs="?",
        metavar="DIR|GLOB",
        help="a directory of logs (*.csv, *.tsv, *.txt, optionally .gz/.bz2/.xz/.zst; not "
        "recursive) or a quoted glob pattern ('logs/**/*.csv')",
    )
    src.add_argument(
        "--manifest",
        metavar="UNITS.csv",
        help="a CSV with the columns unit and path (relative to the manifest), optionally line, "
        "station, timestamp (ISO 8601 or seconds since 1970)",
    )
    p.add_argument(
        "--model", required=True, metavar="MODEL.toml", help="the start model of every unit"
    )
    p.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="output directory: units.parquet, population.json, fleet.html, units/, cache.sqlite "
        "(created if missing; never one that holds an input)",
    )
    what = p.add_mutually_exclusive_group()
    what.add_argument(
        "--add",
        action="append",
        default=[],
        metavar="EFFECT[,EFFECT...]",
        help=f"effects to fit on every unit, in this order (repeatable): {', '.join(EFFECT_NAMES)}",
    )
    what.add_argument(
        "--diagnose",
        action="store_true",
        help="run the full diagnose rounds on every unit instead of a fixed list",
    )
    p.add_argument(
        "--rounds",
        type=_count(1),
        default=3,
        metavar="N",
        help="with --diagnose: at most N rounds (default 3)",
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler",
        metavar="tcp://HOST:8786",
        help="a running Dask scheduler; its workers need the gearsim package (with the fleet "
        "extra) and the logs at the same paths",
    )
    where.add_argument(
        "--workers",
        type=_count(1),
        metavar="N",
        help="worker processes of the local cluster (default: one per CPU)",
    )
    p.add_argument(
        "--threshold",
        type=_positive,
        default=THRESHOLD,
        metavar="Z",
        help=f"robust z-score beyond which a unit is an outlier (default {THRESHOLD:g})",
    )
    p.add_argument(
        "--refresh", action="store_true", help="analyse every unit again, ignoring the cache"
    )
    p.add_argument("--no-report", action="store_true", help="write no HTML report")
    p.add_argument("--json", action="store_true", help="print exactly one JSON object on stdout")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    ana = p.add_argument_group("how each log is read and judged (as in gearsim fit)")
    ana.add_argument(
        "--column",
        action="append",
        default=[],
        metavar="CANONICAL=SOURCE[*FACTOR]",
        help="read a canonical column from another header name (repeatable)",
    )
    ana.add_argument("--resample", action="store_true", help="interpolate non-uniform sampling")
    ana.add_argument("--max-gap", type=_count(0), default=10, metavar="N", help="with --resample")
    ana.add_argument("--input-filter", default="auto", metavar="auto|none|HZ")
    ana.add_argument("--no-validation", action="store_true")
    ana.add_argument("--validation-fraction", type=_fraction, default=0.3, metavar="F")
    ana.add_argument("--max-samples", type=_count(1), metavar="N")


def _effects(items: list[str]) -> tuple[str, ...]:
    return tuple(e.strip() for item in items for e in item.split(",") if e.strip())


def _progress(quiet: bool):
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        if not quiet:
            sys.stderr.write(f"[{time.perf_counter() - t0:7.1f} s] {msg}\n")
            sys.stderr.flush()

    return say


def _print(res) -> None:
    c = res.counts
    print(
        f"fleet: {c['units']} units, {c['ok']} analysed, {c['errors']} with errors "
        f"({c['cached']} from the cache, {c['computed']} analysed now) in {res.seconds:.1f} s"
    )
    thr = res.population.get("threshold")
    if res.population.get("note"):
        print(res.population["note"])
    else:
        print(f"outliers (robust |z| > {thr:g}): {len(res.outliers)}")
        for o in res.outliers:
            by = "remaining error (nrmse after)" if o["by"] == "nrmse_after" else o["by"]
            print(f"  {o['unit']:24s} by {by:34s} z = {o['z']:+.1f}")
    for name, d in (res.population.get("drift") or {}).items():
        if isinstance(d, dict) and d.get("drifting"):
            print(
                f"drifts: {name}: {d['slope_per_day']:+.4g} per day "
                f"({d['change_sigmas']:+.1f} sigma over the span)"
            )
    for unit, err in res.errors[:10]:
        print(f"error: {unit}: {err}")
    if len(res.errors) > 10:
        print(f"... and {len(res.errors) - 10} more errors (units.parquet, status = 'error')")
    print(f"wrote {res.parquet}, {res.population_file}" + (f", {res.report}" if res.report else ""))


def _run(args: argparse.Namespace) -> int:
    from .run import FleetOptions, run_fleet
    from .units import FleetInputError

    if (args.source is None) == (args.manifest is None):
        raise FleetInputError(
            "give the logs: a directory or glob, or --manifest UNITS.csv (one of them)"
        )
    effects = _effects(args.add)
    if not effects and not args.diagnose:
        raise FleetInputError("say what to fit: --add EFFECT[,EFFECT...] or --diagnose")
    opts = FleetOptions(
        effects=effects,
        diagnose=args.diagnose,
        rounds=args.rounds,
        validation=not args.no_validation,
        validation_fraction=args.validation_fraction,
        input_filter=args.input_filter,
        columns=tuple(args.column),
        resample=args.resample,
        max_gap=args.max_gap,
        max_samples=args.max_samples,
    )
    res = run_fleet(
        args.source,
        manifest=args.manifest,
        model=args.model,
        out=args.out,
        options=opts,
        scheduler=args.scheduler,
        workers=args.workers,
        threshold=args.threshold,
        refresh=args.refresh,
        report=not args.no_report,
        progress=_progress(args.quiet),
        quiet=args.quiet,
    )
    if args.json:
        sys.stdout.write(json.dumps(res.to_json(), allow_nan=False) + "\n")
    else:
        _print(res)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    from ..cli import add_command

    add_command(
        subparsers,
        "fleet",
        "analyse every log of a fleet on Dask: one Parquet row per unit, outliers, drift",
        _configure,
        _run,
        requires=REQUIRES,
    )

"""Run the analysis over a fleet of logs on Dask and collect the results.

:func:`run_fleet` is the whole job: find the units, check every input and
output before any work, hash the logs, take what the cache already has,
send one task per remaining log to the cluster (a local one by default, or
the scheduler at an address), keep each result in the cache as it arrives,
then compute the population and write the Parquet file, population.json
and the HTML report.

Tasks go out in a bounded window (a few per worker thread): the client
never holds more than that many futures, and results go to the cache as
they arrive, so memory stays bounded however many logs there are. A worker
that dies takes only its task with it: the scheduler gives the task to
another worker (Dask's own rescheduling, up to its allowed-failures, 3 by
default); a task that fails even then becomes a row with error_kind
"lost", and the run goes on.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import math
import os
import sys
import time
import uuid
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from .._outputs import OutputPathError, atomic_write_text, check_output, printable
from .cache import CACHEABLE_KINDS, Cache, cache_key
from .population import THRESHOLD, Sample, population
from .task import analyse_unit, code_id, parse_input_filter, tool_version
from .units import FleetInputError, Unit, content_hash, find_units

__all__ = [
    "FleetOptions",
    "FleetResult",
    "run_fleet",
    "PARQUET",
    "POPULATION",
    "REPORT",
    "CACHE",
    "OVERLAYS",
    "CONNECT_TIMEOUT_S",
]

PARQUET = "units.parquet"
POPULATION = "population.json"
REPORT = "fleet.html"
CACHE = "cache.sqlite"
#: the directory of the per-unit overlay pages of the report
OVERLAYS = "units"
CONNECT_TIMEOUT_S = 15.0
#: tasks in flight per worker thread
WINDOW_PER_THREAD = 4


class FleetClusterError(RuntimeError):
    """The cluster went away during the run (exit 1); what finished is cached."""


@dataclass(frozen=True)
class FleetOptions:
    """What every unit is analysed with (part of the cache key).

    effects: fitted in this order, each on the model the previous left;
    diagnose: the full rounds of diagnose -> add the best effect instead
    (at most `rounds`); the other fields are those of ``gearsim fit``."""

    effects: tuple[str, ...] = ()
    diagnose: bool = False
    rounds: int = 3
    validation: bool = True
    validation_fraction: float = 0.3
    input_filter: Any = "auto"
    columns: tuple[str, ...] = ()
    resample: bool = False
    max_gap: int = 10
    max_samples: int | None = None

    def task_options(self) -> dict[str, Any]:
        return {
            "mode": "diagnose" if self.diagnose else "fit",
            "effects": [] if self.diagnose else list(self.effects),
            "rounds": int(self.rounds) if self.diagnose else 0,
            "validation": bool(self.validation),
            "validation_fraction": float(self.validation_fraction),
            "input_filter": parse_input_filter(self.input_filter),
            "columns": list(self.columns),
            "resample": bool(self.resample),
            "max_gap": int(self.max_gap),
            "max_samples": self.max_samples,
        }


@dataclass
class FleetResult:
    """What a run wrote and found. counts: units, ok, errors, cached (taken
    from the cache), computed (analysed in this run), lost (tasks the
    cluster could not run); outliers: the population's outlier entries."""

    out: str
    parquet: str
    population_file: str
    report: str | None
    population: dict[str, Any]
    counts: dict[str, int]
    outliers: list[dict[str, Any]]
    dashboard: str | None = None
    seconds: float = 0.0
    errors: list[tuple[str, str]] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        pop = {k: v for k, v in self.population.items() if k != "z"}
        return {
            "out": self.out,
            "parquet": self.parquet,
            "population": self.population_file,
            "report": self.report,
            **self.counts,
            "outliers": [{"unit": o["unit"], "by": o["by"], "z": o["z"]} for o in self.outliers],
            "threshold": pop.get("threshold"),
            "drifting": [
                k
                for k, v in (pop.get("drift") or {}).items()
                if isinstance(v, dict) and v.get("drifting")
            ],
            "error_units": [{"unit": u, "error": e} for u, e in self.errors[:100]],
            "dashboard": self.dashboard,
            "seconds": self.seconds,
        }


# ------------------------------------------------------------------ checks


def _load_model(model: Any):
    from ..analysis import AnalysisModel, load_model
    from ..errors import ModelFileError

    if isinstance(model, str | os.PathLike):
        path = os.fspath(model)
        if not os.path.exists(path):
            raise ModelFileError("no such file", file=printable(path, limit=200))
        return load_model(path), path
    return AnalysisModel.of(model), None


def _check_effects(effects: Sequence[str], model: Any) -> None:
    """Unknown, inapplicable, repeated effects: exit 2 before any work."""
    from ..analysis.effects import get_effect

    seen = set()
    for e in effects:
        if e in seen:
            raise FleetInputError(f"--add {printable(e)}: named twice")
        seen.add(e)
        get_effect(e, model)  # EffectError: unknown, not for this rig, already in the model


def _check_out(out: str, inputs: Sequence[str]) -> str:
    """--out: a directory (created), never one that holds an input."""
    out = check_output(out, [], option="--out", directory=True)
    root = os.path.realpath(out)
    for p in inputs:
        if p is None:
            continue
        real = os.path.realpath(p)
        if real == root or real.startswith(root.rstrip(os.sep) + os.sep):
            raise OutputPathError(
                f"--out {printable(out)}: holds an input of this run ({printable(p)}); "
                "the fleet's outputs never go among its inputs, choose another directory",
                parameter="--out",
            )
    for name in (PARQUET, POPULATION, REPORT, CACHE):
        target = os.path.join(out, name)
        if os.path.isdir(target):
            raise OutputPathError(
                f"--out {printable(out)}: {name} in it is a directory", parameter="--out"
            )
    return out


# ------------------------------------------------------------------ cluster


def _check_scheduler(address: str) -> None:
    """A tcp:// scheduler that does not answer: exit 2 before any work
    (other protocols are left to Dask's own connect)."""
    import socket
    from urllib.parse import urlsplit

    if not address.startswith("tcp://"):
        return
    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port or 8786
    except ValueError:
        raise FleetInputError(
            f"--scheduler {printable(address)}: not an address tcp://HOST:PORT"
        ) from None
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise FleetInputError(
            f"--scheduler {printable(address)}: cannot connect ({exc.strerror or exc})"
        ) from None


def _client(scheduler: str | None, workers: int | None):
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise FleetInputError(
                f"--scheduler {printable(scheduler)}: cannot connect within "
                f"{CONNECT_TIMEOUT_S:g} s ({type(exc).__name__}: {printable(exc, 200)})"
            ) from None
        return client, None
    n = workers or os.cpu_count() or 1
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",  # any free port: several runs may share a machine
        silence_logs=logging.CRITICAL,  # a worker's shutdown chatter is not the user's
    )
    return Client(cluster, set_as_default=False), cluster


def _dashboard(client, local: bool) -> str | None:
    """The dashboard's link when it serves pages: the scheduler always
    reports an HTTP service, but the pages need bokeh where it runs."""
    try:
        if "dashboard" not in client.scheduler_info().get("services", {}):
            return None
        link = str(client.dashboard_link)
    except Exception:  # pragma: no cover - an old scheduler without the info
        return None
    if local:
        return link if importlib.util.find_spec("bokeh") is not None else None
    import urllib.request

    try:
        with urllib.request.urlopen(link, timeout=2.0) as reply:
            return link if reply.status == 200 else None
    except (OSError, ValueError):
        return None


class _Progress:
    """A tqdm bar on a terminal, else a line every PERIOD_S seconds."""

    PERIOD_S = 10.0

    def __init__(self, total: int, say: Callable[[str], None], quiet: bool) -> None:
        self.total, self.say, self.quiet = total, say, quiet
        self.done = self.errors = 0
        self.bar = None
        self.last = time.monotonic()
        if not quiet and total and sys.stderr.isatty() and importlib.util.find_spec("tqdm"):
            import shutil

            from tqdm import tqdm

            width = shutil.get_terminal_size((80, 24)).columns
            self.bar = tqdm(
                total=total,
                unit="unit",
                file=sys.stderr,
                ncols=min(width, 100) if width >= 40 else 80,
            )

    def update(self, ok: bool) -> None:
        self.done += 1
        self.errors += 0 if ok else 1
        if self.bar is not None:
            self.bar.update(1)
            self.bar.set_postfix(errors=self.errors, refresh=False)
        elif not self.quiet and (
            time.monotonic() - self.last >= self.PERIOD_S or self.done == self.total
        ):
            self.last = time.monotonic()
            self.say(f"fleet: {self.done}/{self.total} units analysed, {self.errors} with errors")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _lost_row(exc: BaseException | None, content: str | None) -> dict[str, Any]:
    name = type(exc).__name__ if exc is not None else "unknown"
    return {
        "status": "error",
        "error": f"the cluster could not run this unit ({name}: {printable(exc, 300)})",
        "error_kind": "lost",
        "content_hash": content,
        "tool_version": None,
        "code_id": None,
        "warnings": [],
        "effects_fitted": [],
        "effects_found": [],
        "parameters": {},
    }


@dataclass
class _Job:
    key: str | None
    task: dict[str, Any]
    units: list[Unit]


def _compute(
    jobs: list[_Job],
    cache: Cache,
    *,
    scheduler: str | None,
    workers: int | None,
    say: Callable[[str], None],
    quiet: bool,
    memory: dict[int, dict],
) -> tuple[str | None, int]:
    """Run the jobs on the cluster; rows go to the cache (or to `memory`,
    by unit index, when they are not cacheable). Returns the dashboard link
    and the number of rows computed by another installation than this
    client's (not cached)."""
    from distributed import as_completed

    mine = code_id()
    foreign = 0
    dist_log = logging.getLogger("distributed")
    level = dist_log.level
    dist_log.setLevel(logging.CRITICAL)  # a lost worker is handled, not an error of ours
    client, cluster = _client(scheduler, workers)
    progress = None
    try:
        dashboard = _dashboard(client, scheduler is None)
        threads = max(1, sum(client.nthreads().values()))
        if not quiet:
            where = scheduler or f"a local cluster of {threads} worker process(es)"
            say(f"fleet: {sum(len(j.units) for j in jobs)} units to analyse on {where}")
            if dashboard:
                say(f"fleet: Dask dashboard: {dashboard}")
        progress = _Progress(sum(len(j.units) for j in jobs), say, quiet)
        pending = deque(jobs)
        running: dict[str, _Job] = {}
        window = max(8, WINDOW_PER_THREAD * threads)
        run_id = uuid.uuid4().hex[:8]

        def submit():
            job = pending.popleft()
            name = f"gearsim-fleet-{run_id}-{job.units[0].index}"
            fut = client.submit(analyse_unit, job.task, key=name, pure=False)
            running[fut.key] = job
            return fut

        ac = as_completed([submit() for _ in range(min(window, len(pending)))], loop=client.loop)
        for fut in ac:
            job = running.pop(fut.key)
            if fut.status == "finished":
                row = fut.result()
            elif fut.status == "cancelled":
                raise FleetClusterError(
                    "the cluster cancelled the run (the scheduler went away?); what finished is "
                    "in the cache: run the same command again to go on"
                )
            else:
                row = _lost_row(fut.exception(), job.task.get("content_hash"))
            fut.release()
            if row.get("code_id") not in (None, mine):
                foreign += 1
            cacheable = (
                job.key is not None
                and row.get("error_kind") in CACHEABLE_KINDS
                and row.get("code_id") == mine
            )
            if cacheable:
                cache.put_many([(job.key, row)])
            else:
                for u in job.units:
                    memory[u.index] = row
            for _ in job.units:
                progress.update(row.get("status") == "ok")
            if pending:
                ac.add(submit())
        return dashboard, foreign
    finally:
        if progress is not None:
            progress.close()
        client.close()
        if cluster is not None:
            cluster.close()
        dist_log.setLevel(level)


# ------------------------------------------------------------------ the run


def run_fleet(
    source: str | None = None,
    *,
    manifest: str | None = None,
    model: Any,
    out: str,
    options: FleetOptions | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    threshold: float = THRESHOLD,
    refresh: bool = False,
    report: bool = True,
    progress: Callable[[str], None] | None = None,
    quiet: bool = False,
) -> FleetResult:
    """Analyse every log of a fleet and write OUT/units.parquet,
    OUT/population.json and OUT/fleet.html (module docstring).

    source: a directory or a glob; or manifest: a manifest CSV. model: a
    model file (or a gearsim.Model). options: what to fit (FleetOptions).
    scheduler: a Dask scheduler address (tcp://host:8786) instead of a
    local cluster of `workers` processes (default: one per CPU).
    refresh: analyse every unit again (the cache is still updated).
    Raises FleetInputError / OutputPathError / ModelFileError / EffectError
    on bad input, before any work."""
    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    opts = options or FleetOptions()
    if not opts.diagnose and not opts.effects:
        raise FleetInputError("name the effects to fit (--add EFFECT ...) or ask for --diagnose")
    if not (threshold > 0 and math.isfinite(threshold)):
        raise FleetInputError(f"--threshold must be a positive number, got {threshold!r}")
    units = find_units(source, manifest=manifest)
    start, model_file = _load_model(model)
    if not opts.diagnose:
        _check_effects(opts.effects, start)
    task_opts = opts.task_options()  # a bad --input-filter: exit 2 here
    from ..analysis.measurement import parse_column_map

    parse_column_map(task_opts["columns"])  # a bad --column: exit 2 here, not on every unit
    out = _check_out(out, [u.path for u in units] + [manifest, model_file])
    if scheduler:
        _check_scheduler(scheduler)
    os.makedirs(out, exist_ok=True)
    model_text = start.dumps()
    code = code_id()
    say(f"fleet: {len(units)} units; hashing the logs")
    keys: list[str | None] = []
    jobs_by_key: dict[str, _Job] = {}
    loose: list[_Job] = []
    for u in units:
        digest = content_hash(u.path)
        key = cache_key(digest, model_text, task_opts, code)
        keys.append(key)
        task = {
            "unit": u.unit,
            "path": os.path.abspath(u.path),
            "content_hash": digest,
            "model": model_text,
            "model_file": model_file,
            "options": task_opts,
        }
        if key is None:
            loose.append(_Job(None, task, [u]))
        elif key in jobs_by_key:
            jobs_by_key[key].units.append(u)
        else:
            jobs_by_key[key] = _Job(key, task, [u])
    cache = Cache(os.path.join(out, CACHE))
    try:
        have = set() if refresh else cache.keys_present(jobs_by_key)
        jobs = [j for k, j in jobs_by_key.items() if k not in have] + loose
        cached_units = sum(len(j.units) for k, j in jobs_by_key.items() if k in have)
        memory: dict[int, dict] = {}
        dashboard = None
        if jobs:
            if cached_units:
                say(f"fleet: {cached_units} units from the cache")
            dashboard, foreign = _compute(
                jobs,
                cache,
                scheduler=scheduler,
                workers=workers,
                say=say,
                quiet=quiet,
                memory=memory,
            )
            if foreign:
                say(
                    f"fleet: warning: {foreign} units were analysed by another gearsim "
                    f"installation than this client's ({code}); their rows are not cached"
                )
        else:
            say(f"fleet: every unit is in the cache ({len(units)})")
        computed = {u.index for j in jobs for u in j.units}

        def rows():
            for u, key in zip(units, keys, strict=True):
                row = memory.get(u.index)
                if row is None and key is not None:
                    row = cache.get(key)
                if row is None:  # pragma: no cover - a row lost between put and get
                    row = _lost_row(None, None)
                row = dict(row)
                row["from_cache"] = u.index not in computed
                row["mode"] = task_opts["mode"]
                yield u, row

        result = _finish(
            out, units, rows, start, model_file, task_opts, threshold, report, say, cached_units
        )
        result.dashboard = dashboard
        result.seconds = time.perf_counter() - t0
        return result
    finally:
        cache.close()


def _finish(out, units, rows, start, model_file, task_opts, threshold, report, say, cached_units):
    """Population, Parquet, population.json, report."""
    from ..analysis import RIG_SPECS
    from .table import write_parquet

    samples: list[Sample] = []
    units_of: dict[str, str] = {}
    params: set[str] = set()
    counts = {"units": len(units), "ok": 0, "errors": 0, "lost": 0}
    errors: list[tuple[str, str]] = []
    for u, row in rows():
        if row.get("status") == "ok":
            counts["ok"] += 1
            values = {}
            for name, p in (row.get("parameters") or {}).items():
                values[name] = p["value"]
                units_of.setdefault(name, p.get("unit") or "")
                params.add(name)
            samples.append(
                Sample(
                    u.unit,
                    values,
                    float(row["nrmse_after"]),
                    u.timestamp,
                    {"nrmse_before": row.get("nrmse_before"), "index": u.index},
                )
            )
        else:
            counts["errors"] += 1
            counts["lost"] += row.get("error_kind") == "lost"
            errors.append((u.unit, str(row.get("error"))))
    counts["cached"] = cached_units
    counts["computed"] = len(units) - cached_units
    pop = population(samples, units_of, threshold)
    outliers = {o["unit"]: o for o in pop["outliers"]}
    outputs = list(RIG_SPECS[start.block].outputs)
    param_names = sorted(params)
    aware = any(u.timestamp is not None and u.timestamp.tzinfo is not None for u in units)
    meta = {
        "model_file": model_file,
        "options": task_opts,
        "threshold": threshold,
        "tool_version": tool_version(),
        "code_id": code_id(),
        "outputs": outputs,
        "parameter_units": {p: units_of.get(p, "") for p in param_names},
    }
    parquet = os.path.join(out, PARQUET)
    write_parquet(
        parquet,
        rows(),
        outputs=outputs,
        params=param_names,
        aware=aware,
        outliers=outliers,
        meta=meta,
    )
    say(f"fleet: wrote {printable(parquet, limit=200)}")
    pop_file = os.path.join(out, POPULATION)
    saved = {k: v for k, v in pop.items() if k != "z"}
    saved.update({"counts": counts, "model_file": model_file, "options": task_opts})
    atomic_write_text(pop_file, json.dumps(_json_safe(saved), indent=1, allow_nan=False) + "\n")
    html = None
    if report:
        from .report import write_fleet_report

        html = write_fleet_report(
            out,
            samples=samples,
            pop=pop,
            units=units,
            rows=rows,
            start=start,
            options=task_opts,
            counts=counts,
            errors=errors,
            say=say,
        )
    return FleetResult(out, parquet, pop_file, html, pop, counts, pop["outliers"], errors=errors)


def _json_safe(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    return obj

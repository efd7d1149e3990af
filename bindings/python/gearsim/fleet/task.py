"""One unit of the fleet: what a Dask worker runs (:func:`analyse_unit`).

compare -> fit -> compare with the analysis' public functions
(gearsim.analysis: load_measurement, prepare_inputs, compare, fit; and
gearsim.analysis.report.run_rounds for the full diagnose rounds), on the log
the task names. The task is a plain dict and so is the row it returns, so a
worker needs nothing but the installed gearsim package. The row never
raises: a log that cannot be analysed becomes a row with status "error" and
one line saying why; the other units run on.

error_kind says whose the problem is: "input" (the log or the model for it:
a bad column, a truncated or binary file, a model that does not fit the
rig's columns, an effect the model cannot take), "analysis" (the analysis
could not finish on this log) or "internal" (a bug, or a worker out of
memory). Rows with "input" or "analysis" are cached like results (the same
file gives the same error); "internal" ones are tried again on the next run.
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import socket
import time
import warnings
from typing import Any

__all__ = ["analyse_unit", "code_id", "tool_version", "parse_input_filter"]


def tool_version() -> str:
    from .. import __version__

    return __version__


@functools.cache
def code_id() -> str:
    """The version plus a digest of the package's Python sources and its
    compiled core: two installations with the same code_id compute the same
    rows. Part of the cache key, so an edited source (an editable install)
    does not reuse rows of the old code."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    h = hashlib.sha256()
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith((".", "__pycache__")))
        for name in sorted(filenames):
            if name.endswith(".py") or name.startswith("_gearsim"):
                path = os.path.join(dirpath, name)
                h.update(os.path.relpath(path, root).encode())
                with open(path, "rb") as fh:
                    h.update(hashlib.sha256(fh.read()).digest())
    return f"{tool_version()}+{h.hexdigest()[:12]}"


def parse_input_filter(value: Any) -> float | str | None:
    """--input-filter as the analysis takes it: "auto", None, or Hz > 0."""
    from ..analysis.errors import MeasurementError

    if value is None:
        return None
    if isinstance(value, int | float) and not isinstance(value, bool):
        hz = float(value)
    else:
        v = str(value).strip().lower()
        if v == "auto":
            return "auto"
        if v in ("none", "off", "0"):
            return None
        try:
            hz = float(v)
        except ValueError:
            raise MeasurementError(
                f"--input-filter must be auto, none or a frequency in Hz, got '{value}'"
            ) from None
    if not (hz > 0 and math.isfinite(hz)):
        raise MeasurementError(f"--input-filter must be a positive frequency in Hz, got '{value}'")
    return hz


def _one_line(exc: BaseException) -> str:
    from .._outputs import one_line

    text = one_line(exc)
    from ..errors import GearsimError

    if isinstance(exc, GearsimError):
        return text
    return f"{type(exc).__name__}: {text}"


def _kind(exc: BaseException) -> str:
    from ..errors import GearsimError

    if isinstance(exc, GearsimError) and isinstance(exc, ValueError):
        return "input"
    if isinstance(exc, GearsimError):
        return "analysis"
    return "internal"


def _fit_parameters(params: dict[str, dict], fitted: list[dict]) -> None:
    """Record a fit's parameters; a later fit re-estimating one replaces it
    (it was fitted jointly with more of the model)."""
    for f in fitted:
        role = f["role"]
        if f["name"] in params and params[f["name"]]["role"] == "effect":
            role = "effect"
        params[f["name"]] = {
            "value": float(f["value"]),
            "std": None if f["std"] is None else float(f["std"]),
            "unit": f.get("unit") or "",
            "role": role,
        }


def _warning_lines(effect: str | None, warns: list[dict]) -> list[str]:
    return [f"{effect}: {w['text']}" if effect else str(w["text"]) for w in warns]


def _fixed_effects(model, meas, inputs, opts: dict, row: dict) -> Any:
    """Fit each effect of the list in turn, each on the model the previous
    one left (the last fit re-estimates most of what came before)."""
    from ..analysis import fit
    from ..analysis.scoring import HELP_MARGIN

    params: dict[str, dict] = {}
    found: list[str] = []
    first = None
    last = None
    for effect in opts["effects"]:
        r = fit(
            model,
            meas,
            effect,
            inputs,
            max_samples=opts.get("max_samples"),
            validation=opts["validation"],
            validation_fraction=opts["validation_fraction"],
        )
        first = first or r
        last = r
        model = r.model
        _fit_parameters(params, r.fitted)
        row["warnings"] += _warning_lines(effect, r.warnings)
        negligible = any(w.get("kind") == "negligible" for w in r.warnings)
        if not negligible and r.validation_nrmse_after <= (1 - HELP_MARGIN) * (
            r.validation_nrmse_before
        ):
            found.append(effect)
    row["effects_fitted"] = list(opts["effects"])
    row["effects_found"] = found
    row["parameters"] = params
    if first is not None:
        row["validation_nrmse_before"] = float(first.validation_nrmse_before)
        row["validation_nrmse_after"] = float(last.validation_nrmse_after)
    return model


def _diagnose_rounds(model, meas, opts: dict, row: dict) -> Any:
    from ..analysis.report import run_rounds

    rounds = run_rounds(
        model,
        meas,
        rounds=opts["rounds"],
        input_filter=opts["input_filter"],
        validation=opts["validation"],
        validation_fraction=opts["validation_fraction"],
    )
    params: dict[str, dict] = {}
    for r in rounds[1:]:
        _fit_parameters(params, r.fit.fitted)
        row["warnings"] += _warning_lines(r.effect, r.fit.warnings)
    last = rounds[-1].diagnosis
    if last is not None:
        row["warnings"] += _warning_lines(None, last.warnings)
        row["conclusion"] = last.conclusion
    row["effects_fitted"] = [r.effect for r in rounds[1:]]
    row["effects_found"] = [r.effect for r in rounds[1:]]
    row["parameters"] = params
    row["validation_nrmse_before"] = float(rounds[0].validation_nrmse)
    row["validation_nrmse_after"] = float(rounds[-1].validation_nrmse)
    return rounds[-1].model


def _analyse(task: dict, row: dict) -> None:
    from ..analysis import AnalysisModel, compare, load_measurement, prepare_inputs
    from ..analysis.errors import MeasurementError
    from ..analysis.measurement import parse_column_map

    opts = task["options"]
    path = task["path"]
    if not os.path.exists(path):
        raise MeasurementError("no such file", file=path)
    got = _file_hash(path)
    if task.get("content_hash") and got != task["content_hash"]:
        raise MeasurementError(
            "the file changed since the run started (its content hash differs); run again",
            file=path,
        )
    row["content_hash"] = got
    model = AnalysisModel.loads(task["model"], file=task.get("model_file"))
    notes: list[str] = []
    meas = load_measurement(
        path,
        model.block,
        columns=parse_column_map(opts.get("columns") or []),
        resample=opts.get("resample", False),
        max_gap=opts.get("max_gap"),
        note=notes.append,
    )
    row["warnings"] += [n if n.startswith("warning:") else f"note: {n}" for n in notes]
    filt = opts["input_filter"]
    if isinstance(filt, float) and filt >= 0.5 / meas.dt:
        raise MeasurementError(
            f"--input-filter {filt:g} Hz is at or above the Nyquist frequency "
            f"{0.5 / meas.dt:.6g} Hz of the log (0.5/dt): it would filter nothing",
            file=path,
        )
    row["samples"] = int(meas.n)
    row["dt"] = float(meas.dt)
    inputs = prepare_inputs(meas, filt)
    before = compare(model, meas, inputs)
    row["nrmse_before"] = float(before.nrmse)
    row["outputs_before"] = {o: float(m.nrmse) for o, m in before.outputs.items()}
    if opts["mode"] == "diagnose":
        final = _diagnose_rounds(model, meas, opts, row)
    else:
        final = _fixed_effects(model, meas, inputs, opts, row)
    after = compare(final, meas, inputs)
    row["nrmse_after"] = float(after.nrmse)
    row["outputs_after"] = {o: float(m.nrmse) for o, m in after.outputs.items()}
    row["model"] = final.dumps()
    row["status"] = "ok"


def _file_hash(path: str) -> str:
    from .units import content_hash

    got = content_hash(path)
    if got is None:
        from ..analysis.errors import MeasurementError

        raise MeasurementError("cannot read the file", file=path)
    return got


def analyse_unit(task: dict) -> dict:
    """The row of one unit (module docstring); never raises for a bad log.

    task: {"unit", "path", "content_hash", "model" (TOML text), "model_file",
    "options": {"mode": "fit"|"diagnose", "effects", "rounds",
    "validation", "validation_fraction", "input_filter", "columns",
    "resample", "max_gap", "max_samples"}}."""
    t0 = time.perf_counter()
    c0 = time.process_time()
    row: dict[str, Any] = {
        "status": "error",
        "error": None,
        "error_kind": None,
        "content_hash": task.get("content_hash"),
        "tool_version": tool_version(),
        "code_id": code_id(),
        "worker": f"{socket.gethostname()}:{os.getpid()}",
        "warnings": [],
        "effects_fitted": [],
        "effects_found": [],
        "parameters": {},
    }
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _analyse(task, row)
        for w in caught:
            text = f"warning: {w.category.__name__}: {w.message}"
            if text not in row["warnings"]:
                row["warnings"].append(text)
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # a bad log must not stop the fleet
        if isinstance(exc, SystemExit):
            exc = RuntimeError(f"exit {exc.code}")
        row["status"] = "error"
        row["error"] = _one_line(exc)
        row["error_kind"] = "internal" if isinstance(exc, MemoryError) else _kind(exc)
    row["seconds"] = time.perf_counter() - t0
    row["cpu_seconds"] = time.process_time() - c0
    return row

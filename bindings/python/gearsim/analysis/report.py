"""report: rounds of compare -> diagnose -> fit, drawn into PNG files and one
self-contained HTML page (images embedded as base64; matplotlib, Agg backend).

Figures:
- ``overlay.png``: measured vs simulated, per output, first and last round;
- ``residual.png``: the residual over time, per output, with the failing
  regimes of the first round shaded;
- ``residual_vs.png``: the drive-torque residual against speed and against
  load, first and last round (the signature plots a person checks);
- ``regimes.png``: error per regime, first and last round, with the failing
  threshold;
- ``error_fall.png``: nrmse on the estimation and on the validation blocks
  after each round of adding an effect;
- ``signatures.png``: the signature plot of each effect class that draws one
  (Effect.plot: the transient after reversals, residual against speed or
  angle, the residual/derivative cross-correlation against lag), for the
  effects that were added (labelled with the round that added them) and,
  labelled "not added", those a diagnosis found helpful or listed among its
  first candidates, drawn on the residual of the round that diagnosed them.
"""

from __future__ import annotations

import base64
import html
import io
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._outputs import OutputPathError, atomic_write_bytes, atomic_write_text, printable
from . import scoring
from .compare import CompareResult, compare
from .diagnose import DiagnoseResult, diagnose
from .fitting import REFIT, FitResult, fit_effect, refit_effects, validation_nrmse
from .measurement import Measurement
from .regimes import FAILING_RATIO
from .signatures import build_context
from .simulate import prepare_inputs
from .threads import single_blas_thread

__all__ = ["Round", "run_rounds", "write_report", "FIGURES"]

FIGURES = ("overlay", "residual", "residual_vs", "regimes", "error_fall", "signatures")
#: a diagnosis's first SHOWN_CANDIDATES candidates get their signature plot
SHOWN_CANDIDATES = 3
MAX_POINTS = 20_000


@dataclass
class Round:
    """One round: the model, the effect added to reach it (None for the
    starting model), its comparison, its errors on the estimation and the
    validation blocks, the diagnosis of this model (which chose the next
    effect, or concluded that nothing helps) and the fit that reached it."""

    model: Any
    effect: str | None
    compare: CompareResult
    estimation_nrmse: float
    validation_nrmse: float
    diagnosis: DiagnoseResult | None = None
    fit: FitResult | None = None


def _round(model: Any, effect: str | None, cur: CompareResult, split, fit=None) -> Round:
    sim = cur.sim.outputs
    return Round(
        model,
        effect,
        cur,
        validation_nrmse(cur.meas, sim, split.estimation),
        validation_nrmse(cur.meas, sim, split.validation),
        None,
        fit,
    )


def _full_fit(d: DiagnoseResult, split, say: Callable[[str], None]) -> FitResult:
    """The accepted candidate's fit: diagnose's own when it fitted every
    parameter at full resolution, else a full fit on the same split (kept
    unless its validation error ends above diagnose's)."""
    best = d.best
    if best is None:
        raise ValueError("diagnose has no candidate to fit")
    if best.fit is not None and best.fit.complete:
        return best.fit
    full = fit_effect(d.context, best.effect, validation=split, progress=say)
    if best.fit is None or full.validation_nrmse_after <= best.fit.validation_nrmse_after:
        return full
    return best.fit  # the full search ended worse than the ranking fit (a local minimum)


@single_blas_thread
def run_rounds(
    model: Any,
    meas: Measurement,
    rounds: int = 3,
    *,
    input_filter: Any = "auto",
    validation: bool = True,
    validation_fraction: float = scoring.DEFAULT_FRACTION,
    progress: Callable[[str], None] | None = None,
) -> list[Round]:
    """Start from model; each round diagnoses and adds the best candidate
    when it helps (gearsim.analysis.scoring.helps, the rule diagnose reports
    with), then compares again. Stops when nothing helps or after `rounds`
    rounds. The last diagnosed model's diagnosis is kept on its round: its
    conclusion says why the rounds stopped. When two effects or more were
    added, a final round re-fits them all together
    (gearsim.analysis.fitting.refit_effects; each was fitted with the ones
    before it, the later ones absent) and is kept when it lowers both the
    validation error and the whole record's (effect REFIT)."""
    say = progress or (lambda s: None)
    inputs = prepare_inputs(meas, input_filter)
    split = scoring.split_record(meas.n, validation, validation_fraction)
    cur = compare(model, meas, inputs)
    out = [_round(model, None, cur, split)]
    say(f"round 0: nrmse {cur.nrmse:.4f}, validation nrmse {out[0].validation_nrmse:.4f}")
    for k in range(1, rounds + 1):
        d = diagnose(
            out[-1].model,
            meas,
            inputs,
            validation=validation,
            validation_fraction=validation_fraction,
            progress=say,
        )
        out[-1].diagnosis = d
        if not d.best_helps:
            say(f"round {k}: {d.conclusion} - stopping")
            break
        fr = _full_fit(d, split, say)
        cur = compare(fr.model, meas, inputs)
        out.append(_round(fr.model, fr.effect, cur, split, fr))
        say(
            f"round {k}: + {fr.effect}: validation nrmse {out[-2].validation_nrmse:.4f} -> "
            f"{out[-1].validation_nrmse:.4f}"
        )
    if len(out) >= 3:
        last = out[-1].compare
        ctx = build_context(last.model, meas, inputs, last.sim, last.regime_masks)
        rf = refit_effects(ctx, validation=split, progress=say)
        say(f"final round: {rf.verdict}")
        if rf.accepted:
            out.append(_round(rf.model, REFIT, compare(rf.model, meas, inputs), split, rf))
    return out


def conclusion(rounds: list[Round]) -> str | None:
    """The conclusion of the last diagnosis of the rounds (why they stopped)."""
    for r in reversed(rounds):
        if r.diagnosis is not None:
            return r.diagnosis.conclusion
    return None


# ---------------------------------------------------------------- drawing


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _stride(n: int) -> int:
    return max(1, int(np.ceil(n / MAX_POINTS)))


def _spans(mask: np.ndarray) -> list[tuple[int, int]]:
    if not mask.any():
        return []
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts = np.nonzero(d == 1)[0]
    ends = np.nonzero(d == -1)[0]
    return list(zip(starts, ends, strict=True))


_COLORS = ["#d62728", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#bcbd22", "#17becf"]


def _time_axes(plt, meas: Measurement):
    """A figure with one row per output over time; the decimation stride and
    the decimated time axis."""
    outs = meas.spec.outputs
    fig, axes = plt.subplots(
        len(outs), 1, figsize=(11, 3.2 * len(outs)), sharex=True, squeeze=False
    )
    axes[-1, 0].set_xlabel("time [s]")
    s = _stride(meas.n)
    return fig, axes, s, meas.time[::s]


def _fig_overlay(plt, meas: Measurement, rounds: list[Round]):
    fig, axes, s, t = _time_axes(plt, meas)
    for ax, o in zip(axes[:, 0], meas.spec.outputs, strict=True):
        ax.plot(t, meas[o][::s], color="0.55", lw=0.8, label="measured")
        first = rounds[0].compare.sim.outputs[o][::s]
        ax.plot(
            t,
            first,
            color="#1f77b4",
            lw=0.9,
            ls="--" if len(rounds) > 1 else "-",
            label="simulated, starting model",
        )
        if len(rounds) > 1:
            ax.plot(
                t,
                rounds[-1].compare.sim.outputs[o][::s],
                color="#2ca02c",
                lw=0.9,
                label=f"simulated, after round {len(rounds) - 1}",
            )
        ax.set_ylabel(f"{o} [{meas.spec.unit(o)}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle("measured vs simulated (open loop)")
    fig.tight_layout()
    return fig


def _fig_residual(plt, meas: Measurement, rounds: list[Round]):
    fig, axes, s, t = _time_axes(plt, meas)
    base = rounds[0].compare
    failing = [r["regime"] for r in base.failing_regimes]
    masks = {r.name: r.mask for r in base.regime_masks}
    # the spans of each shaded regime, found once for all the axes
    shaded = [(name, _spans(masks[name])) for name in failing[:4]]
    for ax, o in zip(axes[:, 0], meas.spec.outputs, strict=True):
        for i, (name, spans) in enumerate(shaded):
            for j, (a, b) in enumerate(spans):
                ax.axvspan(
                    meas.time[a],
                    meas.time[min(b, meas.n - 1)],
                    color=_COLORS[i % len(_COLORS)],
                    alpha=0.18,
                    lw=0,
                    label=name if j == 0 else None,
                )
        ax.plot(
            t, (meas[o] - base.sim.outputs[o])[::s], color="#1f77b4", lw=0.6, label="starting model"
        )
        if len(rounds) > 1:
            last = rounds[-1].compare
            ax.plot(
                t,
                (meas[o] - last.sim.outputs[o])[::s],
                color="#2ca02c",
                lw=0.6,
                label=f"after round {len(rounds) - 1}",
            )
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel(f"residual {o} [{meas.spec.unit(o)}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    title = "residual (measured - simulated)"
    if failing:
        title += "; shaded: failing regimes of the starting model"
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def _fig_residual_vs(plt, meas: Measurement, rounds: list[Round]):
    spec = meas.spec
    o = spec.torque_output
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), squeeze=False)
    s = _stride(meas.n)
    x_speed = rounds[0].compare.inputs.base_speed[::s]
    x_load = meas[spec.torque_output][::s]
    for ax, x, label in (
        (axes[0, 0], x_speed, f"{spec.speed_input} [{spec.speed_unit}]"),
        (axes[0, 1], x_load, f"measured {spec.torque_output} [{spec.torque_unit}]"),
    ):
        r0 = (meas[o] - rounds[0].compare.sim.outputs[o])[::s]
        ax.scatter(x, r0, s=2, alpha=0.35, color="#1f77b4", label="starting model", rasterized=True)
        if len(rounds) > 1:
            r1 = (meas[o] - rounds[-1].compare.sim.outputs[o])[::s]
            ax.scatter(
                x,
                r1,
                s=2,
                alpha=0.35,
                color="#2ca02c",
                label=f"after round {len(rounds) - 1}",
                rasterized=True,
            )
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlabel(label)
        ax.set_ylabel(f"residual {o} [{spec.torque_unit}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=8, markerscale=4)
    fig.suptitle(
        "residual signatures: a step at zero speed = Coulomb, a slope with speed = viscous, "
        "a fan with torque = efficiency",
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def _fig_regimes(plt, meas: Measurement, rounds: list[Round]):
    o = meas.spec.torque_output
    regs = rounds[0].compare.regimes
    names = [r["regime"] for r in regs]
    fig, ax = plt.subplots(figsize=(11, 3.8))
    x = np.arange(len(names))
    first = [r["outputs"][o]["nrmse"] for r in regs]
    ax.bar(x - 0.2, first, 0.4, label="starting model", color="#1f77b4")
    if len(rounds) > 1:
        last = [r["outputs"][o]["nrmse"] for r in rounds[-1].compare.regimes]
        ax.bar(x + 0.2, last, 0.4, label=f"after round {len(rounds) - 1}", color="#2ca02c")
    for i, r in enumerate(regs):
        if r["failing"]:
            ax.annotate(
                "fails",
                (x[i] - 0.2, first[i]),
                ha="center",
                va="bottom",
                fontsize=8,
                color="#d62728",
            )
    overall = rounds[0].compare.outputs[o].nrmse
    ax.axhline(overall, color="#1f77b4", ls=":", lw=1, label="overall, starting model")
    ax.axhline(
        FAILING_RATIO * overall,
        color="#d62728",
        ls="--",
        lw=1,
        label=f"fails above {FAILING_RATIO:g}x overall (starting model)",
    )
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(f"{o}: rms residual / std")
    ax.set_title("error by operating regime")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _fig_error_fall(plt, meas: Measurement, rounds: list[Round]):
    fig, ax = plt.subplots(figsize=(8, 3.8))
    labels = ["starting model"] + [f"+ {r.effect}" for r in rounds[1:]]
    x = np.arange(len(rounds))
    curves = (
        ("estimation blocks", [r.estimation_nrmse for r in rounds], "#1f77b4", "o"),
        ("validation blocks (held out)", [r.validation_nrmse for r in rounds], "#d62728", "s"),
    )
    for label, vals, color, marker in curves:
        ax.plot(x, vals, color=color, marker=marker, label=label)
        for i, v in enumerate(vals):
            ax.annotate(f"{v:.3f}", (x[i], v), ha="center", va="bottom", fontsize=8, color=color)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=15, ha="right", fontsize=9)
    ax.set_ylabel("nrmse (mean over outputs)")
    ax.set_ylim(bottom=0)
    ax.set_title("error fall across rounds of adding effects")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _signature_cases(rounds: list[Round]) -> list[tuple[Any, Any, str]]:
    """(effect, context, label) of each effect to draw: every effect added
    (drawn on the residual of the round that diagnosed it, labelled with the
    round that added it), then those a diagnosis found helpful or listed
    among its first candidates without adding them (labelled "not added")."""
    from .effects import EFFECTS

    added_in = {r.effect: k for k, r in enumerate(rounds) if r.effect}
    cases: dict[str, Any] = {}
    for r in rounds:
        d = r.diagnosis
        if d is None:
            continue
        for i, c in enumerate(d.candidates):
            eff = EFFECTS.get(c.effect)
            if eff is None or eff.plot is None or c.effect in cases:
                continue
            if c.effect in added_in:
                cases[c.effect] = (eff, d.context, f"added in round {added_in[c.effect]}")
            elif c.helps or i < SHOWN_CANDIDATES:
                cases[c.effect] = (eff, d.context, "not added")
    ordered = sorted(cases.values(), key=lambda c: c[2] == "not added")
    return ordered


def _fig_signatures(plt, meas: Measurement, rounds: list[Round]):
    cases = _signature_cases(rounds)
    cols = 2
    rows = max(1, (len(cases) + cols - 1) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(11, 3.8 * rows), squeeze=False)
    for ax in axes.ravel()[len(cases) :]:
        ax.axis("off")
    if not cases:
        axes[0, 0].text(0.02, 0.5, "no candidate with a signature plot", fontsize=10)
    for ax, (eff, ctx, label) in zip(axes.ravel(), cases, strict=False):
        eff.plot(ctx, ax)
        ax.grid(alpha=0.3)
        ax.set_title(f"[{label}] {ax.get_title()}", fontsize=9)
        if label == "not added":
            ax.set_facecolor("#f4f4f4")
    fig.suptitle(
        "signatures of the effects diagnosed, on the residual of their round "
        "(labelled: added in round k, or not added)"
    )
    fig.tight_layout()
    return fig


_DRAW = {
    "overlay": _fig_overlay,
    "residual": _fig_residual,
    "residual_vs": _fig_residual_vs,
    "regimes": _fig_regimes,
    "error_fall": _fig_error_fall,
    "signatures": _fig_signatures,
}


# ---------------------------------------------------------------- html

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1150px;
margin:2em auto;padding:0 1em;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:2em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}
td.l,th.l{text-align:left}.fail{color:#c00;font-weight:600}.warn{color:#a60}
img{max-width:100%;border:1px solid #eee;margin:.5em 0}.small{color:#666;font-size:.85em}
"""


def _e(x: Any) -> str:
    return html.escape(str(x))


def _num(x: Any, fmt: str = ".4g") -> str:
    try:
        f = float(x)
    except (TypeError, ValueError):
        return _e(x)
    return format(f, fmt) if np.isfinite(f) else "-"


def _params(p: dict) -> str:
    parts = []
    for k, v in p.items():
        if isinstance(v, list):
            v = "[" + ", ".join(_num(x) for x in v) + "]"
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            v = _num(v)
        parts.append(f"{_e(k)} = {_e(v)}")
    return "<br>".join(parts)


def _html(meas: Measurement, rounds: list[Round], images: dict[str, bytes], title: str) -> str:
    h: list[str] = [
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{_e(title)}</title>"
        f"<style>{_CSS}</style></head><body><h1>{_e(title)}</h1>"
    ]
    base = rounds[0].compare
    cut = ", ".join(
        f"{k}: " + (f"{_num(v)} Hz" if v else "none") for k, v in base.inputs.cutoffs.items()
    )
    h.append(
        f"<p>Measurement <code>{_e(meas.path)}</code>: {meas.n} samples, dt = {meas.dt:.6g} s, "
        f"{meas.spec.block} rig. Simulation: open loop, the measured inputs drive the C rig from "
        f"the first sample. Input filter cut-offs (zero phase): {_e(cut)}.</p>"
    )
    h.append(_rounds_table(meas, rounds))
    if "error_fall" in images:
        h.append(_img(images["error_fall"], "error fall"))
    h.append("<h2>Measured vs simulated</h2>")
    h.append(_img(images["overlay"], "overlay"))
    h.append("<h2>Where the starting model fails</h2>")
    h.append(_regime_table(base, meas))
    h.append(_img(images["residual"], "residual"))
    h.append(_img(images["regimes"], "regimes"))
    h.append(_img(images["residual_vs"], "residual signatures"))
    if _signature_cases(rounds):
        h.append("<h2>Signatures of the effects diagnosed</h2>")
        h.append(_img(images["signatures"], "effect signatures"))
    for i, r in enumerate(rounds):
        if r.diagnosis is not None:
            h.append(_diagnosis_html(i, r.diagnosis))
        next_fit = rounds[i + 1].fit if i + 1 < len(rounds) else None
        if next_fit is not None:
            h.append(_fit_html(i + 1, next_fit))
    h.append(
        "<p class='small'>nrmse = rms(measured - simulated) / std(measured) per output; the "
        "overall nrmse is their mean (docs/measurement-format.md). Validation: the record is cut "
        "into 10 contiguous blocks, the held-out ones never enter a fit; score: BIC on the "
        "estimation blocks with an effective sample count (docs/analysis.md). Standard "
        "deviations come from the Jacobian and are lower bounds when the residual is "
        "correlated in time.</p></body></html>"
    )
    return "\n".join(h)


def _rounds_table(meas: Measurement, rounds: list[Round]) -> str:
    outs = meas.spec.outputs
    h = [
        "<h2>Error across rounds</h2><table><tr><th class='l'>round</th>"
        "<th class='l'>effect added</th>"
        + "".join(f"<th>nrmse {_e(o)}</th>" for o in outs)
        + "<th>nrmse</th><th>estimation nrmse</th><th>validation nrmse</th><th>fit %</th></tr>"
    ]
    for i, r in enumerate(rounds):
        h.append(
            f"<tr><td class='l'>{i}</td><td class='l'>{_e(r.effect or 'starting model')}</td>"
            + "".join(f"<td>{_num(r.compare.outputs[o].nrmse)}</td>" for o in outs)
            + f"<td><b>{_num(r.compare.nrmse)}</b></td><td>{_num(r.estimation_nrmse)}</td>"
            + f"<td><b>{_num(r.validation_nrmse)}</b></td>"
            + f"<td>{_num(100 * (1 - r.compare.nrmse), '.2f')}</td></tr>"
        )
    h.append("</table>")
    last = next((r.diagnosis for r in reversed(rounds) if r.diagnosis is not None), None)
    if last is not None and not last.best_helps:
        h.append(f"<p><b>{_e(last.conclusion)}</b></p>")
    return "".join(h)


def _method(c: Any) -> str:
    return "fit" if c.method == "fit" else "screening estimate"


def _diagnosis_html(i: int, d: DiagnoseResult) -> str:
    h = [
        f"<h2>Diagnosis of the round {i} model (nrmse {_num(d.baseline_nrmse)}, validation "
        f"{_num(d.validation_baseline_nrmse)}, score {_num(d.baseline_score, '.1f')})</h2>",
        "<table><tr><th>rank</th><th class='l'>effect</th><th>score</th><th class='l'>method</th>"
        "<th>nrmse after</th><th>validation nrmse</th><th class='l'>helps</th>"
        "<th class='l'>parameters</th><th class='l'>evidence from the residual</th></tr>",
    ]
    for k, c in enumerate(d.candidates, 1):
        tie = f" (within the noise of {', '.join(c.tied_with)})" if c.tied_with else ""
        h.append(
            f"<tr><td>{k}</td><td class='l'><b>{_e(c.effect)}</b></td>"
            f"<td>{_num(c.score, '.1f')}</td><td class='l'>{_method(c)}</td>"
            f"<td>{_num(c.nrmse_after)}</td><td>{_num(c.validation_nrmse_after)}</td>"
            f"<td class='l'>{'yes' if c.helps else 'no'}{_e(tie)}</td>"
            f"<td class='l'>{_params(c.parameters)}</td>"
            f"<td class='l'>{_e(c.evidence.get('text', ''))}</td></tr>"
        )
    h.append("</table>")
    h.append(
        "<p class='small'>Sorted by score (lower is better); screening estimates follow the "
        "fitted candidates.</p>"
    )
    for w in d.warnings:
        h.append(f"<p class='warn'>warning: {_e(w['text'])}</p>")
    h.append(f"<p><b>{_e(d.conclusion)}</b></p>")
    if d.skipped:
        h.append(
            "<p class='small'>Not candidates: "
            + "; ".join(f"{_e(k)} ({_e(v)})" for k, v in d.skipped.items())
            + "</p>"
        )
    return "".join(h)


def _fit_html(k: int, f: FitResult) -> str:
    h = [
        f"<h2>Round {k}: fit of {_e(f.effect)}: nrmse {_num(f.nrmse_before)} &rarr; "
        f"{_num(f.nrmse_after)}, validation {_num(f.validation_nrmse_before)} &rarr; "
        f"{_num(f.validation_nrmse_after)}</h2>",
        "<table><tr><th class='l'>parameter</th><th>value</th><th>std</th><th>before</th>"
        "<th class='l'>role</th></tr>",
    ]
    for p in f.fitted:
        before = _num(p["before"]) if p["before"] is not None else ""
        h.append(
            f"<tr><td class='l'>{_e(p['name'])}</td><td>{_num(p['value'])}</td>"
            f"<td>{_num(p['std'])}</td><td>{before}</td><td class='l'>{_e(p['role'])}</td></tr>"
        )
    h.append("</table>")
    h += [f"<p class='warn'>warning: {_e(w['text'])}</p>" for w in f.warnings]
    h += [f"<p class='small'>note: {_e(n)}</p>" for n in f.notes]
    return "".join(h)


def _regime_table(c: CompareResult, meas: Measurement) -> str:
    outs = meas.spec.outputs
    rows = [
        f"<p>A regime fails when an output's error in it is at least {FAILING_RATIO:g}x its "
        "overall error (and it holds at least 1 % of the samples).</p>"
        "<table><tr><th class='l'>regime</th><th class='l'>definition</th><th>share</th>"
        + "".join(f"<th>{_e(o)} nrmse (x overall)</th>" for o in outs)
        + f"<th class='l'>fails (&ge; {FAILING_RATIO:g}x)</th></tr>"
    ]
    for r in c.regimes:
        cls = " class='fail'" if r["failing"] else ""
        rows.append(
            f"<tr{cls}><td class='l'>{_e(r['regime'])}</td>"
            f"<td class='l'>{_e(r['description'])}</td>"
            f"<td>{100 * r['fraction']:.1f} %</td>"
            + "".join(
                f"<td>{_num(r['outputs'][o]['nrmse'])} "
                f"({_num(r['outputs'][o]['ratio'], '.2f')}x)</td>"
                for o in outs
            )
            + f"<td class='l'>{'fails' if r['failing'] else ''}</td></tr>"
        )
    rows.append("</table>")
    return "".join(rows)


def _img(png: bytes, alt: str) -> str:
    return (
        f"<img alt='{_e(alt)}' src='data:image/png;base64,{base64.b64encode(png).decode('ascii')}'>"
    )


def write_report(
    out_dir: str,
    meas: Measurement,
    rounds: list[Round],
    *,
    title: str = "gearsim report",
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Draw the figures of FIGURES into out_dir/*.png and out_dir/report.html
    (self-contained), each file written atomically; out_dir is created when
    missing and must not be a file. Returns {"html": path, "images": [paths]}."""
    say = progress or (lambda s: None)
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise OutputPathError(
            f"--out {printable(out_dir)}: exists and is not a directory", parameter="--out"
        )
    plt = _plt()
    os.makedirs(out_dir, exist_ok=True)
    images: dict[str, bytes] = {}
    paths = []
    for name in FIGURES:
        fig = _DRAW[name](plt, meas, rounds)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        plt.close(fig)
        images[name] = buf.getvalue()
        p = os.path.join(out_dir, f"{name}.png")
        atomic_write_bytes(p, images[name])
        paths.append(p)
        say(f"report: drew {name}.png")
    page = os.path.join(out_dir, "report.html")
    atomic_write_text(page, _html(meas, rounds, images, title))
    return {"html": page, "images": paths}

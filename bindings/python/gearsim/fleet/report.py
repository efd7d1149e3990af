"""The fleet report: one self-contained HTML page (plots embedded as
base64 PNG, matplotlib with the Agg backend) and one page per outlier with
its overlay of measured against simulated.

Figures: a histogram per parameter and of the remaining error, with the
median, the +-threshold band and the outliers marked; a scatter of the two
most variable parameters; the population's error before and after the
fit; with timestamps, each parameter against time with a rolling median
and its Theil-Sen trend line. The overlay of an outlier runs the analysis'
compare twice on its log: with the start model and with the model fitted
to it.
"""

from __future__ import annotations

import base64
import hashlib
import html
import io
import math
import os
import re
from collections.abc import Callable
from typing import Any

import numpy as np

from .._outputs import atomic_write_text, printable
from .population import REMAINING_ERROR, Sample

__all__ = ["write_fleet_report", "overlay_name", "MAX_OVERLAYS"]

#: outliers (by |z|) that get an overlay page
MAX_OVERLAYS = 50
#: error rows listed on the page
MAX_ERRORS = 200
_MAX_POINTS = 20_000
_COLS = 3

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1200px;
margin:2em auto;padding:0 1em;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:2em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}
td.l,th.l{text-align:left}.out{color:#c00;font-weight:600}.small{color:#666;font-size:.85em}
img{max-width:100%;border:1px solid #eee;margin:.5em 0}
"""


def _e(x: Any) -> str:
    return html.escape(str(x))


def _num(x: Any, fmt: str = ".4g") -> str:
    try:
        f = float(x)
    except (TypeError, ValueError):
        return "-"
    return format(f, fmt) if math.isfinite(f) else "-"


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(plt, fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()


def _img(png: bytes, alt: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return f"<img alt='{_e(alt)}' src='data:image/png;base64,{data}'>"


def overlay_name(unit: str) -> str:
    """The file name of a unit's overlay page (safe on every file system,
    unique per unit id)."""
    safe = re.sub(r"[^A-Za-z0-9._-]", "_", unit)[:60]
    return f"{safe}-{hashlib.sha256(unit.encode()).hexdigest()[:8]}.html"


def _metric_values(samples: list[Sample], name: str) -> np.ndarray:
    if name == REMAINING_ERROR:
        return np.array([s.nrmse_after for s in samples], dtype=float)
    return np.array([s.values.get(name, math.nan) for s in samples], dtype=float)


def _label(name: str, pop: dict) -> str:
    if name == REMAINING_ERROR:
        return "remaining error (nrmse after)"
    unit = pop["parameters"].get(name, {}).get("unit", "")
    return f"{name} [{unit}]" if unit else name


def _stat(pop: dict, name: str) -> dict:
    return pop["remaining_error"] if name == REMAINING_ERROR else pop["parameters"][name]


def _fig_histograms(plt, samples, pop, metrics):
    rows = math.ceil(len(metrics) / _COLS)
    fig, axes = plt.subplots(rows, _COLS, figsize=(12, 3.0 * rows), squeeze=False)
    thr = pop["threshold"]
    out_units = {o["unit"]: o for o in pop["outliers"]}
    for ax, name in zip(axes.flat, metrics, strict=False):
        x = _metric_values(samples, name)
        st = _stat(pop, name)
        ok = np.isfinite(x)
        ax.hist(x[ok], bins=min(60, max(10, int(ok.sum() ** 0.5) * 2)), color="#9bbcd9")
        m, s = st["median"], st["sigma"]
        ax.axvline(m, color="k", lw=1)
        if s > 0:
            for k in (1,) if name == REMAINING_ERROR else (-1, 1):
                ax.axvline(m + k * thr * s, color="#c00", lw=0.8, ls="--")
        flagged = [
            (x[i], s_.unit)
            for i, s_ in enumerate(samples)
            if s_.unit in out_units
            and any(r["metric"] == name for r in out_units[s_.unit]["reasons"])
        ]
        for v, u in flagged[:12]:
            ax.plot([v], [0], marker="v", color="#c00", ms=8, clip_on=False)
            ax.annotate(
                u,
                (v, 0),
                xytext=(0, 10),
                textcoords="offset points",
                fontsize=7,
                color="#c00",
                rotation=60,
                ha="left",
            )
        ax.set_title(_label(name, pop), fontsize=9)
        ax.tick_params(labelsize=8)
    for ax in list(axes.flat)[len(metrics) :]:
        ax.axis("off")
    fig.suptitle(
        f"per parameter: median (black), median +- {thr:g} robust sigma (red, dashed), "
        "outliers by this parameter (red triangles)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def _span(v: np.ndarray) -> tuple[float, float]:
    """The range of v (finite values) with 15 % margin."""
    v = v[np.isfinite(v)]
    if v.size == 0:
        return -1.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    pad = 0.15 * (hi - lo or abs(hi) or 1.0)
    return lo - pad, hi + pad


def _fig_scatter(plt, samples, pop):
    """The population's cloud at its own scale; an outlier beyond it is drawn
    at the edge and labelled "off scale"."""
    a, b = pop["most_variable"]
    x, y = _metric_values(samples, a), _metric_values(samples, b)
    out_units = {o["unit"] for o in pop["outliers"]}
    is_out = np.array([s.unit in out_units for s in samples])
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    ax.scatter(x[~is_out], y[~is_out], s=10, color="#1f77b4", label="units")
    (x0, x1), (y0, y1) = _span(x[~is_out]), _span(y[~is_out])
    cx, cy = np.clip(x, x0, x1), np.clip(y, y0, y1)
    ax.scatter(cx[is_out], cy[is_out], s=28, color="#c00", marker="x", label="outliers")
    for i in np.nonzero(is_out)[0][:20]:
        off = " (off scale)" if (cx[i], cy[i]) != (x[i], y[i]) else ""
        ax.annotate(
            samples[i].unit + off,
            (cx[i], cy[i]),
            fontsize=7,
            color="#c00",
            xytext=(3, 3),
            textcoords="offset points",
        )
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel(_label(a, pop))
    ax.set_ylabel(_label(b, pop))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("the two most variable parameters (largest robust sigma / |median|)")
    fig.tight_layout()
    return fig


def _fig_errors(plt, samples):
    before = np.array([s.extra.get("nrmse_before", math.nan) for s in samples], dtype=float)
    after = np.array([s.nrmse_after for s in samples], dtype=float)
    both = np.concatenate([before, after])
    both = both[np.isfinite(both) & (both > 0)]
    fig, ax = plt.subplots(figsize=(9, 3.8))
    if both.size:
        bins = np.geomspace(both.min() * 0.9, both.max() * 1.1, 50)
        ax.hist(
            before[np.isfinite(before)], bins=bins, alpha=0.6, label="start model", color="#1f77b4"
        )
        ax.hist(after[np.isfinite(after)], bins=bins, alpha=0.6, label="fitted", color="#2ca02c")
        ax.set_xscale("log")
    ax.set_xlabel("nrmse (mean over the outputs)")
    ax.set_ylabel("units")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax.set_title("the population's error before and after the fit")
    fig.tight_layout()
    return fig


def _fig_drift(plt, samples, pop, metrics):
    drift = pop["drift"]
    metrics = [m for m in metrics if m in drift]
    t0 = np.datetime64(drift["start"].replace("+00:00", ""))
    days = np.array(
        [
            (np.datetime64(s.timestamp.replace(tzinfo=None)) - t0) / np.timedelta64(1, "s") / 86400
            if s.timestamp is not None
            else math.nan
            for s in samples
        ],
        dtype=float,
    )
    rows = math.ceil(len(metrics) / _COLS)
    fig, axes = plt.subplots(rows, _COLS, figsize=(12, 3.0 * rows), squeeze=False)
    for ax, name in zip(axes.flat, metrics, strict=False):
        y = _metric_values(samples, name)
        ok = np.isfinite(days) & np.isfinite(y)
        order = np.argsort(days[ok], kind="stable")
        d, v = days[ok][order], y[ok][order]
        zs = np.array([pop["z"].get(s.unit, {}).get(name, 0.0) for s in samples], dtype=float)
        far = (np.abs(zs) > pop["threshold"])[ok][order]
        ax.plot(d[~far], v[~far], ".", ms=3, color="#1f77b4")
        if (~far).sum() >= 2:  # the outliers are drawn at the edge, not scaled to
            lo, hi = _span(v[~far])
            ax.set_ylim(lo, hi)
            ax.plot(d[far], np.clip(v[far], lo, hi), "x", ms=6, color="#c00")
        win = max(5, len(d) // 20)
        if len(d) >= win:
            med = np.array(
                [np.median(v[max(0, i - win // 2) : i + win // 2 + 1]) for i in range(len(d))]
            )
            ax.plot(d, med, color="k", lw=1, label=f"rolling median ({win} units)")
        st = drift[name]
        centre = float(np.median(v - st["slope_per_day"] * d)) if len(d) else 0.0
        ax.plot(
            d,
            centre + st["slope_per_day"] * d,
            color="#c00" if st["drifting"] else "#999",
            lw=1.2,
            ls="--",
            label="Theil-Sen trend",
        )
        flag = "DRIFTS: " if st["drifting"] else ""
        ax.set_title(
            f"{flag}{_label(name, pop)}", fontsize=9, color="#c00" if st["drifting"] else "k"
        )
        ax.tick_params(labelsize=8)
        ax.set_xlabel("days since the first unit", fontsize=8)
    for ax in list(axes.flat)[len(metrics) :]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle(
        "parameters against time; outliers (red x, at the edge when beyond it) are left out of "
        "the trend",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def _overlay(plt, unit, row, start, options):
    """measured vs simulated (start model and fitted model) for one unit."""
    from ..analysis import AnalysisModel, compare, load_measurement, prepare_inputs
    from ..analysis.measurement import parse_column_map

    meas = load_measurement(
        unit.path,
        start.block,
        columns=parse_column_map(options.get("columns") or []),
        resample=options.get("resample", False),
        max_gap=options.get("max_gap"),
    )
    inputs = prepare_inputs(meas, options["input_filter"])
    fitted = AnalysisModel.loads(row["model"])
    c0 = compare(start, meas, inputs, regimes=False)
    c1 = compare(fitted, meas, inputs, regimes=False)
    outs = list(c0.outputs)
    fig, axes = plt.subplots(
        len(outs), 1, figsize=(11, 3.2 * len(outs)), sharex=True, squeeze=False
    )
    s = max(1, int(math.ceil(meas.n / _MAX_POINTS)))
    t = meas.time[::s]
    for ax, o in zip(axes[:, 0], outs, strict=True):
        ax.plot(t, meas[o][::s], color="0.55", lw=0.8, label="measured")
        ax.plot(
            t,
            c0.sim.outputs[o][::s],
            color="#1f77b4",
            lw=0.8,
            ls="--",
            label=f"start model (nrmse {c0.outputs[o].nrmse:.4f})",
        )
        ax.plot(
            t,
            c1.sim.outputs[o][::s],
            color="#2ca02c",
            lw=0.9,
            label=f"fitted to this unit (nrmse {c1.outputs[o].nrmse:.4f})",
        )
        ax.set_ylabel(f"{o} [{meas.spec.unit(o)}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"unit {unit.unit}: measured vs simulated (open loop)")
    fig.tight_layout()
    return fig


def _unit_page(unit, row, outlier, pop, png: bytes | None, problem: str | None) -> str:
    h = [
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>unit {_e(unit.unit)}</title>"
        f"<style>{_CSS}</style></head><body><h1>unit {_e(unit.unit)}</h1>",
        f"<p>log <code>{_e(unit.path)}</code>; nrmse {_num(row.get('nrmse_before'))} &rarr; "
        f"{_num(row.get('nrmse_after'))}; effects fitted: "
        f"{_e(', '.join(row.get('effects_fitted') or []))}"
        "; <a href='../fleet.html'>back to the fleet</a></p>",
        "<table><tr><th class='l'>metric</th><th>value</th><th>std</th><th>population median</th>"
        "<th>robust z</th></tr>",
    ]
    z = pop["z"].get(unit.unit, {})
    flagged = {r["metric"] for r in outlier["reasons"]}
    params = row.get("parameters") or {}
    for name in [*sorted(params), REMAINING_ERROR]:
        if name == REMAINING_ERROR:
            value, std, st = row.get("nrmse_after"), None, pop["remaining_error"]
        else:
            value, std = params[name]["value"], params[name]["std"]
            st = pop["parameters"].get(name, {})
        cls = " class='out'" if name in flagged else ""
        h.append(
            f"<tr{cls}><td class='l'>{_e(_label(name, pop) if st else name)}</td>"
            f"<td>{_num(value)}</td><td>{_num(std)}</td><td>{_num(st.get('median'))}</td>"
            f"<td>{_num(z.get(name), '.2f')}</td></tr>"
        )
    h.append("</table>")
    if png is not None:
        h.append(_img(png, "overlay"))
    if problem:
        h.append(f"<p class='out'>no overlay: {_e(problem)}</p>")
    for w in row.get("warnings") or []:
        h.append(f"<p class='small'>{_e(w)}</p>")
    h.append("</body></html>")
    return "\n".join(h)


def _write_overlays(out, pop, units, rows, start, options, say) -> dict[str, str]:
    """One page per outlier (the first MAX_OVERLAYS by |z|); stale pages of
    earlier runs are removed. Returns unit id -> relative link."""
    plt = _plt()
    folder = os.path.join(out, "units")
    os.makedirs(folder, exist_ok=True)
    wanted = {o["unit"]: o for o in pop["outliers"][:MAX_OVERLAYS]}
    links: dict[str, str] = {}
    for u, row in rows():
        if u.unit not in wanted:
            continue
        png, problem = None, None
        try:
            png = _png(plt, _overlay(plt, u, row, start, options))
        except Exception as exc:  # the page still shows the numbers
            problem = f"{type(exc).__name__}: {printable(exc, 300)}"
        name = overlay_name(u.unit)
        atomic_write_text(
            os.path.join(folder, name), _unit_page(u, row, wanted[u.unit], pop, png, problem)
        )
        links[u.unit] = f"units/{name}"
    keep = {os.path.basename(v) for v in links.values()}
    for old in os.listdir(folder):
        if old.endswith(".html") and old not in keep:
            os.unlink(os.path.join(folder, old))
    say(f"fleet: wrote {len(links)} overlay page(s) in {printable(folder, limit=200)}")
    return links


def _param_table(pop) -> str:
    drift = pop.get("drift") or {}
    h = [
        "<table><tr><th class='l'>metric</th><th>units</th><th>median</th><th>MAD</th>"
        "<th>robust sigma</th><th>sigma / |median|</th>"
        + ("<th>drift per day</th><th>change over the span (sigma)</th>" if drift else "")
        + "</tr>"
    ]
    for name in [*pop["parameters"], REMAINING_ERROR]:
        st = _stat(pop, name)
        d = drift.get(name)
        cells = ""
        if drift:
            cls = " class='out'" if d and d["drifting"] else ""
            cells = (
                f"<td{cls}>{_num(d['slope_per_day']) if d else '-'}</td>"
                f"<td{cls}>{_num(d['change_sigmas'], '.2f') if d else '-'}"
                f"{' drifts' if d and d['drifting'] else ''}</td>"
            )
        h.append(
            f"<tr><td class='l'>{_e(_label(name, pop))}</td><td>{st['n']}</td>"
            f"<td>{_num(st['median'])}</td><td>{_num(st['mad'])}</td><td>{_num(st['sigma'])}</td>"
            f"<td>{_num(st['relative_spread'], '.3f')}</td>{cells}</tr>"
        )
    h.append("</table>")
    return "".join(h)


def _outlier_table(pop, units_by_id, links) -> str:
    if not pop["outliers"]:
        return "<p>No outlier.</p>"
    h = [
        "<table><tr><th class='l'>unit</th><th class='l'>outlier by</th><th>z</th>"
        "<th class='l'>also above the threshold</th><th class='l'>line</th>"
        "<th class='l'>station</th><th class='l'>timestamp</th><th class='l'>overlay</th></tr>"
    ]
    for o in pop["outliers"]:
        u = units_by_id[o["unit"]]
        more = ", ".join(f"{r['metric']} ({r['z']:.1f})" for r in o["reasons"][1:])
        link = links.get(o["unit"])
        cell = f"<a href='{_e(link)}'>measured vs simulated</a>" if link else "-"
        by = "remaining error" if o["by"] == REMAINING_ERROR else o["by"]
        h.append(
            f"<tr><td class='l'><b>{_e(o['unit'])}</b></td><td class='l out'>{_e(by)}</td>"
            f"<td>{_num(o['z'], '.1f')}</td><td class='l'>{_e(more)}</td>"
            f"<td class='l'>{_e(u.line or '')}</td><td class='l'>{_e(u.station or '')}</td>"
            f"<td class='l'>{_e(u.timestamp.isoformat() if u.timestamp else '')}</td>"
            f"<td class='l'>{cell}</td></tr>"
        )
    h.append("</table>")
    return "".join(h)


def write_fleet_report(
    out: str,
    *,
    samples: list[Sample],
    pop: dict,
    units: list,
    rows: Callable,
    start: Any,
    options: dict,
    counts: dict,
    errors: list[tuple[str, str]],
    say: Callable[[str], None],
) -> str:
    """Write OUT/fleet.html and OUT/units/*.html; returns the page's path."""
    plt = _plt()
    h = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>gearsim fleet</title>"
        f"<style>{_CSS}</style></head><body><h1>gearsim fleet: {counts['units']} units</h1>",
        f"<p>{counts['ok']} analysed, {counts['errors']} with errors"
        f" ({counts['cached']} from the cache). Mode: {_e(options['mode'])}"
        + (
            f", effects fitted in order: {_e(', '.join(options['effects']))}"
            if options["effects"]
            else ""
        )
        + f". Start model: {_e(start.block)}. Results: <code>units.parquet</code>, "
        "<code>population.json</code>.</p>",
    ]
    if not pop["parameters"] and pop.get("note"):
        h.append(f"<p><b>{_e(pop['note'])}</b></p>")
    else:
        metrics = [*pop["parameters"], REMAINING_ERROR]
        units_by_id = {u.unit: u for u in units}
        links = _write_overlays(out, pop, units, rows, start, options, say)
        h.append(
            f"<h2>Outliers ({len(pop['outliers'])}; robust |z| &gt; {pop['threshold']:g})</h2>"
        )
        h.append(_outlier_table(pop, units_by_id, links))
        h.append("<h2>Population</h2>")
        h.append(_param_table(pop))
        h.append(_img(_png(plt, _fig_histograms(plt, samples, pop, metrics)), "histograms"))
        if len(pop["most_variable"]) == 2:
            h.append(_img(_png(plt, _fig_scatter(plt, samples, pop)), "scatter"))
        h.append(_img(_png(plt, _fig_errors(plt, samples)), "error before and after"))
        if pop.get("drift"):
            h.append("<h2>Drift against time</h2>")
            h.append(_img(_png(plt, _fig_drift(plt, samples, pop, metrics)), "drift"))
    if errors:
        h.append(
            f"<h2>Units with errors ({len(errors)})</h2><table><tr><th class='l'>unit</th>"
            "<th class='l'>error</th></tr>"
        )
        for unit, err in errors[:MAX_ERRORS]:
            h.append(f"<tr><td class='l'>{_e(unit)}</td><td class='l'>{_e(err)}</td></tr>")
        h.append("</table>")
        if len(errors) > MAX_ERRORS:
            h.append(
                f"<p class='small'>... and {len(errors) - MAX_ERRORS} more: see units.parquet "
                "(status = 'error').</p>"
            )
    h.append(
        f"<p class='small'>Robust z = (value - median) / (1.4826 MAD); a unit is an outlier when "
        f"|z| &gt; {pop['threshold']:g} for a parameter, or z &gt; {pop['threshold']:g} for its "
        "remaining error (a fault in an effect the fitted list does not have). Drift: Theil-Sen "
        "slope against time with its 95 % interval; a parameter drifts when the interval excludes "
        "0 and the change over the span is at least one robust sigma (docs/fleet.md).</p>"
        "</body></html>"
    )
    page = os.path.join(out, "fleet.html")
    atomic_write_text(page, "\n".join(h))
    say(f"fleet: wrote {printable(page, limit=200)}")
    return page

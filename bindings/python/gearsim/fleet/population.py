"""The population of a fleet: robust centre and spread per parameter,
outliers, drift against time.

Per parameter p over the units analysed without error:

- centre: the median m; spread: the MAD (median absolute deviation from
  m), scaled to a standard deviation as sigma = 1.4826 MAD (the factor
  that makes it one for normal data). When half the units or more share one
  value (MAD 0), sigma = 1.2533 x the mean absolute deviation from m
  instead; when that is 0 too, the parameter has no spread to judge and no
  unit is an outlier by it.
- robust z-score of unit u: z = (p_u - m) / sigma. A unit is an outlier
  when |z| > THRESHOLD (3.5) for some parameter, or when its remaining error
  (nrmse after the fit, a high value only) has z > THRESHOLD: its fault
  then is in an effect the fitted list does not have. ``by`` is the metric
  with the largest |z|; ``reasons`` lists every metric above the threshold.
  A normally spread population gives about 1 unit in 2,000 above 3.5 per
  metric.
- only parameters fitted on at least half the units (and on MIN_UNITS of
  them) are judged; a fleet of fewer than MIN_UNITS good units has no
  population statistics.
- drift (units with timestamps only): the Theil-Sen slope of p against time
  (the median of the slopes between pairs of units; robust to outliers)
  with its 95 % interval, over at most DRIFT_POINTS units evenly picked in
  time. `change` is slope x the time span; a parameter drifts when the
  interval excludes 0 and |change| is at least one sigma.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

__all__ = [
    "THRESHOLD",
    "MIN_UNITS",
    "REMAINING_ERROR",
    "Sample",
    "robust_centre_spread",
    "population",
]

THRESHOLD = 3.5
MIN_UNITS = 10
DRIFT_POINTS = 2000
MAD_TO_SIGMA = 1.4826
MEAN_AD_TO_SIGMA = 1.2533
#: the metric of the remaining error (judged on its high side only)
REMAINING_ERROR = "nrmse_after"


@dataclass
class Sample:
    """What the population needs of one good unit."""

    unit: str
    values: dict[str, float]
    nrmse_after: float
    timestamp: datetime | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def robust_centre_spread(x: np.ndarray) -> tuple[float, float, float]:
    """(median, MAD, sigma) of the finite values (module docstring)."""
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return math.nan, math.nan, math.nan
    m = float(np.median(x))
    dev = np.abs(x - m)
    mad = float(np.median(dev))
    sigma = MAD_TO_SIGMA * mad
    if sigma == 0.0:
        sigma = MEAN_AD_TO_SIGMA * float(np.mean(dev))
    return m, mad, sigma


def _theil_sen(days: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    from scipy.stats import theilslopes

    ok = np.isfinite(y)
    days, y = days[ok], y[ok]
    if days.size > DRIFT_POINTS:
        pick = np.linspace(0, days.size - 1, DRIFT_POINTS).round().astype(int)
        order = np.argsort(days, kind="stable")[pick]
        days, y = days[order], y[order]
    res = theilslopes(y, days, alpha=0.95)
    return float(res[0]), float(res[2]), float(res[3])


def population(
    samples: Sequence[Sample],
    units_of: dict[str, str] | None = None,
    threshold: float = THRESHOLD,
) -> dict[str, Any]:
    """The population statistics of `samples` (the good units), as a JSON-
    ready dict: "parameters" (per name: median, mad, sigma, n, unit,
    relative_spread), "remaining_error" (the same for nrmse after), "outliers"
    (unit, by, z, reasons), "z" (per unit: metric -> z, for the report),
    "most_variable" (the two parameters with the largest sigma / |median|,
    where a median within one sigma of 0 counts as |median| = sigma),
    "drift" (per metric, or None without timestamps)."""
    units_of = units_of or {}
    n = len(samples)
    out: dict[str, Any] = {
        "threshold": threshold,
        "min_units": MIN_UNITS,
        "units": n,
        "parameters": {},
        "remaining_error": None,
        "outliers": [],
        "most_variable": [],
        "drift": None,
        "z": {},
    }
    if n < MIN_UNITS:
        out["note"] = f"fewer than {MIN_UNITS} units analysed without error: no population"
        return out
    names = sorted({k for s in samples for k in s.values})
    metrics: dict[str, np.ndarray] = {}
    for name in names:
        x = np.array([s.values.get(name, math.nan) for s in samples], dtype=float)
        if np.isfinite(x).sum() >= max(MIN_UNITS, n / 2):
            metrics[name] = x
    metrics[REMAINING_ERROR] = np.array([s.nrmse_after for s in samples], dtype=float)
    stats: dict[str, dict[str, Any]] = {}
    zs: dict[str, np.ndarray] = {}
    for name, x in metrics.items():
        m, mad, sigma = robust_centre_spread(x)
        stats[name] = {
            "median": m,
            "mad": mad,
            "sigma": sigma,
            "n": int(np.isfinite(x).sum()),
            "unit": units_of.get(name, ""),
            "relative_spread": sigma / max(abs(m), sigma) if sigma > 0 else 0.0,
        }
        with np.errstate(invalid="ignore", divide="ignore"):
            zs[name] = (x - m) / sigma if sigma > 0 else np.full(x.shape, math.nan)
    out["remaining_error"] = stats.pop(REMAINING_ERROR)
    out["parameters"] = stats
    ranked = sorted(stats, key=lambda k: -stats[k]["relative_spread"])
    out["most_variable"] = [k for k in ranked if stats[k]["sigma"] > 0][:2]
    for i, s in enumerate(samples):
        reasons = []
        per = {}
        for name, z in zs.items():
            zi = float(z[i])
            if not math.isfinite(zi):
                continue
            per[name] = zi
            high = zi > threshold
            if high or (name != REMAINING_ERROR and abs(zi) > threshold):
                reasons.append({"metric": name, "z": zi, "value": float(metrics[name][i])})
        out["z"][s.unit] = per
        if reasons:
            reasons.sort(key=lambda r: -abs(r["z"]))
            out["outliers"].append(
                {
                    "unit": s.unit,
                    "by": reasons[0]["metric"],
                    "z": reasons[0]["z"],
                    "reasons": reasons,
                }
            )
    out["outliers"].sort(key=lambda o: -abs(o["z"]))
    out["drift"] = _drift(
        samples, metrics, zs, stats | {REMAINING_ERROR: out["remaining_error"]}, threshold
    )
    return out


def _drift(samples, metrics, zs, stats, threshold) -> dict[str, Any] | None:
    stamps = [s.timestamp for s in samples]
    have = [t is not None for t in stamps]
    if sum(have) < MIN_UNITS:
        return None
    t0 = min(t for t in stamps if t is not None)
    days = np.array(
        [(t - t0).total_seconds() / 86400.0 if t is not None else math.nan for t in stamps]
    )
    span = float(np.nanmax(days))
    if span <= 0:
        return None
    out: dict[str, Any] = {"span_days": span, "start": t0.isoformat()}
    for name, x in metrics.items():
        keep = np.isfinite(days) & np.isfinite(x)
        z = zs[name]
        keep &= ~(np.abs(np.nan_to_num(z, nan=0.0)) > threshold)  # outliers do not set a trend
        if keep.sum() < MIN_UNITS:
            continue
        slope, low, high = _theil_sen(days[keep], x[keep])
        sigma = stats[name]["sigma"]
        change = slope * span
        sig = change / sigma if sigma > 0 else math.nan
        out[name] = {
            "slope_per_day": slope,
            "low": low,
            "high": high,
            "change": change,
            "change_sigmas": sig,
            "drifting": bool((low > 0 or high < 0) and math.isfinite(sig) and abs(sig) >= 1.0),
        }
    return out

"""Error metrics of a simulated output against its measurement.

All functions take float arrays of equal length (measured first) and return
plain floats, in the unit of the output unless said otherwise.

- ``nrmse = rms(measured - simulated) / std(measured)`` (docs/measurement-format.md
  section 4): 0 is perfect, 1 is as bad as predicting the mean.
- ``fit_percent = 100 * (1 - ||y - yhat|| / ||y - mean(y)||)``, the NRMSE fit of
  system identification toolboxes; it equals ``100 * (1 - nrmse)``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["OutputMetrics", "output_metrics", "nrmse", "rms"]


def rms(x: np.ndarray) -> float:
    """Root mean square of x (same unit as x)."""
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


def _scale(measured: np.ndarray) -> float:
    s = float(np.std(measured))
    return s


def nrmse(measured: np.ndarray, simulated: np.ndarray) -> float:
    """rms(measured - simulated) / std(measured) (dimensionless).

    Returns inf when the measurement is constant and the error is not zero,
    0 when both are zero."""
    e = rms(np.asarray(measured, float) - np.asarray(simulated, float))
    s = _scale(measured)
    if s > 0.0:
        return e / s
    return 0.0 if e == 0.0 else float("inf")


@dataclass(frozen=True)
class OutputMetrics:
    """Metrics of one output.

    nrmse: rms(meas - sim)/std(meas) (-); rmse: rms(meas - sim) (output unit);
    max_abs: largest |meas - sim| (output unit) and t_max_abs the time (s) it
    happens; fit_percent: 100*(1 - nrmse) (%); bias: mean(meas - sim) (output
    unit); std: std(meas) (output unit)."""

    nrmse: float
    rmse: float
    max_abs: float
    t_max_abs: float
    fit_percent: float
    bias: float
    std: float

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def output_metrics(measured: np.ndarray, simulated: np.ndarray, time: np.ndarray) -> OutputMetrics:
    """All metrics of one output (arrays of equal length, time in s)."""
    measured = np.asarray(measured, dtype=float)
    simulated = np.asarray(simulated, dtype=float)
    err = measured - simulated
    k = int(np.argmax(np.abs(err))) if err.size else 0
    n = nrmse(measured, simulated)
    return OutputMetrics(
        nrmse=n,
        rmse=rms(err),
        max_abs=float(abs(err[k])) if err.size else float("nan"),
        t_max_abs=float(time[k]) if err.size else float("nan"),
        fit_percent=100.0 * (1.0 - n),
        bias=float(np.mean(err)) if err.size else float("nan"),
        std=_scale(measured),
    )

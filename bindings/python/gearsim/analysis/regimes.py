"""Operating regimes that physics cares about, and the model error in each.

A regime is a boolean mask over the samples, computed from measured signals
(never from the model under test, so that a wrong model cannot hide its own
failure):

=====================  ===================================================================
``direction_reversal``  within ``window`` of a sign change of the base speed
``torque_reversal``     within ``window`` after a sign change of the measured drive torque
``low_speed``           |base speed| below 5 % of its robust maximum (99th percentile)
``high_speed``          |base speed| above 60 % of its robust maximum
``low_load``            |drive torque| in its lowest third
``high_load``           |drive torque| in its highest third
``driving``             power flows from the drive to the load (drive power > 5 % of max)
``overrunning``         power flows back from the load into the drive (drive power < -5 % of max)
``temperature_low``,    thirds of the measured (or simulated) temperature, when it spans
``..._mid``, ``..._high``  more than 2 K
=====================  ===================================================================

Sign changes are detected with hysteresis (the signal must cross a band of
+-5 % of its robust maximum) on the zero-phase filtered signal, so noise near
zero does not make spurious reversals. ``window`` is 5 % of the median time
between reversals, clamped to [5 samples, 0.2 s].

The error in a regime is ``rms(residual in regime) / std(measured output)``
(the same normalisation as the overall nrmse, so the numbers compare), and the
ratio to the overall rms residual. A regime is *failing* when that ratio is
at least 1.5, the error in it is at least 1.5 times the output's noise floor
(the rms of the measurement's own broadband noise, signals.noise_rms), and
it holds at least 1 % of the samples.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .measurement import Measurement
from .signals import auto_cutoff, zero_phase_lowpass

__all__ = ["Regime", "segment", "regime_errors", "sign_changes", "FAILING_RATIO"]

FAILING_RATIO = 1.5


@dataclass(frozen=True)
class Regime:
    name: str
    mask: np.ndarray
    description: str

    @property
    def fraction(self) -> float:
        return float(np.mean(self.mask)) if self.mask.size else 0.0


def _robust_max(x: np.ndarray) -> float:
    return float(np.percentile(np.abs(x), 99.0)) if x.size else 0.0


def sign_changes(x: np.ndarray, band: float) -> np.ndarray:
    """Indices where x changes sign, with hysteresis: the sign only flips once
    x has crossed to the other side of +-band. Returns the sample index at
    which the new sign is confirmed, moved back to the last zero crossing."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return np.zeros(0, dtype=int)
    state = np.zeros(x.size, dtype=np.int8)
    state[x > band] = 1
    state[x < -band] = -1
    nz = np.nonzero(state)[0]
    if nz.size < 2:
        return np.zeros(0, dtype=int)
    s = state[nz]
    flips = np.nonzero(s[1:] != s[:-1])[0]
    events = []
    sg = np.signbit(x)
    for f in flips:
        a, b = nz[f], nz[f + 1]  # last sample of old sign beyond band, first of new
        seg = sg[a : b + 1]
        cross = np.nonzero(seg != seg[0])[0]
        events.append(a + (int(cross[0]) if cross.size else b - a))
    return np.asarray(events, dtype=int)


def _windows(n: int, events: np.ndarray, before: int, after: int) -> np.ndarray:
    mask = np.zeros(n, dtype=bool)
    if events.size == 0:
        return mask
    delta = np.zeros(n + 1, dtype=np.int32)
    lo = np.clip(events - before, 0, n)
    hi = np.clip(events + after + 1, 0, n)
    np.add.at(delta, lo, 1)
    np.add.at(delta, hi, -1)
    return np.cumsum(delta[:-1]) > 0


def _smooth(x: np.ndarray, fs: float) -> np.ndarray:
    fc = auto_cutoff(x, fs)
    return x if fc is None else zero_phase_lowpass(x, fc, fs)


def reversal_window(events: np.ndarray, n: int, dt: float) -> int:
    """Window length (samples) around reversals: 5 % of the median time
    between them, clamped to [5 samples, 0.2 s]."""
    if events.size >= 2:
        gap = float(np.median(np.diff(events)))
    else:
        gap = float(n)
    w = int(round(0.05 * gap))
    return int(min(max(w, 5), max(5, int(round(0.2 / dt)))))


def segment(meas: Measurement, temperature: np.ndarray | None = None) -> list[Regime]:
    """The regimes of a measurement (see the module docstring). temperature:
    a simulated temperature to band when the measurement has none."""
    spec = meas.spec
    fs = 1.0 / meas.dt
    n = meas.n
    w = _smooth(meas[spec.speed_input], fs)
    tq = _smooth(meas[spec.torque_output], fs)
    wmax = _robust_max(w)
    tmax = _robust_max(tq)
    regimes: list[Regime] = []

    ev_w = sign_changes(w, 0.05 * wmax)
    win = reversal_window(ev_w, n, meas.dt)
    regimes.append(
        Regime(
            "direction_reversal",
            _windows(n, ev_w, win, win),
            f"within {win * meas.dt * 1e3:.0f} ms of a reversal of the {spec.speed_input} "
            f"({ev_w.size} reversals)",
        )
    )
    ev_t = sign_changes(tq, 0.05 * tmax)
    win_t = reversal_window(ev_t, n, meas.dt)
    regimes.append(
        Regime(
            "torque_reversal",
            _windows(n, ev_t, 0, win_t),
            f"within {win_t * meas.dt * 1e3:.0f} ms after a sign change of the measured "
            f"{spec.torque_output} ({ev_t.size} reversals)",
        )
    )
    aw = np.abs(w)
    regimes.append(Regime("low_speed", aw < 0.05 * wmax, "|speed| below 5 % of its maximum"))
    regimes.append(Regime("high_speed", aw > 0.6 * wmax, "|speed| above 60 % of its maximum"))
    at = np.abs(tq)
    if at.size and np.ptp(at) > 0:
        lo, hi = np.percentile(at, [100 / 3, 200 / 3])
        regimes.append(Regime("low_load", at <= lo, f"|{spec.torque_output}| in its lowest third"))
        regimes.append(
            Regime("high_load", at >= hi, f"|{spec.torque_output}| in its highest third")
        )
    p = tq * w
    pmax = _robust_max(p)
    regimes.append(Regime("driving", p > 0.05 * pmax, "power flows from the drive into the load"))
    regimes.append(
        Regime(
            "overrunning",
            p < -0.05 * pmax,
            "power flows back from the load into the drive (load overruns)",
        )
    )
    temp = meas["temperature"] if meas.has_temperature else temperature
    if temp is not None and np.ptp(temp) > 2.0:
        t1, t2 = np.percentile(temp, [100 / 3, 200 / 3])
        regimes.append(Regime("temperature_low", temp <= t1, f"temperature <= {t1:.1f} K"))
        regimes.append(
            Regime(
                "temperature_mid",
                (temp > t1) & (temp < t2),
                f"{t1:.1f} K < temperature < {t2:.1f} K",
            )
        )
        regimes.append(Regime("temperature_high", temp >= t2, f"temperature >= {t2:.1f} K"))
    return regimes


def regime_errors(
    regimes: list[Regime],
    residuals: dict[str, np.ndarray],
    scales: dict[str, float],
    noise: dict[str, float] | None = None,
) -> list[dict]:
    """Per regime: fraction of samples, and per output the regime nrmse
    (rms of the residual in the regime / std of the measured output) and its
    ratio to the overall rms residual; `failing` marks the regimes where some
    output's ratio is >= FAILING_RATIO while its error there is also at least
    FAILING_RATIO times the output's noise floor (noise: the rms of the
    measurement's own noise per output, signals.noise_rms; an error at the
    noise or the quantization level fails nothing), and the regime holds
    >= 1 % of samples."""
    out = []
    noise = noise or {}
    overall = {k: float(np.sqrt(np.mean(r * r))) for k, r in residuals.items()}
    for reg in regimes:
        m = reg.mask
        entry: dict[str, Any] = {
            "regime": reg.name,
            "description": reg.description,
            "fraction": reg.fraction,
            "samples": int(m.sum()),
            "outputs": {},
        }
        worst = 0.0
        fails = False
        for k, r in residuals.items():
            if m.any():
                e = float(np.sqrt(np.mean(r[m] ** 2)))
                mean = float(np.mean(r[m]))
            else:
                e, mean = float("nan"), float("nan")
            s = scales.get(k, 0.0)
            ratio = e / overall[k] if overall[k] > 0 and m.any() else float("nan")
            floor = float(noise.get(k, 0.0))
            above = bool(np.isfinite(e) and e >= FAILING_RATIO * floor)
            entry["outputs"][k] = {
                "nrmse": e / s if s > 0 else float("nan"),
                "ratio": ratio,
                "bias": mean / s if s > 0 else float("nan"),
                "noise_floor": floor / s if s > 0 else float("nan"),
                "above_noise": above,
            }
            if np.isfinite(ratio):
                worst = max(worst, ratio)
                if ratio >= FAILING_RATIO and above:
                    fails = True
        entry["worst_ratio"] = worst
        entry["failing"] = bool(fails and reg.fraction >= 0.01)
        out.append(entry)
    return out

"""A logger lag of the torque channel: the simulated torque is delayed by
torque_delay (model file [analysis] table) before it is compared. Its
signature: the residual correlates with the derivative of the simulated
torque (:func:`delay_signature`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import modelkit as mk
from .base import Changes, Column, Effect, FitParam, Screening, as_coestimated, cached, seed_of


@dataclass(frozen=True)
class DelaySignature:
    """Cross-correlation of the torque residual with the derivative of the
    simulated torque.

    lags_s: the lags (s); correlation: the normalised cross-correlation
    sum r(t) y'(t - lag) / (|r| |y'|) at each lag; peak_lag_s: where its
    magnitude peaks (sub-sample, parabolic interpolation); peak_r: its value
    there; gain_s: the regression coefficient of r on y'(t - peak_lag).
    A measured torque that lags the model by d gives r(t) = y(t - d) - y(t)
    ~ -d y'(t - d/2): a peak at d/2 with gain -d, so delay_s = -gain_s."""

    lags_s: np.ndarray
    correlation: np.ndarray
    peak_lag_s: float
    peak_r: float
    gain_s: float

    @property
    def delay_s(self) -> float:
        return -self.gain_s


def _xcorr(r: np.ndarray, d: np.ndarray, max_lag: int) -> np.ndarray:
    """c[L + max_lag] = sum_k r[k] d[k - L] for L in -max_lag..max_lag (FFT)."""
    n = r.size
    size = 1 << int(np.ceil(np.log2(2 * n)))
    full = np.fft.irfft(np.fft.rfft(r, size) * np.conj(np.fft.rfft(d, size)), size)
    return np.concatenate([full[size - max_lag :], full[: max_lag + 1]])


def delay_signature(
    residual: np.ndarray, output: np.ndarray, dt: float, max_lag_s: float = 0.1
) -> DelaySignature:
    """The cross-correlation lag between a residual and the derivative of an
    output (see DelaySignature). max_lag_s is cut to a quarter of the record."""
    from ..signatures import parabolic_peak
    from ..simulate import delayed

    r = np.asarray(residual, dtype=float) - np.mean(residual)
    d = np.gradient(np.asarray(output, dtype=float), dt)
    d = d - d.mean()
    m = int(max(1, min(round(max_lag_s / dt), r.size // 4)))
    den = float(np.linalg.norm(r) * np.linalg.norm(d))
    c = _xcorr(r, d, m) / den if den > 0 else np.zeros(2 * m + 1)
    lags = np.arange(-m, m + 1) * dt
    i = int(np.argmax(np.abs(c)))
    pos, height = parabolic_peak(c, i)
    peak_lag = (pos - m) * dt
    shifted = delayed(d, peak_lag / dt)
    ss = float(np.dot(shifted, shifted))
    gain = float(np.dot(r, shifted) / ss) if ss > 0 else 0.0
    return DelaySignature(lags, c, float(peak_lag), float(height), gain)


def _torque_rate(ctx: Any) -> np.ndarray:
    """d/dt of the simulated drive torque (undelayed), N*m/s."""
    from ..simulate import delayed

    def make() -> np.ndarray:
        y = ctx.sim.outputs[ctx.torque_output]
        # the simulation applies the model's present delay; take it back out
        d = mk.torque_delay(ctx.model)
        y = delayed(y, -d / ctx.meas.dt) if d else y
        return np.gradient(y, ctx.meas.dt)

    return cached(ctx, "torque_rate", make)


class SensorDelay(Effect):
    """A logger lag of the torque channel: the simulated torque is delayed by
    torque_delay (model file [analysis] table) before it is compared."""

    name = "sensor_delay"
    summary = (
        "delay of the measured torque relative to the speed channels ([analysis] torque_delay)"
    )
    signature_text = (
        "residual correlates with the derivative of the simulated torque, peaking at half the delay"
    )
    excitation = "steps of acceleration (a delay shifts the torque steps, an inertia scales them)"
    separated_from = {
        "compliance": "steps of acceleration: a delay shifts the torque step, a compliant "
        "shaft rings after it",
        "inertia": "steps of acceleration: a delay shifts the torque step, an inertia scales it",
    }
    #: the largest delay searched (s): loggers lag by milliseconds
    MAX_DELAY = 0.1

    def present(self, model: Any) -> bool:
        return mk.torque_delay(model) != 0.0

    def columns(self, ctx: Any) -> list[Column]:
        # first order: y(t - d) - y(t) ~ -d y'(t), in driven units
        col = -_torque_rate(ctx) / ctx.kin
        return [("torque_delay", col, (-self.MAX_DELAY, self.MAX_DELAY))]

    def signature(self, ctx: Any) -> DelaySignature:
        return delay_signature(
            ctx.residual[ctx.torque_output],
            ctx.meas[ctx.torque_output] - ctx.residual[ctx.torque_output],
            ctx.meas.dt,
            self.MAX_DELAY,
        )

    def _span(self, ctx: Any, seed: float) -> float:
        return float(min(self.MAX_DELAY, max(20.0 * ctx.meas.dt, 4.0 * abs(seed))))

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        cur = mk.torque_delay(ctx.model)
        x0 = cur + seed_of(screening, "torque_delay")
        lim = self._span(ctx, x0)
        return [
            FitParam(
                "torque_delay",
                x0,
                -lim,
                lim,
                "s",
                before=cur,
                owner=self.name,
                # the interpolated delay is piecewise linear between samples:
                # an absolute step of a twentieth of a sample
                diff_step=0.05 * ctx.meas.dt,
            )
        ]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "torque_delay" not in values:
            return {}, {}
        return {}, {}, {"torque_delay": float(values["torque_delay"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"torque_delay": mk.torque_delay(model)}

    def inconsistent(self, ctx: Any, model: Any) -> str | None:
        """A delay d makes the residual correlate with the simulated torque's
        derivative most at a lag of d/2, with the sign opposite to d's: a
        fitted delay the correlation does not show stands in for another
        effect (in the bundled demo, a missing viscous friction)."""
        d = mk.torque_delay(model)
        if d == 0.0:
            return None
        sig = self.signature(ctx)
        if sig.peak_r * sig.peak_lag_s < 0 and sig.peak_lag_s * d > 0:
            return None
        return (
            f"the fitted delay {1e3 * d:.3g} ms is not what the residual shows (its correlation "
            f"with the simulated torque's derivative peaks at {1e3 * sig.peak_lag_s:.3g} ms with "
            f"r = {sig.peak_r:.2f}; a delay d peaks at d/2 with the opposite sign)"
        )

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        return [as_coestimated(p) for p in self.parameters(ctx, screening)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        sig = self.signature(ctx)
        # a pure delay d peaks at d/2 with a correlation of the opposite sign
        # to d: the peak is a delay's only when the two signs disagree
        delay_like = bool(sig.peak_r * sig.peak_lag_s < 0)
        ev = {
            "peak_lag_s": sig.peak_lag_s,
            "peak_correlation": sig.peak_r,
            "delay_like": delay_like,
            "delay_from_correlation_s": 2.0 * sig.peak_lag_s if delay_like else None,
        }
        if model is not None:
            ev["fitted_delay_s"] = mk.torque_delay(model)
        return ev

    def describe(self, ctx, ev, model=None) -> str | None:
        r, lag = ev["peak_correlation"], ev["peak_lag_s"]
        head = (
            f"the residual correlates with the derivative of the simulated torque (r = {r:.2f} "
            f"at a lag of {1e3 * lag:.2f} ms)"
        )
        if not ev["delay_like"]:
            return (
                f"{head}: not a delay's correlation (a delay d peaks at d/2 with the opposite "
                f"sign); largest in {ev['regime']}"
            )
        d = ev["delay_from_correlation_s"]
        way = "lagged" if d > 0 else "led"
        text = f"{head}: as if the measured torque {way} the model by {1e3 * abs(d):.2f} ms"
        if "fitted_delay_s" in ev:
            text += f" (fitted: {1e3 * ev['fitted_delay_s']:.2f} ms)"
        return f"{text}; largest in {ev['regime']}"

    def plot(self, ctx: Any, ax: Any) -> None:
        sig = self.signature(ctx)
        ax.plot(1e3 * sig.lags_s, sig.correlation, lw=1)
        ax.axvline(1e3 * sig.peak_lag_s, color="C3", ls="--", lw=1)
        ax.set_xlabel("lag (ms)")
        ax.set_ylabel("corr(residual, d torque/dt)")
        # a pure delay d peaks at d/2 with a negative correlation
        ax.set_title(
            f"sensor_delay: peak r = {sig.peak_r:.2f} at {1e3 * sig.peak_lag_s:.2f} ms "
            "(a delay d peaks at d/2, r < 0)"
        )

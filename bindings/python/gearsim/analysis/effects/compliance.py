"""Compliance between the drive and the driven side (eq. 11.2-11.4): a
torsional spring-damper from the drive to the base gear, which turns with
base_inertia. The rigid model's residual then rings at the natural
frequency: a peak in its spectrum (:func:`resonance`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import modelkit as mk
from .base import Changes, Effect, FitParam, Screening, rig_has


@dataclass(frozen=True)
class Resonance:
    """The residual's power spectrum (Welch) and its strongest peak.

    freq_hz, psd: the spectrum; peak_hz: the peak (parabolic interpolation
    on log power); prominence: peak power / median power of the band
    searched; damping_ratio: half the relative -3 dB width of the peak
    (NaN when the peak is not resolved); band_share: share of the
    residual's power within the peak's -3 dB band widened 2x."""

    freq_hz: np.ndarray
    psd: np.ndarray
    peak_hz: float
    prominence: float
    damping_ratio: float
    band_share: float


def resonance(residual: np.ndarray, dt: float, min_hz: float | None = None) -> Resonance:
    """Spectrum of a residual and its strongest peak above min_hz (default:
    four frequency bins) and below 0.4/dt."""
    from scipy.signal import welch

    from ..signatures import parabolic_peak

    r = np.asarray(residual, dtype=float)
    n = r.size
    nper = int(min(n, max(256, 2 ** int(np.log2(max(n // 8, 2))))))
    f, p = welch(r - r.mean(), fs=1.0 / dt, nperseg=nper, detrend="linear")
    lo = 4.0 * f[1] if min_hz is None else max(min_hz, f[1])
    band = (f >= lo) & (f <= 0.4 / dt)
    if not band.any() or not np.any(p[band] > 0):
        return Resonance(f, p, float("nan"), 0.0, float("nan"), 0.0)
    idx = np.nonzero(band)[0]
    i = int(idx[np.argmax(p[idx])])
    logp = np.log(np.maximum(p, 1e-300))
    pos, _ = parabolic_peak(logp, i)
    df = f[1] - f[0]
    peak_hz = float(f[0] + pos * df)
    # prominence against the local floor: the median power over an octave on
    # each side, the peak's own bins left out (a residual's broad low-frequency
    # content is no resonance)
    local = (f >= 0.5 * f[i]) & (f <= 2.0 * f[i]) & (np.abs(f - f[i]) > 3.0 * (f[1] - f[0]))
    floor = np.median(p[local]) if local.any() else np.median(p[idx])
    prominence = float(p[i] / max(floor, 1e-300))
    # -3 dB width: walk down each side to half the peak power
    half = 0.5 * p[i]
    left = i
    while left > 0 and p[left] > half:
        left -= 1
    right = i
    while right < p.size - 1 and p[right] > half:
        right += 1
    width = (right - left) * df
    zeta = float(0.5 * width / peak_hz) if right - left > 2 and peak_hz > 0 else float("nan")
    wide = (f >= peak_hz - width) & (f <= peak_hz + width)
    share = float(p[wide].sum() / p.sum()) if p.sum() > 0 else 0.0
    return Resonance(f, p, peak_hz, prominence, zeta, share)


def band_prominence(res: Resonance) -> float:
    """The peak's power over the median of the octave on each side,
    leaving out the peak's whole -3 dB band rather than three bins. A
    drive shaft does not ring at one frequency: with the motor held
    still it rings at sqrt(k/J_eff), while the motor moves the
    frequency rises, and the rigid model's residual also keeps what the
    input filter cut from the ring; the peak's own shoulders are no
    floor. A narrow peak keeps about the prominence of the spectrum."""
    f, p = res.freq_hz, res.psd
    if not np.isfinite(res.peak_hz) or f.size < 2:
        return float(res.prominence)
    i = int(np.argmin(np.abs(f - res.peak_hz)))
    half = 0.5 * p[i]
    left, right = i, i
    while left > 0 and p[left] > half:
        left -= 1
    while right < p.size - 1 and p[right] > half:
        right += 1
    octave = (f >= 0.5 * f[i]) & (f <= 2.0 * f[i])
    outside = octave & ((f < f[left]) | (f > f[right]))
    if np.count_nonzero(outside) < 5:  # too few bins for a median
        return float(res.prominence)
    return float(p[i] / max(float(np.median(p[outside])), 1e-300))


@dataclass(frozen=True)
class ComplianceScreening(Screening):
    """The compliance screening: the residual spectrum's strongest peak and
    its prominence against the band around it."""

    resonance: Resonance | None = None
    prominence: float = 0.0


class Compliance(Effect):
    """A torsional spring-damper between the drive and the base gear, which
    turns with base_inertia (eq. 11.2-11.4). The rigid model's residual then
    rings at the shaft's natural frequency: a peak in its spectrum, which
    seeds the stiffness through omega_n^2 = k / J_eff."""

    name = "compliance"
    summary = (
        "compliant base shaft: torsional stiffness and damping between the drive and the base "
        "gear (rig compliance_stiffness, compliance_damping; base_inertia given or set)"
    )
    signature_text = (
        "residual power at a resonance: a peak in the residual spectrum, ringing after steps"
    )
    n_params = 2
    excitation = "steps of acceleration (the shaft rings after each)"
    separated_from = {
        "inertia": "steps of acceleration: the shaft rings after a step, an inertia error does not",
        "viscous_friction": "steps of acceleration between two held speeds",
    }
    internal_excitation = "steps of acceleration of several sizes"
    #: a spectral peak less prominent than this (peak / median of the octave
    #: around it outside the peak's -3 dB band, band_prominence)
    #: is no resonance: screening rules the effect out
    MIN_PROMINENCE = 8.0
    #: the base inertia seeded, as a fraction of the driven inertia seen at the base
    BASE_INERTIA_SEED = 0.2

    def unavailable(self, model: Any) -> str | None:
        why = rig_has(model, "compliance_stiffness")
        if why:
            return why
        if mk.rig_values(model).get("base_drive", "speed") != "speed":
            return "a compliant shaft needs a speed-driven base"
        if mk.block_values(model).get("backlash_enabled", False):
            return "a compliant shaft needs a rigid mesh (the model has backlash)"
        return None

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0

    def screen(self, ctx: Any) -> ComplianceScreening:
        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        prom = band_prominence(res)
        tn = ctx.base_nrmse[ctx.torque_output]
        left = tn * np.sqrt(max(1.0 - res.band_share, 0.0)) if prom else tn
        why = None
        if not (np.isfinite(res.peak_hz) and prom >= self.MIN_PROMINENCE):
            why = (
                f"the residual spectrum has no resonance peak (strongest {prom:.1f}x "
                f"its local floor, {self.MIN_PROMINENCE:g}x needed)"
            )
        return ComplianceScreening(float(ctx.overall_nrmse(left)), None, why, res, prom)

    @staticmethod
    def reflected_inertia(model: Any) -> float:
        """The driven inertia seen at the base shaft, a^2 J_F (kg*m^2)."""
        j = float(mk.rig_values(model)[mk.driven_inertia_key(model)])
        return mk.kinematic_ratio(model) ** 2 * j

    def base_inertia(self, ctx: Any) -> float:
        """The base gear's inertia: given (rig base_inertia > 0), else
        BASE_INERTIA_SEED of the driven inertia seen at the base. Only the sum
        J_B + k^2 J_driven is seen on a speed-driven rig (eq. 11.3-11.4: the
        shaft torque accelerates both alike), so it is not fitted: the
        co-estimated driven inertia takes the rest."""
        given = float(mk.rig_values(ctx.model).get("base_inertia", 0.0))
        return given if given > 0 else self.BASE_INERTIA_SEED * self.reflected_inertia(ctx.model)

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        # fitted as the natural frequency and damping ratio of eq. 11.4: the
        # stiffness alone trades off with the co-estimated inertia (both
        # move the frequency), the frequency does not
        res = getattr(screening, "resonance", None)
        f0 = float(res.peak_hz) if res is not None else float("nan")
        if not np.isfinite(f0) or f0 <= 0:
            f0 = 0.05 / ctx.meas.dt
        zeta = res.damping_ratio if res is not None else float("nan")
        zeta = float(zeta) if np.isfinite(zeta) else 0.05
        o = self.name
        return [
            FitParam(
                "compliance_natural_frequency",
                f0,
                0.2 * f0,
                min(5.0 * f0, 0.5 / ctx.meas.dt),
                "Hz",
                owner=o,
                # a lightly damped ring runs through many cycles: a 1 %
                # frequency error turns its phase around, so look close first
                grid=(0.98, 0.99, 1.0, 1.01, 1.02),
                diff_step=1e-5,
            ),
            FitParam(
                "compliance_damping_ratio",
                min(max(zeta, 0.005), 0.5),
                0.0,
                2.0,
                "",
                owner=o,
                diff_step=1e-4,
            ),
        ]

    def _effective_inertia(self, ctx: Any, values: Mapping[str, float]) -> float:
        key = mk.driven_inertia_key(ctx.model)
        j = float(values.get(key, mk.rig_values(ctx.model)[key]))
        return self.base_inertia(ctx) + mk.kinematic_ratio(ctx.model) ** 2 * j

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "compliance_natural_frequency" in values:
            wn = 2.0 * np.pi * float(values["compliance_natural_frequency"])
            zeta = float(values["compliance_damping_ratio"])
        elif "compliance_stiffness" in values:  # present, re-estimated
            k, c = float(values["compliance_stiffness"]), float(values["compliance_damping"])
            return {}, {"compliance_stiffness": k, "compliance_damping": c}
        else:
            return {}, {}
        j = self._effective_inertia(ctx, values)
        k = wn**2 * j
        return {}, {
            "compliance_stiffness": k,
            "compliance_damping": 2.0 * zeta * np.sqrt(k * j),
            "base_inertia": self.base_inertia(ctx),
        }

    def notes(self, model: Any) -> list[str]:
        return [
            "on a speed-driven rig only the sum base_inertia + (driven speed / base speed)^2 x "
            "driven inertia is seen; base_inertia is kept (given, or "
            f"{self.BASE_INERTIA_SEED:g} of the driven inertia seen at the base) and the driven "
            "inertia takes the rest"
        ]

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        out = {k: rig[k] for k in ("compliance_stiffness", "compliance_damping", "base_inertia")}
        j = float(rig["base_inertia"]) + self.reflected_inertia(model)
        k = float(rig["compliance_stiffness"])
        if k > 0 and j > 0:
            out["natural_frequency_hz"] = float(np.sqrt(k / j) / (2.0 * np.pi))
        return out

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        out = []
        for key, unit in (("compliance_stiffness", "N*m/rad"), ("compliance_damping", "N*m*s/rad")):
            now = float(rig[key])
            lo, hi = (1e-2 * now, 1e2 * now) if now > 0 else (0.0, 1.0)
            out.append(
                FitParam(key, now, lo, hi, unit, "coestimated", now, self.name, diff_step=1e-4)
            )
        return out

    def evidence(self, ctx: Any, screening: Screening) -> dict[str, Any]:
        res = screening.resonance
        return {
            "signature": self.signature_text,
            "peak_hz": res.peak_hz,
            "prominence": screening.prominence,
            "damping_ratio": res.damping_ratio,
            "band_share": res.band_share,
            "regime": None,
            "text": (
                f"the torque residual's spectrum peaks at {res.peak_hz:.1f} Hz, "
                f"{screening.prominence:.1f}x its local floor, holding {100 * res.band_share:.0f} % "
                "of the residual power: a resonance a rigid shaft cannot ring at"
            ),
        }

    def plot(self, ctx: Any, ax: Any) -> None:
        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        ax.semilogy(res.freq_hz[1:], res.psd[1:], lw=1)
        if np.isfinite(res.peak_hz):
            ax.axvline(res.peak_hz, color="C3", ls="--", lw=1)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("residual power density")
        ax.set_title(f"compliance: residual spectrum, peak {res.peak_hz:.1f} Hz")

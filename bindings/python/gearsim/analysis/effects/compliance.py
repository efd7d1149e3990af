"""Compliance between the drive and the driven side (eq. 11.2-11.4): a
torsional spring-damper from the drive to the base gear, which turns with
base_inertia (0 unless given: the spring then acts at the mesh, a compliant
mesh). Two signatures in the rigid model's residual:

- it rings at the natural frequency: a peak in its spectrum
  (:func:`resonance`), when the mode is lightly damped;
- at each direction reversal the driven side's friction reverses through the
  spring, so the measured torque reverses later than the rigid model's: the
  torque residual repeats one transient after every reversal of the driven
  speed (:func:`reversal_transient`), whether or not the mode rings.

The friction of the driven side behind the spring creeps (rig
load_friction_regularised): near rest it acts as a damper in series with
the spring, so its smoothing speed load_coulomb_speed_threshold is fitted
with the spring when the model has a friction."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import modelkit as mk
from ..regimes import reversal_window, sign_changes
from .base import Changes, Effect, FitParam, Screening, fmt, rig_has, speed_scale, speed_unit


@dataclass(frozen=True)
class Resonance:
    """The residual's power spectrum (Welch's method) and its strongest peak.

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
    from ..signals import _psd
    from ..signatures import parabolic_peak

    r = np.asarray(residual, dtype=float)
    n = r.size
    nper = int(min(n, max(256, 2 ** int(np.log2(max(n // 8, 2))))))
    # Welch's averaged periodogram (Hann, half overlap): only ratios of it
    # are used, so its scaling does not matter
    f, p = _psd(r - r.mean(), 1.0 / dt, nseg=nper)
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
class ReversalTransient:
    """The driven-side torque residual around reversals of the driven speed.

    reversals: how many; before/after: samples of the window taken before
    and after each; time_share: share of the record inside the windows;
    profile: the event-locked mean of the residual times the sign of the new
    speed (driven units; negative: the measured force reverses later than
    the model's); explained_share: share of the whole residual's energy
    that this one transient explains; peak: its largest magnitude (signed);
    peak_time_s: when it happens after the reversal; half_time_s: how long
    it stays above half of it."""

    reversals: int
    before: int
    after: int
    time_share: float
    profile: np.ndarray
    explained_share: float
    peak: float
    peak_time_s: float
    half_time_s: float


def reversal_transient(
    r_d: np.ndarray, v: np.ndarray, dt: float, total_energy: float | None = None
) -> ReversalTransient:
    """The transient the residual r_d repeats after each reversal of the
    driven speed v: the event-locked mean of sign(new v)*r_d over a window
    of a quarter of regimes.reversal_window before the reversal to one
    window after it, and the share of the residual's energy it explains
    (of total_energy when given: the energy of the residual r_d was cleaned
    from)."""
    r = np.asarray(r_d, dtype=float)
    v = np.asarray(v, dtype=float)
    band = 0.05 * (float(np.percentile(np.abs(v), 99)) or 1.0)
    events = sign_changes(v, band)
    w = reversal_window(events, r.size, dt)
    before, after = max(1, w // 4), w
    keep = events[(events >= before) & (events + after <= r.size)]
    empty = ReversalTransient(int(keep.size), before, after, 0.0, np.zeros(0), 0.0, 0.0, 0.0, 0.0)
    total = float(np.sum(r * r)) if total_energy is None else float(total_energy)
    if keep.size < 3 or total <= 0:
        return empty
    idx = keep[:, None] + np.arange(-before, after)[None, :]
    sign = np.sign(v[np.minimum(keep + 3, v.size - 1)])
    sign[sign == 0] = 1.0
    segs = r[idx] * sign[:, None]
    profile = segs.mean(axis=0)
    explained = float(np.sum(segs**2) - np.sum((segs - profile) ** 2)) / total
    k = int(np.argmax(np.abs(profile[before:]))) + before
    peak = float(profile[k])
    above = np.nonzero(np.abs(profile[before:]) >= 0.5 * abs(peak))[0]
    half = float(above.size) * dt
    return ReversalTransient(
        int(keep.size),
        before,
        after,
        float(keep.size * (before + after) / r.size),
        profile,
        max(explained, 0.0),
        peak,
        (k - before) * dt,
        half,
    )


@dataclass(frozen=True)
class ComplianceScreening(Screening):
    """The compliance screening: the residual spectrum's strongest peak and
    its prominence against the band around it, and the transient the
    residual repeats after each reversal of the driven speed."""

    resonance: Resonance | None = None
    prominence: float = 0.0
    transient: ReversalTransient | None = None


class Compliance(Effect):
    """A torsional spring-damper between the drive and the base gear, which
    turns with base_inertia (eq. 11.2-11.4; with base_inertia 0 the spring
    acts at the mesh). Fitted as its natural frequency and damping ratio
    (the stiffness alone trades off with the co-estimated inertia), and,
    when the model has a driven-side friction, that friction's smoothing
    speed: behind a spring the friction creeps (load_friction_regularised)."""

    name = "compliance"
    summary = (
        "compliance between the drive and the driven side: a torsional spring-damper at the "
        "mesh or in the base shaft (rig compliance_stiffness, compliance_damping; base_inertia "
        "given or 0), the driven side's friction creeping behind it"
    )
    signature_text = (
        "the torque residual repeats one transient after every reversal of the driven speed, "
        "or rings at a resonance"
    )
    n_params = 2
    #: sub-stepped, and it moves the driven speed off the kinematics
    costly = True
    excitation = "steps of acceleration and reversals of the motion under friction"
    separated_from = {
        "inertia": "steps of acceleration: the shaft rings after a step, an inertia error does not",
        "viscous_friction": "steps of acceleration between two held speeds",
        "sensor_delay": "reversals of the motion and steps of acceleration: a delay shifts the "
        "whole torque, a compliance only delays what passes through friction at reversals",
        "coulomb_friction": "reverse slowly and quickly: a compliance delays the friction's "
        "reversal by a displacement, a Coulomb level flips within the speed band",
    }
    internal_excitation = (
        "steps of acceleration of several sizes (stiffness and damping) and slow reversals "
        "under friction (the friction's smoothing speed)"
    )
    #: a spectral peak less prominent than this (peak / median of the octave
    #: around it outside the peak's -3 dB band, band_prominence)
    #: is no resonance
    MIN_PROMINENCE = 8.0
    #: a reversal transient explaining less than this share of the residual's
    #: energy is no sign of compliance (with no resonance either, screening
    #: rules the effect out)
    MIN_REVERSAL_SHARE = 0.03
    #: natural frequencies searched, as fractions of the sampling rate, when
    #: no resonance peak seeds it: the band the record resolves where a well
    #: damped mode need not ring visibly
    FREQUENCY_GRID = (1.0 / 40.0, 1.0 / 20.0, 1.0 / 10.0, 1.0 / 5.0)

    def unavailable(self, model: Any) -> str | None:
        why = rig_has(model, "compliance_stiffness")
        if why:
            return why
        if mk.rig_values(model).get("base_drive", "speed") != "speed":
            return "a compliant shaft needs a speed-driven base"
        if mk.block_values(model).get("backlash_enabled", False):
            return (
                "a compliant shaft needs a rigid mesh: backlash already makes the mesh compliant "
                "(its contact stiffness and damping)"
            )
        return None

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0

    @staticmethod
    def has_friction(model: Any) -> bool:
        """The driven side has a friction whose smoothing the spring exposes."""
        rig = mk.rig_values(model)
        return (
            float(rig.get("load_coulomb_friction", 0.0)) > 0.0
            or float(rig.get("load_breakaway_friction", 0.0)) > 0.0
        )

    #: the columns of the rigid friction and loss family a reversal transient
    #: must not be (a Coulomb step, a viscous slope, an offset, a meshing loss)
    RIGID_FAMILY = ("sign", "speed", "constant", "mesh")

    def rigid_cleaned(self, ctx: Any) -> np.ndarray:
        """The driven-side residual without what the co-estimated parameters
        and the rigid friction family explain (least squares): a Coulomb
        step the model lacks is locked to the reversals too, but a rigid
        friction makes it; what is left at the reversals is what no rigid
        friction can make."""
        from .registry import nuisance_columns

        cols = [c[1] for c in nuisance_columns(ctx, self)]
        cols += [ctx.columns[name] for name in self.RIGID_FAMILY if name in ctx.columns]
        X = np.column_stack(cols)
        coef, *_ = np.linalg.lstsq(X[ctx.idx], ctx.r_d[ctx.idx], rcond=None)
        return ctx.r_d - X @ coef

    def screen(self, ctx: Any) -> ComplianceScreening:
        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        prom = band_prominence(res)
        tr = reversal_transient(
            self.rigid_cleaned(ctx), ctx.v, ctx.meas.dt, float(np.sum(ctx.r_d**2))
        )
        ringing = bool(np.isfinite(res.peak_hz) and prom >= self.MIN_PROMINENCE)
        reversing = tr.explained_share >= self.MIN_REVERSAL_SHARE
        share = max(res.band_share if ringing else 0.0, tr.explained_share if reversing else 0.0)
        tn = ctx.base_nrmse[ctx.torque_output]
        left = tn * np.sqrt(max(1.0 - share, 0.0))
        why = None
        if not (ringing or reversing):
            why = (
                f"the residual spectrum has no resonance peak (strongest {prom:.1f}x its local "
                f"floor, {self.MIN_PROMINENCE:g}x needed) and no transient repeats after the "
                f"reversals ({100 * tr.explained_share:.1f} % of the residual energy, "
                f"{100 * self.MIN_REVERSAL_SHARE:g} % needed)"
            )
        return ComplianceScreening(float(ctx.overall_nrmse(left)), None, why, res, prom, tr)

    @staticmethod
    def reflected_inertia(model: Any) -> float:
        """The driven inertia seen at the base shaft, a^2 J_F (kg*m^2)."""
        j = float(mk.rig_values(model)[mk.driven_inertia_key(model)])
        return mk.kinematic_ratio(model) ** 2 * j

    @staticmethod
    def base_inertia(ctx: Any) -> float:
        """The base gear's inertia behind the spring: given (rig base_inertia),
        else 0, the spring acting at the mesh. Only the sum J_B + k^2 J_driven
        is seen on a speed-driven rig (eq. 11.3-11.4: the spring accelerates
        both alike), so it is not fitted: the co-estimated driven inertia
        takes the rest."""
        return float(mk.rig_values(ctx.model).get("base_inertia", 0.0))

    def _ringing(self, screening: Screening | None) -> Resonance | None:
        res = getattr(screening, "resonance", None)
        prom = float(getattr(screening, "prominence", 0.0))
        if res is None or not np.isfinite(res.peak_hz) or prom < self.MIN_PROMINENCE:
            return None
        return res

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        # fitted as the natural frequency and damping ratio of eq. 11.4: the
        # stiffness alone trades off with the co-estimated inertia (both
        # move the frequency), the frequency does not
        fs = 1.0 / ctx.meas.dt
        res = self._ringing(screening)
        o = self.name
        if res is not None:
            f0 = float(res.peak_hz)
            zeta = float(res.damping_ratio) if np.isfinite(res.damping_ratio) else 0.05
            # a lightly damped ring runs through many cycles: a 1 % frequency
            # error turns its phase around, so look close first
            z_grid: tuple[float, ...]
            f_grid, z_grid = (0.98, 0.99, 1.0, 1.01, 1.02), ()
            zeta = min(max(zeta, 0.005), 0.5)
        else:
            f0 = self.FREQUENCY_GRID[1] * fs
            f_grid = tuple(g * fs / f0 for g in self.FREQUENCY_GRID)
            zeta, z_grid = 0.3, (0.5, 1.0, 2.0)
        out = [
            FitParam(
                "compliance_natural_frequency",
                f0,
                min(0.2 * f0, 0.01 * fs),
                0.45 * fs,
                "Hz",
                owner=o,
                grid=f_grid,
                diff_step=1e-5 if res is not None else 1e-4,
                log=res is None,
            ),
            FitParam(
                "compliance_damping_ratio", zeta, 0.0, 4.0, "", owner=o, diff_step=1e-4, grid=z_grid
            ),
        ]
        if self.has_friction(ctx.model):
            out.append(self._creep_speed(ctx))
        return out

    def _creep_speed(self, ctx: Any) -> FitParam:
        """The driven-side friction's smoothing speed, fitted as a logarithm:
        behind the spring it sets how fast the friction reverses."""
        now = float(mk.rig_values(ctx.model).get("load_coulomb_speed_threshold", 1e-3))
        vmax = speed_scale(ctx)
        return FitParam(
            "load_coulomb_speed_threshold",
            now,
            min(1e-5 * vmax, now),
            max(vmax, now),
            speed_unit(ctx.model),
            before=now,
            owner=self.name,
            grid=(1.0, 3.0, 10.0, 30.0),
            diff_step=1e-3,
            log=True,
        )

    def _effective_inertia(self, ctx: Any, values: Mapping[str, float]) -> float:
        key = mk.driven_inertia_key(ctx.model)
        j = float(values.get(key, mk.rig_values(ctx.model)[key]))
        return self.base_inertia(ctx) + mk.kinematic_ratio(ctx.model) ** 2 * j

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        rig: dict[str, Any] = {}
        if "compliance_natural_frequency" in values:
            wn = 2.0 * np.pi * float(values["compliance_natural_frequency"])
            zeta = float(values["compliance_damping_ratio"])
            j = self._effective_inertia(ctx, values)
            k = wn**2 * j
            rig = {
                "compliance_stiffness": k,
                "compliance_damping": 2.0 * zeta * np.sqrt(k * j),
                "base_inertia": self.base_inertia(ctx),
                "load_friction_regularised": True,
            }
        elif "compliance_stiffness" in values:  # present, re-estimated
            rig = {
                "compliance_stiffness": float(values["compliance_stiffness"]),
                "compliance_damping": float(values["compliance_damping"]),
            }
        if rig and "load_coulomb_speed_threshold" in values:
            rig["load_coulomb_speed_threshold"] = float(values["load_coulomb_speed_threshold"])
        return {}, rig

    def notes(self, model: Any) -> list[str]:
        return [
            "on a speed-driven rig only the sum base_inertia + (driven speed / base speed)^2 x "
            "driven inertia is seen; base_inertia is kept as given (0: the spring acts at the "
            "mesh) and the driven inertia takes the rest",
            "behind the spring the driven side's friction creeps (load_friction_regularised): "
            "near rest it is a damper in series with the spring",
        ]

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        keys = ("compliance_stiffness", "compliance_damping", "base_inertia")
        out = {k: rig[k] for k in keys}
        j = float(rig["base_inertia"]) + self.reflected_inertia(model)
        k = float(rig["compliance_stiffness"])
        if k > 0 and j > 0:
            out["natural_frequency_hz"] = float(np.sqrt(k / j) / (2.0 * np.pi))
        if self.has_friction(model):
            out["load_coulomb_speed_threshold"] = rig["load_coulomb_speed_threshold"]
        return out

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        out = []
        for key, unit in (("compliance_stiffness", "N*m/rad"), ("compliance_damping", "N*m*s/rad")):
            now = float(rig[key])
            lo, hi = (1e-2 * now, 1e2 * now) if now > 0 else (0.0, 1.0)
            out.append(
                FitParam(
                    key,
                    now,
                    lo,
                    hi,
                    unit,
                    "coestimated",
                    now,
                    self.name,
                    diff_step=1e-4,
                    log=now > 0,
                )
            )
        return out

    def evidence(self, ctx: Any, screening: Screening, model: Any = None) -> dict[str, Any]:
        if not isinstance(screening, ComplianceScreening):
            raise TypeError(f"{self.name}: evidence needs this effect's own screening")
        res, tr = screening.resonance, screening.transient
        if res is None or tr is None:  # screen() sets both
            raise ValueError(f"{self.name}: the screening lacks its resonance or transient")
        ev: dict[str, Any] = {
            "signature": self.signature_text,
            "peak_hz": res.peak_hz,
            "prominence": screening.prominence,
            "damping_ratio": res.damping_ratio,
            "band_share": res.band_share,
            "reversals": tr.reversals,
            "reversal_share": tr.explained_share,
            "reversal_time_share": tr.time_share,
            "reversal_peak": tr.peak,
            "reversal_peak_time_s": tr.peak_time_s,
            "reversal_half_time_s": tr.half_time_s,
            "min_prominence": self.MIN_PROMINENCE,
            "min_reversal_share": self.MIN_REVERSAL_SHARE,
            "regime": "direction_reversal",
        }
        fu = ctx.meas.spec.driven_force_unit
        parts = []
        if tr.explained_share >= self.MIN_REVERSAL_SHARE:
            later = "later" if tr.peak < 0 else "earlier"
            parts.append(
                f"after the {tr.reversals} reversals of the driven speed the torque residual "
                f"repeats one transient ({100 * tr.explained_share:.0f} % of the residual energy "
                f"in {100 * tr.time_share:.1f} % of the time, peak {fmt(tr.peak)} {fu} "
                f"{1e3 * tr.peak_time_s:.1f} ms after the reversal, above half of it for "
                f"{1e3 * tr.half_time_s:.1f} ms): the measured force reverses {later} than the "
                "rigid model's"
            )
        if self._ringing(screening) is not None:
            parts.append(
                f"the torque residual's spectrum peaks at {res.peak_hz:.1f} Hz, "
                f"{screening.prominence:.1f}x its local floor, holding "
                f"{100 * res.band_share:.0f} % of the residual power: a resonance a rigid "
                "drive cannot ring at"
            )
        if not parts:
            parts.append(
                f"no resonance peak (the strongest, at {res.peak_hz:.1f} Hz, is "
                f"{screening.prominence:.1f}x its local floor) and no repeated transient after "
                f"the reversals ({100 * tr.explained_share:.1f} % of the residual energy)"
            )
        if model is not None and self.present(model):
            fitted = self.report(model)
            ev["fitted_natural_frequency_hz"] = fitted.get("natural_frequency_hz")
            if ev["fitted_natural_frequency_hz"]:
                parts.append(f"fitted natural frequency {ev['fitted_natural_frequency_hz']:.1f} Hz")
        ev["text"] = "; ".join(parts)
        return ev

    def plot(self, ctx: Any, ax: Any) -> None:
        """The residual spectrum when it rings (a prominent peak), else the
        transient the residual repeats after the reversals."""
        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        if np.isfinite(res.peak_hz) and band_prominence(res) >= self.MIN_PROMINENCE:
            ax.semilogy(res.freq_hz[1:], res.psd[1:], lw=1)
            ax.axvline(res.peak_hz, color="C3", ls="--", lw=1)
            ax.set_xlabel("frequency (Hz)")
            ax.set_ylabel("residual power density")
            ax.set_title(f"compliance: residual spectrum, peak {res.peak_hz:.1f} Hz")
            return
        tr = reversal_transient(
            self.rigid_cleaned(ctx), ctx.v, ctx.meas.dt, float(np.sum(ctx.r_d**2))
        )
        if tr.profile.size:
            t = (np.arange(tr.profile.size) - tr.before) * ctx.meas.dt * 1e3
            ax.plot(t, tr.profile, lw=1.2, label=f"mean over {tr.reversals} reversals")
            ax.axvline(0.0, color="k", lw=0.5)
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_xlabel("time after a reversal of the driven speed (ms)")
            ax.set_ylabel(f"residual x sign(new speed) ({ctx.meas.spec.driven_force_unit})")
            ax.legend(fontsize=7)
        ax.set_title(
            f"compliance: the transient after reversals ({100 * tr.explained_share:.0f} % of "
            "the residual energy)"
        )

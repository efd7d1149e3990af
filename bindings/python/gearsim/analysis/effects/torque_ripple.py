"""A torque ripple on the base side (eq. 11.5), per revolution and per tooth
mesh: the residual's harmonic regression on the base-shaft angle
(:func:`angle_harmonics`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import modelkit as mk
from .base import (
    Changes,
    Column,
    Effect,
    FitParam,
    Screening,
    cached,
    fmt,
    rig_has,
    robust,
)


@dataclass(frozen=True)
class Harmonic:
    """One harmonic of a residual against an angle: residual ~
    amplitude*cos(order*theta + phase); std_error: of the amplitude."""

    order: float
    amplitude: float
    phase: float
    std_error: float


def angle_harmonics(
    residual: np.ndarray, theta: np.ndarray, orders: tuple[float, ...]
) -> list[Harmonic]:
    """Harmonic regression of a residual on cos/sin(order*theta) for each
    order (plus a constant), by least squares. A cos(k theta + phi) =
    A cos(phi) cos(k theta) - A sin(phi) sin(k theta). The standard errors
    use the effective sample count of the left-over residual (lag-1
    autocorrelation), as the score does."""
    from ..scoring import effective_samples, lag1_autocorrelation

    r = np.asarray(residual, dtype=float)
    th = np.asarray(theta, dtype=float)
    cols = [np.ones_like(th)]
    for k in orders:
        cols += [np.cos(k * th), np.sin(k * th)]
    X = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    left = r - X @ coef
    n_eff = effective_samples(r.size, lag1_autocorrelation(left))
    sigma = float(np.std(left))
    out = []
    for j, k in enumerate(orders):
        a, b = float(coef[1 + 2 * j]), float(coef[2 + 2 * j])
        amp = float(np.hypot(a, b))
        # each of a, b has a std of ~ sigma*sqrt(2/n) for a full-cycle cover
        out.append(Harmonic(float(k), amp, float(np.arctan2(-b, a)), sigma * np.sqrt(2.0 / n_eff)))
    return out


def base_angle(speed: np.ndarray, dt: float) -> np.ndarray:
    """The base-shaft angle (rad) at the middle of each step of a rig that
    starts at angle 0 and holds each speed sample for one step (the rig's
    evaluation angle of the ripple, docs/physics.md 11.5)."""
    w = np.asarray(speed, dtype=float)
    return dt * (np.cumsum(w) - 0.5 * w)


#: (model key prefix, index, order factor) of the four ripple harmonics: the
#: per-revolution ones turn at i*theta, the per-tooth ones at j*Z*theta
_RIPPLE_TERMS = (
    ("revolution", 0, 1),
    ("revolution", 1, 2),
    ("mesh", 0, 1),
    ("mesh", 1, 2),
)


@dataclass(frozen=True)
class RippleScreening(Screening):
    """The ripple screening: the regression on the harmonics' cos/sin
    columns and the harmonic regression itself (amplitude, phase, standard
    error per harmonic)."""

    harmonics: tuple[Harmonic, ...] = ()


class TorqueRipple(Effect):
    """A base-side torque periodic in the base-shaft angle, per revolution
    and per tooth mesh (eq. 11.5). Its signature is linear: the residual's
    harmonic regression on cos/sin of i*theta and j*Z*theta. The harmonics
    fitted are those the regression finds above 4 standard errors (at least
    the strongest), each with its amplitude and phase."""

    name = "torque_ripple"
    summary = (
        "torque ripple on the base side, per revolution and per tooth mesh (rig ripple_* keys)"
    )
    signature_text = "residual periodic in the base-shaft angle (per revolution or per tooth)"
    n_params = 2
    excitation = "turn several revolutions at constant speed"
    separated_from = {
        "noise": "turn several revolutions at constant speed",
    }
    #: harmonics whose amplitude stays under this many standard errors are not fitted
    SIGNIFICANCE = 4.0

    @staticmethod
    def teeth(model: Any) -> int:
        """The teeth count of the base gear / pinion: given (rig
        ripple_mesh_teeth) or the rack's teeth_count; 0 when unknown."""
        z = int(mk.rig_values(model).get("ripple_mesh_teeth", 0) or 0)
        if z > 0:
            return z
        blk = mk.block_values(model)
        if blk.get("parameterization") == "tooth_parameters":
            return int(round(float(blk.get("teeth_count", 0))))
        return 0

    def unavailable(self, model: Any) -> str | None:
        why = rig_has(model, "ripple_mesh_teeth")
        if why:
            return why
        if self.teeth(model) < 1:
            return (
                "the teeth count of the base gear (pinion) is unknown: give it as [rig] "
                "ripple_mesh_teeth"
            )
        return None

    def present(self, model: Any) -> bool:
        rig = mk.rig_values(model)
        amps = list(rig.get("ripple_revolution_amplitude", [0, 0])) + list(
            rig.get("ripple_mesh_amplitude", [0, 0])
        )
        return any(float(a) > 0 for a in amps)

    def theta(self, ctx: Any) -> np.ndarray:
        return cached(ctx, "base_angle", lambda: base_angle(ctx.inputs.base_speed, ctx.meas.dt))

    def orders(self, model: Any) -> list[float]:
        z = self.teeth(model)
        return [float(k if kind == "revolution" else k * z) for kind, _, k in _RIPPLE_TERMS]

    def harmonics(self, ctx: Any) -> tuple[Harmonic, ...]:
        return tuple(
            angle_harmonics(
                ctx.residual[ctx.torque_output], self.theta(ctx), tuple(self.orders(ctx.model))
            )
        )

    def selected(self, harmonics: tuple[Harmonic, ...]) -> list[int]:
        """Indices into _RIPPLE_TERMS of the harmonics worth fitting."""
        keep = [i for i, h in enumerate(harmonics) if h.amplitude > self.SIGNIFICANCE * h.std_error]
        return keep or [int(np.argmax([h.amplitude for h in harmonics]))]

    def columns(self, ctx: Any) -> list[Column]:
        # the ripple adds to the drive torque: in driven units, divided by kin
        th = self.theta(ctx)
        cols = []
        for (kind, i, _), k in zip(_RIPPLE_TERMS, self.orders(ctx.model), strict=True):
            cols += [
                (f"{kind}{i}_cos", np.cos(k * th) / ctx.kin, (-np.inf, np.inf)),
                (f"{kind}{i}_sin", np.sin(k * th) / ctx.kin, (-np.inf, np.inf)),
            ]
        return cols

    def screen(self, ctx: Any) -> RippleScreening:
        reg = self.regression(ctx)
        return RippleScreening(float(reg.nrmse), reg, None, self.harmonics(ctx))

    def _harmonics_of(self, ctx: Any, screening: Screening | None) -> tuple[Harmonic, ...]:
        return getattr(screening, "harmonics", ()) or self.harmonics(ctx)

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        harm = self._harmonics_of(ctx, screening)
        amp_hi = 5.0 * robust(ctx.meas[ctx.torque_output]) or 1.0
        out = []
        for t in self.selected(harm):
            kind, i, _ = _RIPPLE_TERMS[t]
            h = harm[t]
            out += [
                FitParam(
                    f"ripple_{kind}_amplitude[{i}]",
                    h.amplitude,
                    0.0,
                    amp_hi,
                    "N*m",
                    owner=self.name,
                ),
                FitParam(
                    f"ripple_{kind}_phase[{i}]",
                    h.phase,
                    -2 * np.pi,
                    2 * np.pi,
                    "rad",
                    owner=self.name,
                    diff_step=1e-4,
                ),
            ]
        return out

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        rig_now = mk.rig_values(ctx.model)
        rig: dict[str, Any] = {}
        for kind in ("revolution", "mesh"):
            for part in ("amplitude", "phase"):
                key = f"ripple_{kind}_{part}"
                pair = [float(x) for x in rig_now.get(key, [0.0, 0.0])]
                for i in (0, 1):
                    name = f"{key}[{i}]"
                    if name in values:
                        pair[i] = float(values[name])
                        rig[key] = pair
        if rig:
            rig["ripple_mesh_teeth"] = self.teeth(ctx.model)
        return {}, rig

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        keys = [f"ripple_{k}_{p}" for k in ("revolution", "mesh") for p in ("amplitude", "phase")]
        return {**{k: list(rig[k]) for k in keys}, "ripple_mesh_teeth": rig["ripple_mesh_teeth"]}

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        amp_hi = 5.0 * robust(ctx.meas[ctx.torque_output]) or 1.0
        out = []
        for kind, i, _ in _RIPPLE_TERMS:
            amp = float(rig[f"ripple_{kind}_amplitude"][i])
            if amp <= 0:
                continue
            ph = float(rig[f"ripple_{kind}_phase"][i])
            out += [
                FitParam(
                    f"ripple_{kind}_amplitude[{i}]",
                    amp,
                    0.0,
                    max(amp_hi, 2 * amp),
                    "N*m",
                    "coestimated",
                    amp,
                    self.name,
                ),
                FitParam(
                    f"ripple_{kind}_phase[{i}]",
                    ph,
                    ph - 2 * np.pi,
                    ph + 2 * np.pi,
                    "rad",
                    "coestimated",
                    ph,
                    self.name,
                    diff_step=1e-4,
                ),
            ]
        return out

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        harm = self._harmonics_of(ctx, screening)
        return {
            "teeth": self.teeth(ctx.model),
            "harmonics": [
                {
                    "order": h.order,
                    "amplitude": h.amplitude,
                    "phase": h.phase,
                    "std_error": h.std_error,
                }
                for h in harm
            ],
        }

    def describe(self, ctx, ev, model=None) -> str | None:
        parts = [
            f"{fmt(h['amplitude'])} N*m at {h['order']:g}/rev"
            for h in ev["harmonics"]
            if h["amplitude"] > self.SIGNIFICANCE * h["std_error"]
        ]
        shown = ", ".join(parts) or "no harmonic above the noise"
        return (
            f"the torque residual repeats with the base-shaft angle (r = "
            f"{ev['correlation']:.2f}): {shown} (Z = {ev['teeth']} teeth); largest in "
            f"{ev['regime']}"
        )

    def plot(self, ctx: Any, ax: Any) -> None:
        th = np.mod(self.theta(ctx), 2 * np.pi)
        r = ctx.residual[ctx.torque_output]
        z = self.teeth(ctx.model)
        bins = 72
        for angle, label in (
            (th, "per revolution"),
            (np.mod(z * self.theta(ctx), 2 * np.pi), f"per tooth (Z = {z})"),
        ):
            which = np.minimum((angle / (2 * np.pi) * bins).astype(int), bins - 1)
            cnt = np.bincount(which, minlength=bins)
            mean = np.bincount(which, weights=r, minlength=bins) / np.maximum(cnt, 1)
            ax.plot((np.arange(bins) + 0.5) * 360.0 / bins, mean, lw=1, label=label)
        ax.set_xlabel("angle (deg)")
        ax.set_ylabel("mean torque residual (N*m)")
        ax.set_title("torque_ripple: residual against base-shaft angle")
        ax.legend(fontsize=7)

"""Stribeck friction (eq. 11.1): a breakaway level above the Coulomb one,
falling with speed. Its signature: the residual times sign(speed), binned
against |speed| (:func:`speed_profile`)."""

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
    fmt,
    force_scale,
    force_unit,
    rig_has,
    seed_of,
    speed_scale,
    speed_unit,
)
from .coulomb_friction import CoulombFriction


@dataclass(frozen=True)
class SpeedProfile:
    """The driven-side residual against |speed|: r_d * sgn(v) averaged in
    log-spaced bins of |v| (a friction level per speed).

    speed: bin centres (driven units); level: mean r_d*sgn(v) per bin;
    count: samples per bin; coulomb / excess / stribeck_speed: the curve
    level = coulomb + excess*exp(-(speed/stribeck_speed)^2) fitted to the
    bins (weighted by their counts)."""

    speed: np.ndarray
    level: np.ndarray
    count: np.ndarray
    coulomb: float
    excess: float
    stribeck_speed: float


def speed_profile(r_d: np.ndarray, v: np.ndarray, bins: int = 30) -> SpeedProfile:
    """Binned r_d*sgn(v) against |v| and the Stribeck curve that fits it
    best (grid over the Stribeck speed, linear least squares for the two
    levels at each)."""
    u = np.abs(np.asarray(v, dtype=float))
    y = np.asarray(r_d, dtype=float) * np.sign(v)
    vmax = float(np.percentile(u, 99)) if u.size else 0.0
    if vmax <= 0:
        return SpeedProfile(np.zeros(0), np.zeros(0), np.zeros(0), 0.0, 0.0, 0.0)
    edges = np.geomspace(2e-3 * vmax, vmax, bins + 1)
    which = np.digitize(u, edges) - 1
    ok = (which >= 0) & (which < bins)
    count = np.bincount(which[ok], minlength=bins).astype(float)
    total = np.bincount(which[ok], weights=y[ok], minlength=bins)
    keep = count >= 5
    centre = np.sqrt(edges[:-1] * edges[1:])[keep]
    level = total[keep] / count[keep]
    w = np.sqrt(count[keep])
    best = (np.inf, 0.0, 0.0, 0.0)
    for vs in np.geomspace(edges[0], 0.5 * vmax, 60):
        X = np.column_stack([np.ones_like(centre), np.exp(-((centre / vs) ** 2))])
        coef, *_ = np.linalg.lstsq(X * w[:, None], level * w, rcond=None)
        if coef[1] < 0:  # a friction that rises towards rest only
            continue
        sse = float(np.sum((w * (level - X @ coef)) ** 2))
        if sse < best[0]:
            best = (sse, float(coef[0]), float(coef[1]), float(vs))
    return SpeedProfile(centre, level, count[keep], best[1], best[2], best[3])


@dataclass(frozen=True)
class StribeckScreening(Screening):
    """The Stribeck screening: the regression with the hump's column at the
    best of three Stribeck speeds, and the binned friction level."""

    stribeck_speed: float = 0.0
    profile: SpeedProfile | None = None


class StribeckFriction(Effect):
    """Driven-side breakaway friction falling to the Coulomb level with speed
    (eq. 11.1). Fitted as the excess over the Coulomb friction, so that the
    C core's rule F_brk >= F_C holds for any parameter vector; the Coulomb
    friction is fitted with it (its own parameter when the model has none)."""

    name = "stribeck_friction"
    summary = (
        "Stribeck friction: breakaway above the Coulomb level, falling with speed "
        "(rig load_breakaway_friction, load_stribeck_speed)"
    )
    signature_text = (
        "residual times sign(speed) peaks at low speed and decays with speed to a constant level"
    )
    n_params = 3
    nests = ("coulomb_friction",)
    excitation = "hold at several low speeds"
    separated_from = {
        "coulomb_friction": "hold at several low speeds (the Stribeck hump falls with speed, "
        "Coulomb friction does not)",
        "viscous_friction": "hold at several low speeds and at one high speed",
    }

    def unavailable(self, model: Any) -> str | None:
        return rig_has(model, "load_breakaway_friction")

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model).get("load_breakaway_friction", 0.0)) > 0.0

    def profile(self, ctx: Any) -> SpeedProfile:
        return speed_profile(ctx.r_d, ctx.v)

    def _column(self, ctx: Any, vs: float) -> np.ndarray:
        return ctx.columns["sign"] * np.exp(-((ctx.v / max(vs, 1e-12)) ** 2))

    def _own(self, ctx: Any, vs: float) -> list[Column]:
        cols = [("stribeck", self._column(ctx, vs), (0.0, np.inf))]
        if not CoulombFriction().present(ctx.model):
            cols.append(("sign", ctx.columns["sign"], (0.0, np.inf)))
        return cols

    def screen(self, ctx: Any) -> StribeckScreening:
        """The profile's Stribeck speed, and the screening regression with
        the hump's column at that speed and at 1/3 and 3 times it (the best
        one kept): the profile is coarse at the lowest speeds."""
        prof = self.profile(ctx)
        vs0 = prof.stribeck_speed if prof.stribeck_speed > 0 else 0.05 * speed_scale(ctx)
        # the first of the lowest error (min keeps the first of equals)
        speeds = (vs0 / 3.0, vs0, 3.0 * vs0)
        tried = [(self.regression(ctx, self._own(ctx, vs)), vs) for vs in speeds]
        best, best_vs = min(tried, key=lambda t: t[0].nrmse)
        return StribeckScreening(float(best.nrmse), best, None, float(best_vs), prof)

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        unit = force_unit(ctx.model)
        vmax = speed_scale(ctx)
        vs = float(getattr(screening, "stribeck_speed", 0.0) or 0.05 * vmax)
        excess = max(seed_of(screening, "stribeck", 0.0), 0.0)
        hi = max(5.0 * force_scale(ctx), 10.0 * excess)
        out = [
            FitParam("breakaway_excess", excess, 0.0, hi, unit, owner=self.name),
            FitParam(
                "load_stribeck_speed",
                vs,
                1e-4 * vmax,
                vmax,
                speed_unit(ctx.model),
                before=float(rig.get("load_stribeck_speed", 0.01)),
                owner=self.name,
                grid=(0.3, 1.0, 3.0),
            ),
        ]
        if not CoulombFriction().present(ctx.model):
            fc = max(seed_of(screening, "sign", 0.0), 0.0)
            out.append(
                FitParam(
                    "load_coulomb_friction", fc, 0.0, hi, unit, before=0.0, owner="coulomb_friction"
                )
            )
        return out

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "breakaway_excess" not in values:
            return {}, {}
        fc = float(
            values.get("load_coulomb_friction", mk.rig_values(ctx.model)["load_coulomb_friction"])
        )
        rig = {
            "load_breakaway_friction": fc + float(values["breakaway_excess"]),
            "load_stribeck_speed": float(values["load_stribeck_speed"]),
        }
        if "load_coulomb_friction" in values:
            rig["load_coulomb_friction"] = fc
        return {}, rig

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        keys = ("load_breakaway_friction", "load_stribeck_speed", "load_coulomb_friction")
        return {k: rig[k] for k in keys}

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        fc = float(rig["load_coulomb_friction"])
        vs = float(rig["load_stribeck_speed"])
        ex = float(rig["load_breakaway_friction"]) - fc
        hi = max(5.0 * force_scale(ctx), 10.0 * ex)
        return [
            FitParam(
                "breakaway_excess",
                ex,
                0.0,
                hi,
                force_unit(ctx.model),
                "coestimated",
                ex,
                self.name,
            ),
            FitParam(
                "load_stribeck_speed",
                vs,
                min(1e-4 * speed_scale(ctx), vs),
                max(speed_scale(ctx), vs),
                role="coestimated",
                before=vs,
                owner=self.name,
            ),
        ]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        rig = mk.rig_values(ctx.model)
        ex = float(rig["load_breakaway_friction"]) - float(rig["load_coulomb_friction"])
        col = self._column(ctx, float(rig["load_stribeck_speed"]))
        return [("stribeck", col, (-ex, np.inf))]

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        prof = getattr(screening, "profile", None) or self.profile(ctx)
        ev: dict[str, Any] = {
            "profile_coulomb": prof.coulomb,
            "profile_excess": prof.excess,
            "profile_stribeck_speed": prof.stribeck_speed,
        }
        if model is not None and self.present(model):
            rig = mk.rig_values(model)
            ev["fitted"] = {
                "load_breakaway_friction": float(rig["load_breakaway_friction"]),
                "load_coulomb_friction": float(rig["load_coulomb_friction"]),
                "load_stribeck_speed": float(rig["load_stribeck_speed"]),
            }
        return ev

    def describe(self, ctx, ev, model=None) -> str | None:
        fu, vu = ctx.meas.spec.driven_force_unit, ctx.meas.spec.driven_speed_unit
        if ev["profile_excess"] > 0 and ev["profile_stribeck_speed"] > 0:
            seen = (
                f"the friction level in the residual rises towards rest (r = "
                f"{ev['correlation']:.2f}): {fmt(ev['profile_excess'])} {fu} above its level in "
                f"motion, falling over ~{fmt(ev['profile_stribeck_speed'])} {vu}"
            )
        else:
            seen = (
                f"the residual's friction level shows no rise towards rest (r = "
                f"{ev['correlation']:.2f})"
            )
        fitted = ev.get("fitted")
        if fitted:
            seen += (
                f"; fitted: breakaway {fmt(fitted['load_breakaway_friction'])} {fu} against a "
                f"Coulomb level of {fmt(fitted['load_coulomb_friction'])} {fu}, falling over "
                f"{fmt(fitted['load_stribeck_speed'])} {vu}"
            )
        return f"{seen}; largest in {ev['regime']}"

    def plot(self, ctx: Any, ax: Any) -> None:
        prof = self.profile(ctx)
        if prof.speed.size == 0:
            return
        ax.semilogx(prof.speed, prof.level, "o", ms=3, label="residual x sign(speed), binned")
        u = np.geomspace(prof.speed[0], prof.speed[-1], 200)
        if prof.stribeck_speed > 0:
            curve = prof.coulomb + prof.excess * np.exp(-((u / prof.stribeck_speed) ** 2))
            ax.semilogx(u, curve, "C3-", lw=1, label="Stribeck curve through the bins")
        ax.set_xlabel(f"|driven speed| ({ctx.meas.spec.driven_speed_unit})")
        ax.set_ylabel(f"friction level ({ctx.meas.spec.driven_force_unit})")
        ax.set_title("stribeck_friction: residual against speed")
        ax.legend(fontsize=7)

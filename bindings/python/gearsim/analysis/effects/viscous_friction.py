"""Viscous friction on the driven side: a residual proportional to the speed."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import modelkit as mk
from .base import (
    Changes,
    Column,
    Effect,
    FitParam,
    Screening,
    as_coestimated,
    fmt,
    force_scale,
    seed_of,
    speed_scale,
)


class ViscousFriction(Effect):
    name = "viscous_friction"
    summary = "viscous friction on the driven side"
    signature_text = "residual proportional to the speed"
    excitation = "hold at two speeds"
    separated_from = {
        "coulomb_friction": "hold at two speeds (viscous friction grows with speed, Coulomb "
        "friction does not)",
        "meshing_efficiency": "hold at two speeds under the same load",
    }

    @staticmethod
    def key(model: Any) -> str:
        if mk.block_name(model) == "simple_gear":
            return "viscous_coefficients[1]"
        return "rack_viscous_coefficient"

    def present(self, model: Any) -> bool:
        return mk.viscous_value(model) > 0.0 or mk.base_viscous_value(model) > 0.0

    def columns(self, ctx: Any) -> list[Column]:
        cur = mk.viscous_value(ctx.model)
        return [("speed", ctx.columns["speed"], (0.0 - cur, np.inf))]

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        cur = mk.viscous_value(ctx.model)
        x0 = max(cur + seed_of(screening, "speed"), 0.0)
        hi = 20.0 * force_scale(ctx) / speed_scale(ctx)
        unit = "N*m/(rad/s)" if mk.block_name(ctx.model) == "simple_gear" else "N/(m/s)"
        key = self.key(ctx.model)
        return [FitParam(key, x0, 0.0, max(hi, 10 * x0), unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        key = self.key(ctx.model)
        if key not in values:
            return {}, {}
        if mk.block_name(ctx.model) == "simple_gear":
            vc = list(mk.block_values(ctx.model)["viscous_coefficients"])
            vc[1] = float(values[key])
            return {"viscous_coefficients": vc}, {}
        return {"rack_viscous_coefficient": float(values[key])}, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        if mk.block_name(model) == "simple_gear":
            return {"viscous_coefficients": list(v["viscous_coefficients"])}
        return {
            "rack_viscous_coefficient": v["rack_viscous_coefficient"],
            "pinion_viscous_coefficient": v["pinion_viscous_coefficient"],
        }

    def notes(self, model: Any) -> list[str]:
        if mk.block_name(model) != "simple_gear":
            return []
        return [
            "base and follower viscous coefficients act alike on a rigid, speed-driven mesh; "
            "the fit puts the whole viscous loss on the follower side (viscous_coefficients[1])"
        ]

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        return [as_coestimated(p) for p in self.parameters(ctx, screening)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        return {"slope": float(own.get("speed", 0.0))}

    def describe(self, ctx, ev, model=None) -> str | None:
        if not ev["slope"] > 0:
            return None
        return (
            f"residual grows in proportion to speed (r = {ev['correlation']:.2f}, slope "
            f"{fmt(ev['slope'])} {ctx.meas.spec.driven_force_unit} per "
            f"{ctx.meas.spec.driven_speed_unit} of driven speed); largest in {ev['regime']}"
        )

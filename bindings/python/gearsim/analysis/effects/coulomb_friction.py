"""Coulomb friction on the driven side (rig load_coulomb_friction): a step of
the residual at each direction reversal."""

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
    force_unit,
    seed_of,
)


class CoulombFriction(Effect):
    name = "coulomb_friction"
    summary = "Coulomb friction on the driven side (rig load_coulomb_friction)"
    signature_text = (
        "residual follows the sign of the speed: a constant-magnitude step at each "
        "direction reversal"
    )
    excitation = "reverse the direction of motion at a constant load"
    separated_from = {
        "load_offset": "reverse the direction of motion (Coulomb friction flips with it, an "
        "offset does not)",
        "meshing_efficiency": "hold at two loads in each direction (an efficiency loss scales "
        "with the load, Coulomb friction does not)",
        "load_dependent_efficiency": "hold at several loads, including near zero load",
        "viscous_friction": "hold at two speeds",
    }

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model)["load_coulomb_friction"]) > 0.0

    def columns(self, ctx: Any) -> list[Column]:
        cur = float(mk.rig_values(ctx.model)["load_coulomb_friction"])
        return [("sign", ctx.columns["sign"], (0.0 - cur, np.inf))]

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        cur = float(mk.rig_values(ctx.model)["load_coulomb_friction"])
        x0 = max(cur + seed_of(screening, "sign"), 0.0)
        hi = max(5.0 * force_scale(ctx), 10 * x0)
        unit = force_unit(ctx.model)
        return [FitParam("load_coulomb_friction", x0, 0.0, hi, unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "load_coulomb_friction" not in values:
            return {}, {}
        return {}, {"load_coulomb_friction": float(values["load_coulomb_friction"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"load_coulomb_friction": mk.rig_values(model)["load_coulomb_friction"]}

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        return [as_coestimated(p) for p in self.parameters(ctx, screening)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def describe(self, ctx, screening, own, r, regime) -> str:
        fc = own.get("sign", 0.0)
        return (
            f"residual follows sign(speed) (r = {r:.2f}): a step of 2 x {fmt(fc)} "
            f"{ctx.meas.spec.driven_force_unit} at each direction reversal; largest in {regime}"
        )

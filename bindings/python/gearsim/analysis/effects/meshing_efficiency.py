"""A constant meshing efficiency: a loss proportional to the transmitted
torque that follows the direction of power flow."""

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
    eff_from_loss,
    fmt,
    present_mesh_loss,
    seed_of,
)

#: the friction models that carry an efficiency
EFFICIENCY_MODELS = (
    "constant_efficiency",
    "load_dependent_efficiency",
    "temperature_dependent_efficiency",
    "temperature_load_dependent_efficiency",
)


def flow_split(ctx: Any) -> dict[str, float]:
    """Mesh-loss coefficient fitted separately where the drive drives the load
    and where the load overruns (power-flow direction), the inertia part
    removed with it."""
    x = ctx.columns["mesh"]
    a = ctx.columns["acceleration"]
    p = ctx.T * ctx.v
    out = {}
    for name, m in (("driving", p < 0), ("overrunning", p > 0)):
        if m.sum() < 20:
            continue
        coef, *_ = np.linalg.lstsq(np.column_stack([x[m], a[m]]), ctx.r_d[m], rcond=None)
        out[f"loss_factor_{name}"] = float(coef[0])
    return out


class MeshingEfficiency(Effect):
    name = "meshing_efficiency"
    summary = "constant meshing efficiency (friction_model = constant_efficiency)"
    signature_text = (
        "residual proportional to |transmitted torque| with the sign of the speed: the drive "
        "needs more torque while it drives the load and less while the load overruns"
    )
    excitation = "reverse under load: drive the load, then let it overrun"
    separated_from = {
        "load_dependent_efficiency": "hold at several loads, including near zero load",
        "coulomb_friction": "hold at two loads in each direction",
        "load_offset": "reverse under load",
    }

    def present(self, model: Any) -> bool:
        return mk.friction_model(model) in EFFICIENCY_MODELS

    def columns(self, ctx: Any) -> list[Column]:
        return [("mesh", ctx.columns["mesh"], (0.0, 0.7))]

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        x0 = eff_from_loss(seed_of(screening, "mesh", 0.02))
        return [FitParam("efficiency_const", min(x0, 0.999), 0.3, 1.0, "", owner=self.name)]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "efficiency_const" not in values:
            return {}, {}
        eta = float(values["efficiency_const"])
        return {"friction_model": "constant_efficiency", "efficiency_const": eta}, {}

    def report(self, model: Any) -> dict[str, Any]:
        return {"efficiency_const": mk.block_values(model)["efficiency_const"]}

    @staticmethod
    def _constant(model: Any) -> bool:
        return mk.friction_model(model) == "constant_efficiency"

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        if not self._constant(ctx.model):
            return []  # the table efficiencies are not re-estimated automatically
        cur = float(mk.block_values(ctx.model)["efficiency_const"])
        eta = eff_from_loss((1.0 - cur) + seed_of(screening, "mesh", 0.0))
        return [
            FitParam(
                "efficiency_const",
                min(eta, 0.999),
                0.3,
                1.0,
                "",
                role="coestimated",
                before=cur,
                owner=self.name,
            )
        ]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        if not self._constant(ctx.model):
            return []
        loss = present_mesh_loss(ctx.model)
        return [("mesh", ctx.columns["mesh"], (-loss, 0.7 - loss))]

    def describe(self, ctx, screening, own, r, regime) -> str:
        split = flow_split(ctx)
        return (
            f"residual proportional to |transmitted torque| x sign(speed) (r = {r:.2f}): loss "
            f"factor {fmt(split.get('loss_factor_driving', float('nan')))} while driving, "
            f"{fmt(split.get('loss_factor_overrunning', float('nan')))} while overrunning "
            f"(efficiency ~ {fmt(1.0 - own.get('mesh', 0.0))}); largest in {regime}"
        )

    def evidence_extra(self, ctx, screening, own) -> dict[str, Any]:
        return flow_split(ctx)

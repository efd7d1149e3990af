"""A constant load offset on the driven side (rig load_offset): a constant
bias of the residual in every regime."""

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


class LoadOffset(Effect):
    name = "load_offset"
    summary = "constant load offset on the driven side (rig load_offset)"
    signature_text = "constant bias of the residual in every regime"
    excitation = "reverse under load"
    separated_from = {
        "coulomb_friction": "reverse the direction of motion (an offset keeps its sign)",
        "meshing_efficiency": "reverse under load (an offset keeps its sign, a meshing loss "
        "follows the power flow)",
    }

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model)["load_offset"]) != 0.0

    def columns(self, ctx: Any) -> list[Column]:
        return [("constant", ctx.columns["constant"], (-np.inf, np.inf))]

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        cur = float(mk.rig_values(ctx.model)["load_offset"])
        x0 = cur + seed_of(screening, "constant")
        lim = max(5.0 * force_scale(ctx), 10 * abs(x0))
        unit = force_unit(ctx.model)
        return [FitParam("load_offset", x0, -lim, lim, unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "load_offset" not in values:
            return {}, {}
        return {}, {"load_offset": float(values["load_offset"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"load_offset": mk.rig_values(model)["load_offset"]}

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        return [as_coestimated(p) for p in self.parameters(ctx, screening)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    #: the regimes whose mean residual the evidence shows
    SHOWN = ("driving", "overrunning", "direction_reversal", "high_speed")

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        return {
            "bias": -float(own.get("constant", 0.0)),
            "regime_means": {
                reg.name: float(np.mean(ctx.r_d[reg.mask]))
                for reg in ctx.regimes
                if reg.mask.any() and reg.name in self.SHOWN
            },
        }

    def describe(self, ctx, ev, model=None) -> str | None:
        per = [f"{name} {fmt(v)}" for name, v in ev["regime_means"].items()]
        return (
            f"constant bias of the driven-side residual: {fmt(ev['bias'])} "
            f"{ctx.meas.spec.driven_force_unit} of missing load offset (r = "
            f"{ev['correlation']:.2f}); mean residual by regime: {', '.join(per)}"
        )

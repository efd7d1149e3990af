"""Coulomb friction on the driven side (rig load_coulomb_friction): a step of
the residual at each direction reversal. Added to a model that leaves its
smoothing speed load_coulomb_speed_threshold at the default, the smoothing is
set to the speed the record resolves (0.5 % of the driven speed's robust
maximum) when that is wider: a narrower reversal would be timed by the input
noise, not by the friction. Behind a compliance the friction
creeps (rig load_friction_regularised) and its smoothing speed
load_coulomb_speed_threshold shapes every reversal: it is fitted with it."""

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
    speed_scale,
    speed_unit,
)


def _compliant(model: Any) -> bool:
    return float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0


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
        out = [FitParam("load_coulomb_friction", x0, 0.0, hi, unit, before=cur, owner=self.name)]
        if _compliant(ctx.model):
            now = float(mk.rig_values(ctx.model)["load_coulomb_speed_threshold"])
            vmax = speed_scale(ctx)
            out.append(
                FitParam(
                    "load_coulomb_speed_threshold",
                    now,
                    min(1e-5 * vmax, now),
                    max(vmax, now),
                    speed_unit(ctx.model),
                    before=now,
                    owner=self.name,
                    grid=(1.0, 3.0, 10.0),
                    diff_step=1e-3,
                    log=True,
                )
            )
        return out

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "load_coulomb_friction" not in values:
            return {}, {}
        rig: dict[str, Any] = {"load_coulomb_friction": float(values["load_coulomb_friction"])}
        if "load_coulomb_speed_threshold" in values:
            rig["load_coulomb_speed_threshold"] = float(values["load_coulomb_speed_threshold"])
        elif (
            not self.present(ctx.model)
            and "load_coulomb_speed_threshold" not in ctx.model.rig_params
        ):
            # the model leaves the smoothing at its default: no narrower than
            # the speed the record resolves, where the screening saw the step
            now = float(mk.rig_values(ctx.model)["load_coulomb_speed_threshold"])
            rig["load_coulomb_speed_threshold"] = max(now, float(ctx.speed_resolution))
        if _compliant(ctx.model):
            rig["load_friction_regularised"] = True
        return {}, rig

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        out = {"load_coulomb_friction": rig["load_coulomb_friction"]}
        if _compliant(model):
            out["load_coulomb_speed_threshold"] = rig["load_coulomb_speed_threshold"]
        return out

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        out = [as_coestimated(p) for p in self.parameters(ctx, screening)]
        for p in out:
            p.grid = ()
        return out

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        return {"level": float(own.get("sign", 0.0))}

    def describe(self, ctx, ev, model=None) -> str | None:
        if not ev["level"] > 0:
            return None
        return (
            f"residual follows sign(speed) (r = {ev['correlation']:.2f}): a step of 2 x "
            f"{fmt(ev['level'])} {ctx.meas.spec.driven_force_unit} at each direction reversal; "
            f"largest in {ev['regime']}"
        )

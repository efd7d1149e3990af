"""A load-dependent efficiency (eq. 2.4, 2.5): an idle loss plus a loss
growing with the load, so that the efficiency falls at low load."""

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
    fmt,
    force_scale,
    present_mesh_loss,
    seed_of,
    speed_scale,
)


class LoadDependentEfficiency(Effect):
    """tau_mesh = (g*tau_idle + k*|T|)*sgn(w) on the follower (eq. 2.4, 2.5)."""

    name = "load_dependent_efficiency"
    blocks = ("simple_gear",)
    summary = "load-dependent efficiency: idle torque plus a loss proportional to load"
    signature_text = (
        "a Coulomb-like part at no load plus a part growing with |transmitted torque|: the "
        "efficiency falls at low load"
    )
    n_params = 2
    replaces = ("meshing_efficiency",)
    nests = ("meshing_efficiency",)
    excitation = "hold at several loads, including near zero load"
    separated_from = {
        "meshing_efficiency": "hold at several loads, including near zero load (only a "
        "load-dependent efficiency keeps a loss at no load)",
        "coulomb_friction": "hold at several loads, including near zero load",
    }

    def present(self, model: Any) -> bool:
        return mk.friction_model(model) in (
            "load_dependent_efficiency",
            "temperature_load_dependent_efficiency",
        )

    def unavailable(self, model: Any) -> str | None:
        if mk.friction_model(model) in (
            "temperature_dependent_efficiency",
            "temperature_load_dependent_efficiency",
        ):
            return (
                "the model has a temperature-dependent efficiency; combining it with a load "
                "dependence needs the 2-D efficiency_matrix, which is not fitted automatically"
            )
        return None

    def columns(self, ctx: Any) -> list[Column]:
        loss = present_mesh_loss(ctx.model)
        return [
            ("idle", ctx.columns["idle"], (0.0, np.inf)),
            ("mesh", ctx.columns["mesh"], (-loss, 0.7 - loss)),
        ]

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        g = float(mk.block_values(ctx.model)["teeth_ratio"])
        idle_f = max(seed_of(screening, "idle", 0.0), 0.0)  # follower-referred g*tau_idle
        k = max(present_mesh_loss(ctx.model) + seed_of(screening, "mesh", 0.02), 0.0)
        hi = max(2.0 * force_scale(ctx) / g, 10 * idle_f / g)
        out = [
            FitParam("idle_torque", idle_f / g, 0.0, hi, "N*m", owner=self.name),
            FitParam("load_slope", k, 0.0, 2.0, "", owner=self.name),
        ]
        if "speed_threshold" not in ctx.model.block_params:
            out.append(self._speed_threshold(ctx))
        return out

    #: the smoothing speed's grid, as multiples of its seed
    THRESHOLD_GRID = (1.0, 3.0, 10.0, 30.0)

    def _speed_threshold(self, ctx: Any) -> FitParam:
        """The follower speed over which the loss reverses (eq. 2.4's tanh),
        fitted as a logarithm when the model gives none: like a Coulomb
        friction's, it is never sharper than the record's speed resolution
        (signatures.SPEED_RESOLUTION), and a real gearbox's loss reverses
        over a band the record shows (0.5 rad/s in an external test record,
        50 times the 0.01 rad/s default)."""
        default = float(mk.block_values(ctx.model).get("speed_threshold", 0.01))
        vmax = speed_scale(ctx)
        seed = max(default, float(ctx.speed_resolution))
        return FitParam(
            "speed_threshold",
            seed,
            min(1e-5 * vmax, seed),
            max(vmax, seed),
            "rad/s",
            owner=self.name,
            grid=self.THRESHOLD_GRID,
            diff_step=1e-3,
            log=True,
        )

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "idle_torque" not in values:
            return {}, {}  # present and not re-estimated
        g = float(mk.block_values(ctx.model)["teeth_ratio"])
        tnom = ctx.nominal_torque
        idle = float(values["idle_torque"])
        k = float(values["load_slope"])
        # eq. 2.5: k = 1/eta_nom - 1 - g*tau_idle/tau_nom  =>  eta_nom; keep
        # eta_nom < 1 strictly against rounding
        eta = min(1.0 / (1.0 + k + g * idle / tnom + 1e-12), 1.0 - 1e-9)
        block = {
            "friction_model": "load_dependent_efficiency",
            "idle_torque": idle,
            "nominal_output_torque": tnom,
            "efficiency_nominal": eta,
        }
        if "speed_threshold" in values:
            block["speed_threshold"] = float(values["speed_threshold"])
        return block, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        keys = ("idle_torque", "nominal_output_torque", "efficiency_nominal", "speed_threshold")
        return {k: v[k] for k in keys}

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        # driven-side loss = idle + k*|T|: from the fit when there is one,
        # else from the screening (the present constant loss plus its change)
        source = "screening"
        idle = max(float(own.get("idle", 0.0)), 0.0)
        k = max(present_mesh_loss(ctx.model) + float(own.get("mesh", 0.0)), 0.0)
        if model is not None and self.present(model):
            v = mk.block_values(model)
            g = float(v["teeth_ratio"])
            idle = g * float(v["idle_torque"])
            k = (
                1.0 / float(v["efficiency_nominal"])
                - 1.0
                - idle / float(v["nominal_output_torque"])
            )
            k, source = max(k, 0.0), "fit"
        tmax = float(np.percentile(np.abs(ctx.T), 95)) or 1.0
        eff = {}
        for frac in (0.1, 1.0):
            t = frac * tmax
            eff[f"{int(frac * 100)}%"] = t / (t + idle + k * t) if t > 0 else float("nan")
        return {"idle_loss": idle, "load_slope": k, "efficiency_at_load": eff, "source": source}

    def describe(self, ctx, ev, model=None) -> str | None:
        eff = ev["efficiency_at_load"]
        how = "fitted" if ev["source"] == "fit" else "seen in the residual"
        return (
            f"loss {how} = {fmt(ev['idle_loss'])} {ctx.meas.spec.driven_force_unit} at no load + "
            f"{fmt(ev['load_slope'])} x |transmitted torque| (r = {ev['correlation']:.2f}): "
            f"efficiency {fmt(eff['10%'])} at 10 % of the peak load vs {fmt(eff['100%'])} at the "
            f"peak; largest in {ev['regime']}"
        )

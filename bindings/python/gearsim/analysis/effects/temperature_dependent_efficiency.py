"""An efficiency interpolated over temperature: the torque-proportional
meshing loss changes with the temperature."""

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
    present_mesh_loss,
    seed_of,
)


def temperature_hats(temp: np.ndarray, breakpoints: np.ndarray) -> np.ndarray:
    """Linear-interpolation basis: column i is the weight of breakpoint i in
    interp(temp, breakpoints, values), clamped at the ends. Shape (n, len(bp))."""
    bp = np.asarray(breakpoints, dtype=float)
    eye = np.eye(bp.size)
    return np.column_stack([np.interp(temp, bp, eye[i]) for i in range(bp.size)])


def temperature_breakpoints(temp: np.ndarray) -> np.ndarray:
    """Three breakpoints spanning the data: 1st, 50 % between, 99th percentile."""
    lo, hi = float(np.percentile(temp, 1)), float(np.percentile(temp, 99))
    if hi - lo < 1e-6:
        hi = lo + 1.0
    return np.round(np.array([lo, 0.5 * (lo + hi), hi]), 2)


class TemperatureDependentEfficiency(Effect):
    name = "temperature_dependent_efficiency"
    summary = (
        "efficiency interpolated over temperature (friction_model = "
        "temperature_dependent_efficiency)"
    )
    signature_text = "the torque-proportional meshing loss changes with temperature"
    n_params = 3
    replaces = ("meshing_efficiency",)
    nests = ("meshing_efficiency",)
    excitation = "hold at one load while the temperature changes"
    separated_from = {
        "meshing_efficiency": "hold at one load and speed while the gear warms up",
    }
    #: a temperature span (K) below which no temperature dependence can be seen
    MIN_SPAN = 2.0

    def present(self, model: Any) -> bool:
        return mk.friction_model(model) in (
            "temperature_dependent_efficiency",
            "temperature_load_dependent_efficiency",
        )

    def unavailable(self, model: Any) -> str | None:
        if mk.friction_model(model) == "load_dependent_efficiency":
            return (
                "the model has a load-dependent efficiency; combining it with a temperature "
                "dependence needs the 2-D efficiency_matrix, which is not fitted automatically"
            )
        return None

    @staticmethod
    def breakpoints(ctx: Any) -> np.ndarray:
        return temperature_breakpoints(ctx.temperature)

    def columns(self, ctx: Any) -> list[Column]:
        if float(np.ptp(ctx.temperature)) < self.MIN_SPAN:
            return []
        bp = self.breakpoints(ctx)
        hats = temperature_hats(ctx.temperature, bp)
        loss = present_mesh_loss(ctx.model)
        mesh = ctx.columns["mesh"]
        return [
            (f"mesh@{t:.1f}K", mesh * hats[:, i], (-loss, 0.7 - loss)) for i, t in enumerate(bp)
        ]

    def screen(self, ctx: Any) -> Screening:
        reg = self.regression(ctx)
        span = float(np.ptp(ctx.temperature))
        why = None
        if span < self.MIN_SPAN:
            why = (
                f"the {ctx.temperature_source} temperature spans only {span:.2f} K: a "
                "temperature dependence cannot be seen in this record"
            )
        return Screening(float(reg.nrmse), reg, why)

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        loss = present_mesh_loss(ctx.model)
        out = []
        for i, t in enumerate(self.breakpoints(ctx)):
            # screening coefficients are changes of the present loss 1 - eta
            d_loss = seed_of(screening, f"mesh@{t:.1f}K", 0.02 if loss == 0 else 0.0)
            eta = min(eff_from_loss(loss + d_loss), 0.999)
            out.append(FitParam(f"efficiency_vector[{i}]", eta, 0.3, 1.0, "", owner=self.name))
        return out

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "efficiency_vector[0]" not in values:
            return {}, {}  # present and not re-estimated
        bp = self.breakpoints(ctx)
        return {
            "friction_model": "temperature_dependent_efficiency",
            "temperature_vector": [float(x) for x in bp],
            "efficiency_vector": [float(values[f"efficiency_vector[{i}]"]) for i in range(bp.size)],
        }, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        return {
            "temperature_vector": list(v["temperature_vector"]),
            "efficiency_vector": list(v["efficiency_vector"]),
        }

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        bp = self.breakpoints(ctx)
        if model is not None and self.present(model):
            v = mk.block_values(model)
            eta = np.interp(bp, v["temperature_vector"], v["efficiency_vector"])
            source = "fit"
        else:
            loss = present_mesh_loss(ctx.model)
            eta = [eff_from_loss(loss + own.get(f"mesh@{t:.1f}K", 0.0)) for t in bp]
            source = "screening"
        return {
            "temperature_span_K": float(np.ptp(ctx.temperature)),
            "temperature_source": ctx.temperature_source,
            "efficiency_at_temperature": [
                [float(t), float(e)] for t, e in zip(bp, eta, strict=True)
            ],
            "source": source,
        }

    def describe(self, ctx, ev, model=None) -> str | None:
        pts = [f"{e:.3f} at {t:.1f} K" for t, e in ev["efficiency_at_temperature"]]
        how = "fitted" if ev["source"] == "fit" else "seen in the residual"
        return (
            f"the torque-proportional loss changes with temperature (r = "
            f"{ev['correlation']:.2f}): efficiency {how} {', '.join(pts)} "
            f"({ev['temperature_source']} temperature spans {ev['temperature_span_K']:.1f} K); "
            f"largest in {ev['regime']}"
        )

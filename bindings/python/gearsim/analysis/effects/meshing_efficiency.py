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
    robust,
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

    #: the power threshold's seed and upper bound, as fractions of the
    #: record's robust peak of the transmitted power (the loss changes side
    #: over that much power): a smoothing wider than a percent of the peak
    #: blurs every reversal of the power flow, and on a noisy record the fit
    #: could take it for a better efficiency (the demo record: 10 % of the
    #: peak, the held-out error 11 % worse than with a switch)
    POWER_SEED, POWER_MAX = 1e-3, 1e-2

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        x0 = eff_from_loss(seed_of(screening, "mesh", 0.02))
        out = [FitParam("efficiency_const", min(x0, 0.999), 0.3, 1.0, "", owner=self.name)]
        if "power_threshold" not in ctx.model.block_params:
            # where the power flow reverses, the loss moves from one side to
            # the other over the power threshold; the model gives none, so it
            # is fitted with the efficiency (the 1 mW default is a switch)
            p_peak = robust(ctx.T * ctx.v) or 1.0
            seed = self.POWER_SEED * p_peak
            out.append(
                FitParam(
                    "power_threshold",
                    seed,
                    1e-7 * p_peak,
                    self.POWER_MAX * p_peak,
                    "W",
                    owner=self.name,
                    # from a switch to the upper bound: the cost is flat below
                    # the power the record resolves, so look far down
                    grid=(1e-3, 1e-2, 0.1, 1.0, 10.0),
                    diff_step=1e-3,
                    log=True,
                )
            )
        return out

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "efficiency_const" not in values:
            return {}, {}
        eta = float(values["efficiency_const"])
        block: dict[str, Any] = {"friction_model": "constant_efficiency", "efficiency_const": eta}
        if "power_threshold" in values:
            block["power_threshold"] = float(values["power_threshold"])
        return block, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        return {"efficiency_const": v["efficiency_const"], "power_threshold": v["power_threshold"]}

    #: a constant efficiency below this loses in both directions of power
    #: flow: the residual must show it in both
    SEEN_LOSS = 0.95

    def inconsistent(self, ctx: Any, model: Any) -> str | None:
        """A constant efficiency loses (1/eta - 1) of the torque while the
        drive drives and (1 - eta) while the load overruns: when the baseline
        residual shows no such loss in one direction, a fitted efficiency
        stands in for another effect (a missing viscous friction, which takes
        power in both directions in proportion to speed, not to torque)."""
        if not self.present(model) or mk.friction_model(model) != "constant_efficiency":
            return None
        eta = float(mk.block_values(model)["efficiency_const"])
        if eta >= self.SEEN_LOSS:
            return None
        split = flow_split(ctx)
        # possible loss factors: any positive one while driving, below 1
        # while overrunning (the load cannot lose more than it brings)
        for flow, needed, top in (
            ("driving", 1.0 / eta - 1.0, np.inf),
            ("overrunning", 1.0 - eta, 1.0),
        ):
            seen = split.get(f"loss_factor_{flow}")
            if seen is not None and not 0.0 < seen < top:
                return (
                    f"the residual's loss factor while {flow} is {fmt(seen)}, no efficiency's; an "
                    f"efficiency of {fmt(eta)} needs {fmt(needed)} there: it stands in for "
                    "another effect"
                )
        return None

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

    def evidence_extra(self, ctx, screening, own, model=None) -> dict[str, Any]:
        ev: dict[str, Any] = dict(flow_split(ctx))
        if model is not None and mk.friction_model(model) == "constant_efficiency":
            ev["efficiency"] = float(mk.block_values(model)["efficiency_const"])
            ev["efficiency_source"] = "fit"
        else:
            ev["efficiency"] = eff_from_loss(own.get("mesh", 0.0))
            ev["efficiency_source"] = "screening"
        return ev

    def describe(self, ctx, ev, model=None) -> str | None:
        # a loss factor is 1/eta - 1 >= 0 while driving, 1 - eta in [0, 1)
        # while overrunning: others are no loss of this kind
        parts = []
        for flow, ok in (
            ("driving", lambda x: x > 0),
            ("overrunning", lambda x: 0 < x < 1),
        ):
            x = ev.get(f"loss_factor_{flow}", float("nan"))
            parts.append(
                f"loss factor {fmt(x)} while {flow}" if ok(x) else f"no such loss while {flow}"
            )
        how = "fitted" if ev["efficiency_source"] == "fit" else "screening"
        return (
            f"residual proportional to |transmitted torque| x sign(speed) (r = "
            f"{ev['correlation']:.2f}): {', '.join(parts)} ({how} efficiency "
            f"{fmt(ev['efficiency'])}); largest in {ev['regime']}"
        )

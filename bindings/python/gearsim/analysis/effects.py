"""The effects of docs/measurement-format.md section 3, one class each.

An effect class owns everything the analysis knows about one physical effect,
so that diagnose, fitting and report never test an effect's name:

- ``name``, ``blocks`` (rigs it applies to), ``summary``;
- ``unavailable(model)``: why it cannot be added (a combination the block
  cannot express), or None; ``present(model)``: whether the model has it;
- ``signature_text`` and ``columns(ctx)``: its residual signature and the
  screening regressors, with the physical bounds of their coefficients;
- ``screen(ctx)`` and ``ruled_out(ctx, screen)``: the screening result that
  seeds the fit, and the reason screening alone rules it out (not fitted);
- ``parameters(ctx, screen)``: the fit's free parameters, bounds and seeds;
- ``coestimated(ctx, screen)`` / ``nuisance_columns(ctx)``: when the model
  already has the effect, the parameters re-estimated with a new effect that
  trades off against it, and their screening columns;
- ``build(ctx, values)``: the block and rig changes for parameter values;
- ``report(model)``: how its fitted parameters are reported;
- ``describe(ctx, screen, ...)``: the evidence text;
- ``excitation`` / ``separated_from``: the excitation that tells it apart from
  its look-alikes (identifiability warnings name it);
- ``negligible(ctx, model)``: why the fitted size is below what the record
  can claim (the candidate then does not help), or None;
- ``plot(ctx, ax)``: the signature plot of the report, when the general
  residual plots do not show it.

Adding an effect means writing one subclass and registering it in EFFECTS.
The driven inertia is re-estimated with every new effect (an inertia error
shares the acceleration column with every torque-like effect):
:data:`INERTIA`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from . import modelkit as mk
from .errors import EffectError

__all__ = [
    "EFFECTS",
    "EFFECT_NAMES",
    "FitParam",
    "Effect",
    "INERTIA",
    "get_effect",
    "applicable_effects",
    "coestimated",
    "nuisance_columns",
    "build_changes",
    "apply_changes",
    "separating_excitation",
    "present_mesh_loss",
]

#: what Effect.build returns: (block, rig) changes, or (block, rig, analysis)
#: for an effect that sets a key of the model file's [analysis] table
Changes = tuple[dict[str, Any], ...]
Column = tuple[str, np.ndarray, tuple[float, float]]


@dataclass
class FitParam:
    """One free parameter of a fit.

    name: the program name it is reported under ("load_coulomb_friction",
    "efficiency_vector[1]", ...); x0: first guess; lower/upper: bounds; unit:
    SI unit for texts; role: "effect" (new) or "coestimated"; owner: the
    effect (or "inertia") it belongs to; before: its value in the starting
    model; grid: multipliers of x0 tried (cost only) before the local fit, for
    costs that are not smooth; starts: absolute first guesses from each of
    which a local fit is run, the best kept (multi-start); optional: left at
    x0 in quick fits (diagnose); diff_step: relative finite-difference step."""

    name: str
    x0: float
    lower: float
    upper: float
    unit: str = ""
    role: str = "effect"
    before: float | None = None
    owner: str = ""
    grid: tuple[float, ...] = ()
    starts: tuple[float, ...] = ()
    optional: bool = False
    diff_step: float = 1e-6

    def clipped_x0(self) -> float:
        return self.clip(self.x0)

    def clip(self, value: float) -> float:
        """value moved just inside the bounds (the optimiser needs a strictly
        feasible start)."""
        span = self.upper - self.lower
        eps = 1e-6 * (span if np.isfinite(span) else max(abs(value), 1.0))
        lo = self.lower + eps if np.isfinite(self.lower) else -np.inf
        hi = self.upper - eps if np.isfinite(self.upper) else np.inf
        return float(min(max(value, lo), hi))


# ---------------------------------------------------------------- helpers


def _seed(screen: Any, name: str, default: float = 0.0) -> float:
    """A screening coefficient by column name (default when not screened)."""
    names = getattr(screen, "names", None)
    if not names or name not in names:
        return default
    return screen.coefficient(name)


def _robust(x: np.ndarray, q: float = 99.0) -> float:
    return float(np.percentile(np.abs(x), q)) if x.size else 0.0


def _force_scale(ctx: Any) -> float:
    """A typical driven-side force: robust max of the transmitted torque."""
    return max(_robust(ctx.T), _robust(ctx.meas[ctx.torque_output] / ctx.kin), 1e-9)


def _speed_scale(ctx: Any) -> float:
    return max(_robust(ctx.v), 1e-9)


def _force_unit(model: Any) -> str:
    return "N*m" if mk.block_name(model) == "simple_gear" else "N"


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def present_mesh_loss(model: Any) -> float:
    """Present constant meshing loss 1 - eta (0 without an efficiency model)."""
    if mk.friction_model(model) == "constant_efficiency":
        return 1.0 - float(mk.block_values(model)["efficiency_const"])
    return 0.0


def _eff_from_loss(loss: float) -> float:
    # the screening coefficient mixes 1-eta (overrunning) and 1/eta-1
    # (driving); their mean is ~ (1-eta)(1+1/eta)/2, close to 1-eta
    return float(min(max(1.0 - loss, 0.3), 1.0))


# ---------------------------------------------------------------- the base class


class Effect:
    """One physical effect (see the module docstring). Subclasses set the
    class attributes and override the methods that differ."""

    name: str = ""
    blocks: tuple[str, ...] = ("simple_gear", "rack_pinion")
    summary: str = ""
    signature_text: str = ""
    #: number of parameters the effect adds (the fit may add optional ones)
    n_params: int = 1
    #: effects whose model parameters this one replaces when added (they are
    #: then not re-estimated alongside it)
    replaces: tuple[str, ...] = ()
    #: its simulation is costly (contact): fits run on a leading part of the
    #: record and include the driven-speed output
    costly: bool = False
    #: the excitation that separates it from everything else, and from named
    #: look-alikes
    excitation: str = ""
    separated_from: dict[str, str] = {}
    internal_excitation: str = ""
    #: plot(ctx, ax): draws the effect's signature on a matplotlib axis for
    #: the report (None: the report's general residual plots show it)
    plot: Any = None

    # -- applicability
    def unavailable(self, model: Any) -> str | None:
        return None

    def present(self, model: Any) -> bool:  # pragma: no cover - every subclass overrides
        raise NotImplementedError

    def applies(self, model: Any) -> str | None:
        """Why the effect cannot be a candidate for model, or None."""
        blk = mk.block_name(model)
        if blk not in self.blocks:
            return f"does not apply to the {blk} rig"
        if self.present(model):
            return "already in the model"
        return self.unavailable(model)

    # -- screening
    def columns(self, ctx: Any) -> list[Column]:
        return []

    def screen(self, ctx: Any) -> Any:
        """The screening of this effect on the baseline residual: a bounded
        linear regression on the co-estimated columns plus its own."""
        from .signatures import screen

        return screen(ctx, nuisance_columns(ctx, self), self.columns(ctx))

    def ruled_out(self, ctx: Any, screen: Any) -> str | None:
        """Why screening alone rules the effect out (it is then not fitted)."""
        return None

    def predicted_nrmse(self, ctx: Any, screen: Any) -> float:
        return float(screen.nrmse)

    # -- fitting
    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:  # pragma: no cover
        raise NotImplementedError

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:  # pragma: no cover
        raise NotImplementedError

    def report(self, model: Any) -> dict[str, Any]:  # pragma: no cover
        raise NotImplementedError

    def notes(self, model: Any) -> list[str]:
        """Notes on how the fit reads the effect (identifiability by design)."""
        return []

    def negligible(self, ctx: Any, model: Any) -> str | None:
        """Why the effect as fitted in `model` is too small for the record to
        claim it, although it may lower the error (then it does not help), or
        None."""
        return None

    # -- when the model already has it
    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        """Its present parameters, re-estimated when another effect is added."""
        return []

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        """Screening columns of the present parameters re-estimated with a new effect."""
        return []

    # -- evidence
    def evidence(self, ctx: Any, screen: Any) -> dict[str, Any]:
        """What the screening saw: partial correlation with the residual, the
        coefficients, the regime where the effect's part is largest, and a
        readable text."""
        nn = screen.nuisance
        own = {n: float(c) for n, c in zip(screen.names[nn:], screen.coef[nn:], strict=True)}
        regime, ratio = _own_regime(ctx, screen.explained)
        r = screen.partial_r
        ev: dict[str, Any] = {
            "signature": self.signature_text,
            "correlation": r,
            "explained_share": screen.r2_gain,
            "coefficients": own,
            "regime": regime,
            "regime_ratio": ratio,
        }
        if own:
            ev.update(self.evidence_extra(ctx, screen, own))
        if abs(r) < 0.1 or not np.any(screen.explained):
            ev["text"] = (
                f"no sign of it in the residual: {self.signature_text} is not seen "
                f"(partial correlation r = {r:.2f})"
            )
        else:
            ev["text"] = self.describe(ctx, screen, own, r, regime)
        return ev

    def describe(self, ctx: Any, screen: Any, own: dict[str, float], r: float, regime: Any) -> str:
        return f"{self.signature_text} (r = {r:.2f}); largest in {regime}"

    def evidence_extra(self, ctx: Any, screen: Any, own: dict[str, float]) -> dict[str, Any]:
        return {}

    def __repr__(self) -> str:
        return f"<effect {self.name}>"


def _own_regime(ctx: Any, part: np.ndarray) -> tuple[str | None, float]:
    """The regime where an effect's contribution is largest relative to its
    overall rms (regimes under 1 % of the samples, or 10, are skipped)."""
    tot = float(np.sqrt(np.mean(part**2))) if part.size else 0.0
    best, ratio = None, 0.0
    if tot <= 0:
        return None, 0.0
    for reg in ctx.regimes:
        if reg.mask.sum() < max(10, 0.01 * reg.mask.size):
            continue
        r = float(np.sqrt(np.mean(part[reg.mask] ** 2))) / tot
        if r > ratio:
            best, ratio = reg.name, r
    return best, ratio


# ---------------------------------------------------------------- inertia


class DrivenInertia:
    """The driven inertia (follower_inertia / rack_mass), re-estimated with
    every new effect. Not an effect a model can lack; it only takes part in
    the co-estimation and the identifiability texts."""

    name = "inertia"
    excitation = "accelerate and decelerate hard at constant load"
    separated_from = {
        "meshing_efficiency": "hold constant speeds under load (no acceleration) and accelerate "
        "hard with no load",
        "viscous_friction": "hold at two speeds, then accelerate hard between them",
        "coulomb_friction": "accelerate hard within one direction of motion",
        "load_offset": "hold still under load, then accelerate hard",
    }

    def parameter(self, ctx: Any, screen: Any) -> FitParam:
        key = mk.driven_inertia_key(ctx.model)
        j0 = float(mk.rig_values(ctx.model)[key])
        j = j0 + _seed(screen, "acceleration", 0.0)
        j = j if j > 0 else j0
        unit = "kg*m^2" if key == "follower_inertia" else "kg"
        return FitParam(
            key, j, j0 * 1e-3, j0 * 1e3, unit, role="coestimated", before=j0, owner=self.name
        )

    def column(self, ctx: Any) -> Column:
        j0 = float(mk.rig_values(ctx.model)[mk.driven_inertia_key(ctx.model)])
        return ("acceleration", ctx.columns["acceleration"], (-0.999 * j0, 1e3 * j0))


INERTIA = DrivenInertia()


# ---------------------------------------------------------------- the effects


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

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        cur = mk.viscous_value(ctx.model)
        x0 = max(cur + _seed(screen, "speed"), 0.0)
        hi = 20.0 * _force_scale(ctx) / _speed_scale(ctx)
        unit = "N*m/(rad/s)" if mk.block_name(ctx.model) == "simple_gear" else "N/(m/s)"
        key = self.key(ctx.model)
        return [FitParam(key, x0, 0.0, max(hi, 10 * x0), unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
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

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        return [_as_coestimated(p) for p in self.parameters(ctx, screen)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def describe(self, ctx, screen, own, r, regime) -> str:
        return (
            f"residual grows in proportion to speed (r = {r:.2f}, slope "
            f"{_fmt(own.get('speed', 0.0))} {ctx.meas.spec.driven_force_unit} per "
            f"{ctx.meas.spec.driven_speed_unit} of driven speed); largest in {regime}"
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

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        cur = float(mk.rig_values(ctx.model)["load_coulomb_friction"])
        x0 = max(cur + _seed(screen, "sign"), 0.0)
        hi = max(5.0 * _force_scale(ctx), 10 * x0)
        unit = _force_unit(ctx.model)
        return [FitParam("load_coulomb_friction", x0, 0.0, hi, unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "load_coulomb_friction" not in values:
            return {}, {}
        return {}, {"load_coulomb_friction": float(values["load_coulomb_friction"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"load_coulomb_friction": mk.rig_values(model)["load_coulomb_friction"]}

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        return [_as_coestimated(p) for p in self.parameters(ctx, screen)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def describe(self, ctx, screen, own, r, regime) -> str:
        fc = own.get("sign", 0.0)
        return (
            f"residual follows sign(speed) (r = {r:.2f}): a step of 2 x {_fmt(fc)} "
            f"{ctx.meas.spec.driven_force_unit} at each direction reversal; largest in {regime}"
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

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        cur = float(mk.rig_values(ctx.model)["load_offset"])
        x0 = cur + _seed(screen, "constant")
        lim = max(5.0 * _force_scale(ctx), 10 * abs(x0))
        unit = _force_unit(ctx.model)
        return [FitParam("load_offset", x0, -lim, lim, unit, before=cur, owner=self.name)]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "load_offset" not in values:
            return {}, {}
        return {}, {"load_offset": float(values["load_offset"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"load_offset": mk.rig_values(model)["load_offset"]}

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        return [_as_coestimated(p) for p in self.parameters(ctx, screen)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def describe(self, ctx, screen, own, r, regime) -> str:
        bias = -own.get("constant", 0.0)
        shown = ("driving", "overrunning", "direction_reversal", "high_speed")
        per = [
            f"{reg.name} {_fmt(float(np.mean(ctx.r_d[reg.mask])))}"
            for reg in ctx.regimes
            if reg.mask.any() and reg.name in shown
        ]
        return (
            f"constant bias of the driven-side residual: {_fmt(bias)} "
            f"{ctx.meas.spec.driven_force_unit} of missing load offset (r = {r:.2f}); mean "
            f"residual by regime: {', '.join(per)}"
        )


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
        return mk.friction_model(model) in _EFFICIENCY_MODELS

    def columns(self, ctx: Any) -> list[Column]:
        return [("mesh", ctx.columns["mesh"], (0.0, 0.7))]

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        x0 = _eff_from_loss(_seed(screen, "mesh", 0.02))
        return [FitParam("efficiency_const", min(x0, 0.999), 0.3, 1.0, "", owner=self.name)]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "efficiency_const" not in values:
            return {}, {}
        eta = float(values["efficiency_const"])
        return {"friction_model": "constant_efficiency", "efficiency_const": eta}, {}

    def report(self, model: Any) -> dict[str, Any]:
        return {"efficiency_const": mk.block_values(model)["efficiency_const"]}

    def _constant(self, model: Any) -> bool:
        return mk.friction_model(model) == "constant_efficiency"

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        if not self._constant(ctx.model):
            return []  # the table efficiencies are not re-estimated automatically
        cur = float(mk.block_values(ctx.model)["efficiency_const"])
        eta = _eff_from_loss((1.0 - cur) + _seed(screen, "mesh", 0.0))
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

    def describe(self, ctx, screen, own, r, regime) -> str:
        split = _flow_split(ctx)
        return (
            f"residual proportional to |transmitted torque| x sign(speed) (r = {r:.2f}): loss "
            f"factor {_fmt(split.get('loss_factor_driving', float('nan')))} while driving, "
            f"{_fmt(split.get('loss_factor_overrunning', float('nan')))} while overrunning "
            f"(efficiency ~ {_fmt(1.0 - own.get('mesh', 0.0))}); largest in {regime}"
        )

    def evidence_extra(self, ctx, screen, own) -> dict[str, Any]:
        return _flow_split(ctx)


def _flow_split(ctx: Any) -> dict[str, float]:
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


_EFFICIENCY_MODELS = (
    "constant_efficiency",
    "load_dependent_efficiency",
    "temperature_dependent_efficiency",
    "temperature_load_dependent_efficiency",
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

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        g = float(mk.block_values(ctx.model)["teeth_ratio"])
        idle_f = max(_seed(screen, "idle", 0.0), 0.0)  # follower-referred g*tau_idle
        k = max(present_mesh_loss(ctx.model) + _seed(screen, "mesh", 0.02), 0.0)
        hi = max(2.0 * _force_scale(ctx) / g, 10 * idle_f / g)
        return [
            FitParam("idle_torque", idle_f / g, 0.0, hi, "N*m", owner=self.name),
            FitParam("load_slope", k, 0.0, 2.0, "", owner=self.name),
        ]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "idle_torque" not in values:
            return {}, {}  # present and not re-estimated
        g = float(mk.block_values(ctx.model)["teeth_ratio"])
        tnom = ctx.nominal_torque
        idle = float(values["idle_torque"])
        k = float(values["load_slope"])
        # eq. 2.5: k = 1/eta_nom - 1 - g*tau_idle/tau_nom  =>  eta_nom; keep
        # eta_nom < 1 strictly against rounding
        eta = min(1.0 / (1.0 + k + g * idle / tnom + 1e-12), 1.0 - 1e-9)
        return {
            "friction_model": "load_dependent_efficiency",
            "idle_torque": idle,
            "nominal_output_torque": tnom,
            "efficiency_nominal": eta,
        }, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        keys = ("idle_torque", "nominal_output_torque", "efficiency_nominal")
        return {k: v[k] for k in keys}

    def describe(self, ctx, screen, own, r, regime) -> str:
        eff = self.evidence_extra(ctx, screen, own)["efficiency_at_load"]
        return (
            f"loss = {_fmt(own.get('idle', 0.0))} {ctx.meas.spec.driven_force_unit} at no load + "
            f"{_fmt(own.get('mesh', 0.0))} x |transmitted torque| (r = {r:.2f}): efficiency "
            f"{_fmt(eff['10%'])} at 10 % of the peak load vs {_fmt(eff['100%'])} at the peak; "
            f"largest in {regime}"
        )

    def evidence_extra(self, ctx, screen, own) -> dict[str, Any]:
        idle, k = own.get("idle", 0.0), own.get("mesh", 0.0)
        tmax = float(np.percentile(np.abs(ctx.T), 95)) or 1.0
        eff = {}
        for frac in (0.1, 1.0):
            t = frac * tmax
            eff[f"{int(frac * 100)}%"] = t / (t + idle + k * t) if t > 0 else float("nan")
        return {"efficiency_at_load": eff}


class TemperatureDependentEfficiency(Effect):
    name = "temperature_dependent_efficiency"
    summary = (
        "efficiency interpolated over temperature (friction_model = "
        "temperature_dependent_efficiency)"
    )
    signature_text = "the torque-proportional meshing loss changes with temperature"
    n_params = 3
    replaces = ("meshing_efficiency",)
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
        from .signatures import temperature_breakpoints

        return temperature_breakpoints(ctx.temperature)

    def columns(self, ctx: Any) -> list[Column]:
        from .signatures import temperature_hats

        if float(np.ptp(ctx.temperature)) < self.MIN_SPAN:
            return []
        bp = self.breakpoints(ctx)
        hats = temperature_hats(ctx.temperature, bp)
        loss = present_mesh_loss(ctx.model)
        mesh = ctx.columns["mesh"]
        return [
            (f"mesh@{t:.1f}K", mesh * hats[:, i], (-loss, 0.7 - loss)) for i, t in enumerate(bp)
        ]

    def ruled_out(self, ctx: Any, screen: Any) -> str | None:
        span = float(np.ptp(ctx.temperature))
        if span < self.MIN_SPAN:
            return (
                f"the {ctx.temperature_source} temperature spans only {span:.2f} K: a "
                "temperature dependence cannot be seen in this record"
            )
        return None

    def predicted_nrmse(self, ctx: Any, screen: Any) -> float:
        return float(screen.nrmse)

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        loss = present_mesh_loss(ctx.model)
        out = []
        for i, t in enumerate(self.breakpoints(ctx)):
            # screening coefficients are changes of the present loss 1 - eta
            d_loss = _seed(screen, f"mesh@{t:.1f}K", 0.02 if loss == 0 else 0.0)
            eta = min(_eff_from_loss(loss + d_loss), 0.999)
            out.append(FitParam(f"efficiency_vector[{i}]", eta, 0.3, 1.0, "", owner=self.name))
        return out

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
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

    def describe(self, ctx, screen, own, r, regime) -> str:
        loss = present_mesh_loss(ctx.model)
        pts = [f"{1.0 - (loss + c):.3f} at {name.split('@')[1]}" for name, c in own.items()]
        span = float(np.ptp(ctx.temperature))
        return (
            f"the torque-proportional loss changes with temperature (r = {r:.2f}): efficiency "
            f"{', '.join(pts)} ({ctx.temperature_source} temperature spans {span:.1f} K); "
            f"largest in {regime}"
        )

    def evidence_extra(self, ctx, screen, own) -> dict[str, Any]:
        return {
            "temperature_span_K": float(np.ptp(ctx.temperature)),
            "temperature_source": ctx.temperature_source,
        }


class Backlash(Effect):
    name = "backlash"
    summary = "backlash with its gap (stiffness and damping kept)"
    signature_text = (
        "residual concentrated right after reversals of the transmitted torque, with a "
        "driven-speed residual whose integral is the gap"
    )
    costly = True
    excitation = "dwell at zero speed, then reverse the load slowly"
    separated_from: dict[str, str] = {}
    #: what separates its own parameters (gap, contact stiffness, damping)
    internal_excitation = (
        "reverse the load slowly (the gap shows) and quickly (contact stiffness and damping show)"
    )
    #: concentration of the driven-speed residual after reversals below which
    #: the screening rules backlash out (~1 without backlash-like physics)
    MIN_STRENGTH = 1.5
    #: local fits started from this many gaps spread over the evidence's range
    STARTS = 5

    def present(self, model: Any) -> bool:
        return bool(mk.block_values(model).get("backlash_enabled", False))

    def unavailable(self, model: Any) -> str | None:
        if float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0:
            return "backlash needs a rigid base shaft (the model has a compliant one)"
        return None

    def screen(self, ctx: Any) -> Any:
        from .signatures import backlash_evidence

        return backlash_evidence(ctx)

    def ruled_out(self, ctx: Any, screen: Any) -> str | None:
        if screen.strength >= self.MIN_STRENGTH:
            return None
        return (
            f"the driven-speed residual is not concentrated after reversals "
            f"({screen.strength:.2f}x its share, {self.MIN_STRENGTH}x needed)"
        )

    def predicted_nrmse(self, ctx: Any, screen: Any) -> float:
        return float(screen.predicted_nrmse)

    def start_gaps(self, screen: Any) -> tuple[float, ...]:
        """First guesses of the gap (m): geometric steps over the range the
        evidence gives, widened by 2 on each side (the integral of the speed
        residual over a window under- or over-shoots the gap)."""
        lo, hi = getattr(screen, "gap_range", (0.0, 0.0))
        if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= 0:
            return (1e-4, 3e-4, 1e-3, 3e-3)
        lo = max(lo, 0.05 * hi, 1e-7)
        return tuple(float(g) for g in np.geomspace(0.5 * lo, 2.0 * hi, self.STARTS))

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        gap = getattr(screen, "gap_estimate", None) if screen is not None else None
        if not gap or not np.isfinite(gap) or gap <= 0:
            gap = 1e-3
        v = mk.block_values(ctx.model)
        k0, d0 = float(v["stiffness"]), float(v["damping"])
        o = self.name
        return [
            FitParam(
                "linear_backlash",
                float(gap),
                1e-7,
                max(100.0 * gap, 0.05),
                "m",
                owner=o,
                starts=self.start_gaps(screen),
                diff_step=1e-3,
            ),
            FitParam(
                "stiffness",
                k0,
                1e-3 * k0,
                1e3 * k0,
                "N/m",
                owner=o,
                grid=(0.1, 0.3, 1.0, 3.0),
                optional=True,
                diff_step=1e-3,
            ),
            FitParam(
                "damping",
                d0,
                0.0,
                1e3 * max(d0, 1.0),
                "N*s/m",
                owner=o,
                grid=(0.3, 1.0, 3.0),
                optional=True,
                diff_step=1e-3,
            ),
        ]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "linear_backlash" not in values:
            return {}, {}
        b = float(values["linear_backlash"])
        v = mk.block_values(ctx.model)
        block: dict[str, Any] = {"backlash_enabled": True, "linear_backlash": b}
        for key in ("stiffness", "damping"):
            if key in values:
                block[key] = float(values[key])
        d = float(v.get("transition_region", 1e-4))
        if v.get("hard_stop_model", "smooth") == "smooth" and d >= 0.25 * b:
            block["transition_region"] = 0.25 * b
        return block, {}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        out = {k: v[k] for k in ("linear_backlash", "stiffness", "damping")}
        if mk.block_name(model) == "simple_gear":
            out["base_radius"] = v["base_radius"]
        return out

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        # the present gap, stiffness and damping are re-estimated with a new
        # effect: fitted without it (a friction missing), the contact absorbs
        # part of the missing loss
        v = mk.block_values(ctx.model)
        out = []
        for p in self.parameters(ctx, None):
            now = float(v[p.name])
            p.x0, p.before, p.role = now, now, "coestimated"
            p.lower, p.upper = min(p.lower, now), max(p.upper, now)
            p.starts, p.grid, p.optional = (), (), False
            out.append(p)
        return out

    def evidence(self, ctx: Any, be: Any) -> dict[str, Any]:
        ms = be.window * ctx.meas.dt * 1e3
        conc = {k: float(v) for k, v in be.concentration.items()}
        so, to = ctx.speed_output, ctx.torque_output
        share_s = conc.get(so, 0) * be.time_fraction * 100
        share_t = conc.get(to, 0) * be.time_fraction * 100
        return {
            "signature": self.signature_text,
            "reversals": int(be.events.size),
            "window_ms": ms,
            "time_fraction": be.time_fraction,
            "concentration": conc,
            "gap_estimate_m": be.gap_estimate,
            "gap_range_m": list(be.gap_range),
            "regime": "torque_reversal",
            "text": (
                f"{100 * be.time_fraction:.1f} % of the time (the {ms:.0f} ms after "
                f"{be.events.size} torque reversals) holds {share_s:.0f} % of the {so} residual "
                f"energy ({conc.get(so, 0):.1f}x its share) and {share_t:.0f} % of the {to} "
                f"residual energy; the {so} residual integrates to a gap of "
                f"{be.gap_estimate * 1e3:.3g} mm"
            ),
        }


# ---------------------------------------------------------------- effects beyond the seed blocks


def _rig_has(model: Any, key: str) -> str | None:
    """None when this gearsim's rig has the parameter `key`, else why not."""
    if key in mk.rig_values(model):
        return None
    return f"this gearsim build has no rig parameter {key}"


def _cached(ctx: Any, name: str, make: Any) -> np.ndarray:
    """A derived per-sample signal, computed once per baseline context."""
    if name not in ctx.columns:
        ctx.columns[name] = make()
    return ctx.columns[name]


def _torque_rate(ctx: Any) -> np.ndarray:
    """d/dt of the simulated drive torque (undelayed), N*m/s."""
    from .simulate import delayed

    def make() -> np.ndarray:
        y = ctx.sim.outputs[ctx.torque_output]
        # the simulation applies the model's present delay; take it back out
        d = mk.torque_delay(ctx.model)
        y = delayed(y, -d / ctx.meas.dt) if d else y
        return np.gradient(y, ctx.meas.dt)

    return _cached(ctx, "torque_rate", make)


class SensorDelay(Effect):
    """A logger lag of the torque channel: the simulated torque is delayed by
    torque_delay (model file [analysis] table) before it is compared."""

    name = "sensor_delay"
    summary = (
        "delay of the measured torque relative to the speed channels ([analysis] torque_delay)"
    )
    signature_text = (
        "residual correlates with the derivative of the simulated torque, peaking at half the delay"
    )
    excitation = "steps of acceleration (a delay shifts the torque steps, an inertia scales them)"
    separated_from = {
        "compliance": "steps of acceleration: a delay shifts the torque step, a compliant "
        "shaft rings after it",
        "inertia": "steps of acceleration: a delay shifts the torque step, an inertia scales it",
    }
    #: the largest delay searched (s): loggers lag by milliseconds
    MAX_DELAY = 0.1

    def present(self, model: Any) -> bool:
        return mk.torque_delay(model) != 0.0

    def columns(self, ctx: Any) -> list[Column]:
        # first order: y(t - d) - y(t) ~ -d y'(t), in driven units
        col = -_torque_rate(ctx) / ctx.kin
        return [("torque_delay", col, (-self.MAX_DELAY, self.MAX_DELAY))]

    def signature(self, ctx: Any) -> Any:
        from .signatures import delay_signature

        return delay_signature(
            ctx.residual[ctx.torque_output],
            ctx.meas[ctx.torque_output] - ctx.residual[ctx.torque_output],
            ctx.meas.dt,
            self.MAX_DELAY,
        )

    def _span(self, ctx: Any, seed: float) -> float:
        return float(min(self.MAX_DELAY, max(20.0 * ctx.meas.dt, 4.0 * abs(seed))))

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        cur = mk.torque_delay(ctx.model)
        x0 = cur + _seed(screen, "torque_delay")
        lim = self._span(ctx, x0)
        return [
            FitParam(
                "torque_delay",
                x0,
                -lim,
                lim,
                "s",
                before=cur,
                owner=self.name,
                # the interpolated delay is piecewise linear between samples:
                # an absolute step of a twentieth of a sample
                diff_step=0.05 * ctx.meas.dt,
            )
        ]

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "torque_delay" not in values:
            return {}, {}
        return {}, {}, {"torque_delay": float(values["torque_delay"])}

    def report(self, model: Any) -> dict[str, Any]:
        return {"torque_delay": mk.torque_delay(model)}

    #: delays under this many samples are not claimed: the sampling itself
    #: blurs the channels' relative timing by up to a sample (a logger's
    #: stamps), and a central-difference speed or a held output shifts a
    #: channel by half a sample more
    MIN_SAMPLES = 1.5

    def negligible(self, ctx: Any, model: Any) -> str | None:
        d = mk.torque_delay(model)
        dt = ctx.meas.dt
        if abs(d) >= self.MIN_SAMPLES * dt:
            return None
        return (
            f"the fitted delay {1e3 * d:.3g} ms is under {self.MIN_SAMPLES:g} samples "
            f"({1e3 * self.MIN_SAMPLES * dt:.3g} ms): within the timing resolution of the record"
        )

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        return [_as_coestimated(p) for p in self.parameters(ctx, screen)]

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        return self.columns(ctx)

    def evidence_extra(self, ctx: Any, screen: Any, own: dict[str, float]) -> dict[str, Any]:
        sig = self.signature(ctx)
        return {
            "peak_lag_s": sig.peak_lag_s,
            "peak_correlation": sig.peak_r,
            "delay_from_correlation_s": sig.delay_s,
        }

    def describe(self, ctx, screen, own, r, regime) -> str:
        sig = self.signature(ctx)
        return (
            f"the residual correlates with the derivative of the simulated torque (r = "
            f"{sig.peak_r:.2f} at a lag of {1e3 * sig.peak_lag_s:.2f} ms): the measured torque "
            f"lags the model by about {1e3 * own.get('torque_delay', 0.0):.2f} ms; largest in "
            f"{regime}"
        )

    def plot(self, ctx: Any, ax: Any) -> None:
        sig = self.signature(ctx)
        ax.plot(1e3 * sig.lags_s, sig.correlation, lw=1)
        ax.axvline(1e3 * sig.peak_lag_s, color="C3", ls="--", lw=1)
        ax.set_xlabel("lag (ms)")
        ax.set_ylabel("corr(residual, d torque/dt)")
        # a pure delay d peaks at d/2 with a negative correlation
        ax.set_title(
            f"sensor_delay: peak r = {sig.peak_r:.2f} at {1e3 * sig.peak_lag_s:.2f} ms "
            "(a delay d peaks at d/2, r < 0)"
        )


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
    excitation = "hold at several low speeds"
    separated_from = {
        "coulomb_friction": "hold at several low speeds (the Stribeck hump falls with speed, "
        "Coulomb friction does not)",
        "viscous_friction": "hold at several low speeds and at one high speed",
    }

    def unavailable(self, model: Any) -> str | None:
        return _rig_has(model, "load_breakaway_friction")

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model).get("load_breakaway_friction", 0.0)) > 0.0

    def profile(self, ctx: Any) -> Any:
        from .signatures import speed_profile

        return speed_profile(ctx.r_d, ctx.v)

    def _column(self, ctx: Any, vs: float) -> np.ndarray:
        return ctx.columns["sign"] * np.exp(-((ctx.v / max(vs, 1e-12)) ** 2))

    def _own(self, ctx: Any, vs: float) -> list[Column]:
        cols = [("stribeck", self._column(ctx, vs), (0.0, np.inf))]
        if not CoulombFriction().present(ctx.model):
            cols.append(("sign", ctx.columns["sign"], (0.0, np.inf)))
        return cols

    def screen(self, ctx: Any) -> Any:
        """The profile's Stribeck speed, and the screening regression with
        the hump's column at that speed and at 1/3 and 3 times it (the best
        one kept): the profile is coarse at the lowest speeds."""
        from .signatures import screen

        prof = self.profile(ctx)
        vs0 = prof.stribeck_speed if prof.stribeck_speed > 0 else 0.05 * _speed_scale(ctx)
        best = None
        for vs in (vs0 / 3.0, vs0, 3.0 * vs0):
            sr = screen(ctx, nuisance_columns(ctx, self), self._own(ctx, vs))
            if best is None or sr.nrmse < best.nrmse:
                best, best_vs = sr, vs
        best.stribeck_speed = best_vs
        best.profile = prof
        return best

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        unit = _force_unit(ctx.model)
        vunit = "rad/s" if mk.block_name(ctx.model) == "simple_gear" else "m/s"
        vmax = _speed_scale(ctx)
        vs = float(getattr(screen, "stribeck_speed", 0.0) or 0.05 * vmax)
        excess = max(_seed(screen, "stribeck", 0.0), 0.0)
        hi = max(5.0 * _force_scale(ctx), 10.0 * excess)
        out = [
            FitParam("breakaway_excess", excess, 0.0, hi, unit, owner=self.name),
            FitParam(
                "load_stribeck_speed",
                vs,
                1e-4 * vmax,
                vmax,
                vunit,
                before=float(rig.get("load_stribeck_speed", 0.01)),
                owner=self.name,
                grid=(0.3, 1.0, 3.0),
            ),
        ]
        if not CoulombFriction().present(ctx.model):
            fc = max(_seed(screen, "sign", 0.0), 0.0)
            out.append(
                FitParam(
                    "load_coulomb_friction", fc, 0.0, hi, unit, before=0.0, owner="coulomb_friction"
                )
            )
        return out

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
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

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        fc = float(rig["load_coulomb_friction"])
        vs = float(rig["load_stribeck_speed"])
        ex = float(rig["load_breakaway_friction"]) - fc
        hi = max(5.0 * _force_scale(ctx), 10.0 * ex)
        return [
            FitParam(
                "breakaway_excess",
                ex,
                0.0,
                hi,
                _force_unit(ctx.model),
                "coestimated",
                ex,
                self.name,
            ),
            FitParam(
                "load_stribeck_speed",
                vs,
                min(1e-4 * _speed_scale(ctx), vs),
                max(_speed_scale(ctx), vs),
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

    def evidence_extra(self, ctx: Any, screen: Any, own: dict[str, float]) -> dict[str, Any]:
        prof = getattr(screen, "profile", None) or self.profile(ctx)
        return {
            "profile_coulomb": prof.coulomb,
            "profile_excess": prof.excess,
            "stribeck_speed": getattr(screen, "stribeck_speed", prof.stribeck_speed),
        }

    def describe(self, ctx, screen, own, r, regime) -> str:
        vs = float(getattr(screen, "stribeck_speed", 0.0))
        fu, vu = ctx.meas.spec.driven_force_unit, ctx.meas.spec.driven_speed_unit
        return (
            f"the friction level seen in the residual falls with speed (r = {r:.2f}): "
            f"{_fmt(own.get('stribeck', 0.0))} {fu} above the level in motion near rest, "
            f"decaying over ~{_fmt(vs)} {vu}; largest in {regime}"
        )

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


class Compliance(Effect):
    """A torsional spring-damper between the drive and the base gear, which
    turns with base_inertia (eq. 11.2-11.4). The rigid model's residual then
    rings at the shaft's natural frequency: a peak in its spectrum, which
    seeds the stiffness through omega_n^2 = k / J_eff."""

    name = "compliance"
    summary = (
        "compliant base shaft: torsional stiffness and damping between the drive and the base "
        "gear (rig compliance_stiffness, compliance_damping; base_inertia given or set)"
    )
    signature_text = (
        "residual power at a resonance: a peak in the residual spectrum, ringing after steps"
    )
    n_params = 2
    excitation = "steps of acceleration (the shaft rings after each)"
    separated_from = {
        "inertia": "steps of acceleration: the shaft rings after a step, an inertia error does not",
        "viscous_friction": "steps of acceleration between two held speeds",
    }
    internal_excitation = "steps of acceleration of several sizes"
    #: a spectral peak less prominent than this (peak / median of the octave
    #: around it outside the peak's -3 dB band, band_prominence)
    #: is no resonance: screening rules the effect out
    MIN_PROMINENCE = 8.0
    #: the base inertia seeded, as a fraction of the driven inertia seen at the base
    BASE_INERTIA_SEED = 0.2

    def unavailable(self, model: Any) -> str | None:
        why = _rig_has(model, "compliance_stiffness")
        if why:
            return why
        if mk.rig_values(model).get("base_drive", "speed") != "speed":
            return "a compliant shaft needs a speed-driven base"
        if mk.block_values(model).get("backlash_enabled", False):
            return "a compliant shaft needs a rigid mesh (the model has backlash)"
        return None

    def present(self, model: Any) -> bool:
        return float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0

    def screen(self, ctx: Any) -> Any:
        from .signatures import resonance

        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        res.prominence = self.band_prominence(res)
        tn = ctx.base_nrmse[ctx.torque_output]
        left = tn * np.sqrt(max(1.0 - res.band_share, 0.0)) if res.prominence else tn
        res.predicted_nrmse = ctx.overall_nrmse(left)
        return res

    @staticmethod
    def band_prominence(res: Any) -> float:
        """The peak's power over the median of the octave on each side,
        leaving out the peak's whole -3 dB band rather than three bins. A
        drive shaft does not ring at one frequency: with the motor held
        still it rings at sqrt(k/J_eff), while the motor moves the
        frequency rises, and the rigid model's residual also keeps what the
        input filter cut from the ring; the peak's own shoulders are no
        floor. A narrow peak keeps about the prominence of the spectrum."""
        f, p = res.freq_hz, res.psd
        if not np.isfinite(res.peak_hz) or f.size < 2:
            return float(res.prominence)
        i = int(np.argmin(np.abs(f - res.peak_hz)))
        half = 0.5 * p[i]
        left, right = i, i
        while left > 0 and p[left] > half:
            left -= 1
        while right < p.size - 1 and p[right] > half:
            right += 1
        octave = (f >= 0.5 * f[i]) & (f <= 2.0 * f[i])
        outside = octave & ((f < f[left]) | (f > f[right]))
        if np.count_nonzero(outside) < 5:  # too few bins for a median
            return float(res.prominence)
        return float(p[i] / max(float(np.median(p[outside])), 1e-300))

    def ruled_out(self, ctx: Any, screen: Any) -> str | None:
        if np.isfinite(screen.peak_hz) and screen.prominence >= self.MIN_PROMINENCE:
            return None
        return (
            f"the residual spectrum has no resonance peak (strongest {screen.prominence:.1f}x "
            f"its local floor, {self.MIN_PROMINENCE:g}x needed)"
        )

    def predicted_nrmse(self, ctx: Any, screen: Any) -> float:
        return float(screen.predicted_nrmse)

    @staticmethod
    def reflected_inertia(model: Any) -> float:
        """The driven inertia seen at the base shaft, a^2 J_F (kg*m^2)."""
        j = float(mk.rig_values(model)[mk.driven_inertia_key(model)])
        return mk.kinematic_ratio(model) ** 2 * j

    def base_inertia(self, ctx: Any) -> float:
        """The base gear's inertia: given (rig base_inertia > 0), else
        BASE_INERTIA_SEED of the driven inertia seen at the base. Only the sum
        J_B + k^2 J_driven is seen on a speed-driven rig (eq. 11.3-11.4: the
        shaft torque accelerates both alike), so it is not fitted: the
        co-estimated driven inertia takes the rest."""
        given = float(mk.rig_values(ctx.model).get("base_inertia", 0.0))
        return given if given > 0 else self.BASE_INERTIA_SEED * self.reflected_inertia(ctx.model)

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        # fitted as the natural frequency and damping ratio of eq. 11.4: the
        # stiffness alone trades off with the co-estimated inertia (both
        # move the frequency), the frequency does not
        f0 = float(getattr(screen, "peak_hz", float("nan")))
        if not np.isfinite(f0) or f0 <= 0:
            f0 = 0.05 / ctx.meas.dt
        zeta = getattr(screen, "damping_ratio", float("nan"))
        zeta = float(zeta) if np.isfinite(zeta) else 0.05
        o = self.name
        return [
            FitParam(
                "compliance_natural_frequency",
                f0,
                0.2 * f0,
                min(5.0 * f0, 0.5 / ctx.meas.dt),
                "Hz",
                owner=o,
                # a lightly damped ring runs through many cycles: a 1 %
                # frequency error turns its phase around, so look close first
                grid=(0.98, 0.99, 1.0, 1.01, 1.02),
                diff_step=1e-5,
            ),
            FitParam(
                "compliance_damping_ratio",
                min(max(zeta, 0.005), 0.5),
                0.0,
                2.0,
                "",
                owner=o,
                diff_step=1e-4,
            ),
        ]

    def _effective_inertia(self, ctx: Any, values: dict[str, float]) -> float:
        key = mk.driven_inertia_key(ctx.model)
        j = float(values.get(key, mk.rig_values(ctx.model)[key]))
        return self.base_inertia(ctx) + mk.kinematic_ratio(ctx.model) ** 2 * j

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
        if "compliance_natural_frequency" in values:
            wn = 2.0 * np.pi * float(values["compliance_natural_frequency"])
            zeta = float(values["compliance_damping_ratio"])
        elif "compliance_stiffness" in values:  # present, re-estimated
            k, c = float(values["compliance_stiffness"]), float(values["compliance_damping"])
            return {}, {"compliance_stiffness": k, "compliance_damping": c}
        else:
            return {}, {}
        j = self._effective_inertia(ctx, values)
        k = wn**2 * j
        return {}, {
            "compliance_stiffness": k,
            "compliance_damping": 2.0 * zeta * np.sqrt(k * j),
            "base_inertia": self.base_inertia(ctx),
        }

    def notes(self, model: Any) -> list[str]:
        return [
            "on a speed-driven rig only the sum base_inertia + (driven speed / base speed)^2 x "
            "driven inertia is seen; base_inertia is kept (given, or "
            f"{self.BASE_INERTIA_SEED:g} of the driven inertia seen at the base) and the driven "
            "inertia takes the rest"
        ]

    def report(self, model: Any) -> dict[str, Any]:
        rig = mk.rig_values(model)
        out = {k: rig[k] for k in ("compliance_stiffness", "compliance_damping", "base_inertia")}
        j = float(rig["base_inertia"]) + self.reflected_inertia(model)
        k = float(rig["compliance_stiffness"])
        if k > 0 and j > 0:
            out["natural_frequency_hz"] = float(np.sqrt(k / j) / (2.0 * np.pi))
        return out

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        out = []
        for key, unit in (("compliance_stiffness", "N*m/rad"), ("compliance_damping", "N*m*s/rad")):
            now = float(rig[key])
            lo, hi = (1e-2 * now, 1e2 * now) if now > 0 else (0.0, 1.0)
            out.append(
                FitParam(key, now, lo, hi, unit, "coestimated", now, self.name, diff_step=1e-4)
            )
        return out

    def evidence(self, ctx: Any, res: Any) -> dict[str, Any]:
        return {
            "signature": self.signature_text,
            "peak_hz": res.peak_hz,
            "prominence": res.prominence,
            "damping_ratio": res.damping_ratio,
            "band_share": res.band_share,
            "regime": None,
            "text": (
                f"the torque residual's spectrum peaks at {res.peak_hz:.1f} Hz, "
                f"{res.prominence:.1f}x its local floor, holding {100 * res.band_share:.0f} % "
                "of the residual power: a resonance a rigid shaft cannot ring at"
            ),
        }

    def plot(self, ctx: Any, ax: Any) -> None:
        from .signatures import resonance

        res = resonance(ctx.residual[ctx.torque_output], ctx.meas.dt)
        ax.semilogy(res.freq_hz[1:], res.psd[1:], lw=1)
        if np.isfinite(res.peak_hz):
            ax.axvline(res.peak_hz, color="C3", ls="--", lw=1)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("residual power density")
        ax.set_title(f"compliance: residual spectrum, peak {res.peak_hz:.1f} Hz")


#: (model key prefix, index, order factor) of the four ripple harmonics: the
#: per-revolution ones turn at i*theta, the per-tooth ones at j*Z*theta
_RIPPLE_TERMS = (
    ("revolution", 0, 1),
    ("revolution", 1, 2),
    ("mesh", 0, 1),
    ("mesh", 1, 2),
)


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
        why = _rig_has(model, "ripple_mesh_teeth")
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
        from .signatures import base_angle

        return _cached(ctx, "base_angle", lambda: base_angle(ctx.inputs.base_speed, ctx.meas.dt))

    def orders(self, model: Any) -> list[float]:
        z = self.teeth(model)
        return [float(k if kind == "revolution" else k * z) for kind, _, k in _RIPPLE_TERMS]

    def harmonics(self, ctx: Any) -> Any:
        from .signatures import angle_harmonics

        return angle_harmonics(
            ctx.residual[ctx.torque_output], self.theta(ctx), tuple(self.orders(ctx.model))
        )

    def selected(self, harmonics: Any) -> list[int]:
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

    def screen(self, ctx: Any) -> Any:
        sr = super().screen(ctx)
        sr.harmonics = self.harmonics(ctx)
        return sr

    def parameters(self, ctx: Any, screen: Any) -> list[FitParam]:
        harm = getattr(screen, "harmonics", None) or self.harmonics(ctx)
        amp_hi = 5.0 * _robust(ctx.meas[ctx.torque_output]) or 1.0
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

    def build(self, ctx: Any, values: dict[str, float]) -> Changes:
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

    def coestimated(self, ctx: Any, screen: Any) -> list[FitParam]:
        rig = mk.rig_values(ctx.model)
        amp_hi = 5.0 * _robust(ctx.meas[ctx.torque_output]) or 1.0
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

    def evidence_extra(self, ctx: Any, screen: Any, own: dict[str, float]) -> dict[str, Any]:
        harm = getattr(screen, "harmonics", None) or self.harmonics(ctx)
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

    def describe(self, ctx, screen, own, r, regime) -> str:
        harm = getattr(screen, "harmonics", None) or self.harmonics(ctx)
        parts = [
            f"{_fmt(h.amplitude)} N*m at {h.order:g}/rev"
            for h in harm
            if h.amplitude > self.SIGNIFICANCE * h.std_error
        ]
        shown = ", ".join(parts) or "no harmonic above the noise"
        return (
            f"the torque residual repeats with the base-shaft angle (r = {r:.2f}): {shown} "
            f"(Z = {self.teeth(ctx.model)} teeth); largest in {regime}"
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


def _as_coestimated(p: FitParam) -> FitParam:
    p.role = "coestimated"
    return p


#: The effects, by name, in the order they are offered.
EFFECTS: dict[str, Effect] = {
    e.name: e
    for e in (
        MeshingEfficiency(),
        LoadDependentEfficiency(),
        TemperatureDependentEfficiency(),
        ViscousFriction(),
        Backlash(),
        CoulombFriction(),
        LoadOffset(),
        SensorDelay(),
        StribeckFriction(),
        Compliance(),
        TorqueRipple(),
    )
}
#: The effects in the order they are offered (that of EFFECTS).
EFFECT_NAMES: tuple[str, ...] = tuple(EFFECTS)


def get_effect(name: str, model: Any | None = None) -> Effect:
    """The effect called name; raises EffectError (exit 2) naming it when it is
    unknown, not applicable to the model's rig, or already in the model."""
    eff = EFFECTS.get(name)
    if eff is None:
        raise EffectError(
            f"unknown effect '{name}'; known effects: {', '.join(EFFECT_NAMES)}", parameter=name
        )
    if model is not None:
        blk = mk.block_name(model)
        if blk not in eff.blocks:
            raise EffectError(f"effect '{name}' does not apply to the {blk} rig", parameter=name)
        why = eff.unavailable(model)
        if why:
            raise EffectError(f"effect '{name}' cannot be added: {why}", parameter=name)
        if eff.present(model):
            raise EffectError(f"effect '{name}': the model already has it", parameter=name)
    return eff


def applicable_effects(model: Any) -> tuple[list[Effect], dict[str, str]]:
    """Candidate effects for the model, and {effect: reason} for those left out."""
    out, skipped = [], {}
    for name, eff in EFFECTS.items():
        why = eff.applies(model)
        if why:
            skipped[name] = why
        else:
            out.append(eff)
    return out, skipped


# ---------------------------------------------------------------- co-estimation


def _present_others(model: Any, effect: Effect | None) -> list[Effect]:
    """Effects the model has that trade off against `effect` (all present ones
    but those it replaces)."""
    replaced = effect.replaces if effect is not None else ()
    return [
        e
        for e in EFFECTS.values()
        if e is not effect and e.name not in replaced and e.present(model)
    ]


def coestimated(ctx: Any, effect: Effect, screen: Any = None) -> list[FitParam]:
    """Existing parameters re-estimated together with effect: the driven
    inertia and the present parameters of the effects the model has."""
    out = [INERTIA.parameter(ctx, screen)]
    for other in _present_others(ctx.model, effect):
        out += other.coestimated(ctx, screen)
    return out


def nuisance_columns(ctx: Any, effect: Effect | None) -> list[Column]:
    """Screening columns of the co-estimated parameters (effect None: the
    present parameters alone)."""
    cols = [INERTIA.column(ctx)]
    for other in _present_others(ctx.model, effect):
        cols += other.nuisance_columns(ctx)
    return cols


def three_changes(changes: tuple) -> tuple[dict, dict, dict]:
    """(block, rig, analysis) from what Effect.build returns: (block, rig),
    or (block, rig, analysis) for an effect that sets an [analysis] key."""
    if len(changes) == 2:
        return dict(changes[0]), dict(changes[1]), {}
    return dict(changes[0]), dict(changes[1]), dict(changes[2])


def apply_changes(model: Any, changes: tuple) -> Any:
    """model with the changes of Effect.build (2- or 3-tuple) applied."""
    block, rig, analysis = three_changes(changes)
    return mk.changed(model, block, rig, analysis)


def build_changes(
    ctx: Any, effect: Effect, values: dict[str, float]
) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Block, rig and [analysis] changes for effect + co-estimated parameter values."""
    block: dict[str, Any] = {}
    rig: dict[str, Any] = {}
    analysis: dict[str, Any] = {}
    key = mk.driven_inertia_key(ctx.model)
    if key in values:
        rig[key] = float(values[key])
    for builder in [*_present_others(ctx.model, effect), effect]:
        b, r, a = three_changes(builder.build(ctx, values))
        block.update(b)
        rig.update(r)
        analysis.update(a)
    return block, rig, analysis


# ---------------------------------------------------------------- separation


def _owner(name: str) -> Any:
    return INERTIA if name == INERTIA.name else EFFECTS.get(name)


def separating_excitation(a: str, b: str) -> str:
    """The excitation that tells effect (or parameter owner) a from b apart."""
    ea, eb = _owner(a), _owner(b)
    for x, y in ((ea, b), (eb, a)):
        if x is not None and y in x.separated_from:
            return x.separated_from[y]
    if a == b and ea is not None:
        return getattr(ea, "internal_excitation", "") or ea.excitation
    hints = [e.excitation for e in (ea, eb) if e is not None and e.excitation]
    if hints:
        return "; ".join(dict.fromkeys(hints))
    return "a record that excites them differently"

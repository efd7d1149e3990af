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
  its look-alikes (identifiability warnings name it).

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
    "separating_excitation",
    "present_mesh_loss",
]

Changes = tuple[dict[str, Any], dict[str, Any]]
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


def build_changes(ctx: Any, effect: Effect, values: dict[str, float]) -> Changes:
    """Block and rig changes for effect + co-estimated parameter values."""
    block: dict[str, Any] = {}
    rig: dict[str, Any] = {}
    key = mk.driven_inertia_key(ctx.model)
    if key in values:
        rig[key] = float(values[key])
    for other in _present_others(ctx.model, effect):
        b, r = other.build(ctx, values)
        block.update(b)
        rig.update(r)
    b, r = effect.build(ctx, values)
    block.update(b)
    rig.update(r)
    return block, rig


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

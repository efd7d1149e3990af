"""The effects of docs/measurement-format.md section 3: what each one sets in
a model, which model parameters it fits, their bounds and first guesses, and
its residual signature (gearsim.analysis.signatures).

Each effect knows:

- ``present(model)``: whether the model already has it (then it is not a
  candidate);
- ``unavailable(model, ctx)``: why it cannot be offered (wrong rig, a
  combination the block cannot express), or None;
- ``signature(ctx)``: its regressor columns with the physical sign bounds of
  their coefficients;
- ``parameters(ctx, screen)``: the free parameters of the fit, seeded from the
  screening coefficients;
- ``build(ctx, values)``: the block and rig parameter changes for a set of
  values of those parameters.

Parameters already in the model that trade off against a new effect are
re-estimated with it (:func:`coestimated`): the driven inertia always, and the
viscous coefficient, Coulomb friction, load offset and constant efficiency
when the model has them. They share signature columns (a viscous term absorbs
part of a missing Coulomb friction, an inertia error part of a missing
efficiency), so fitting the new effect alone would leave them biased.
"""

from __future__ import annotations

from collections.abc import Callable
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
    "get_effect",
    "applicable_effects",
    "coestimated",
    "nuisance_columns",
]

_EFFICIENCY_MODELS = (
    "constant_efficiency",
    "load_dependent_efficiency",
    "temperature_dependent_efficiency",
    "temperature_load_dependent_efficiency",
)


@dataclass
class FitParam:
    """One free parameter of a fit.

    name: the program name it is reported under ("load_coulomb_friction",
    "efficiency_vector[1]", ...); x0: first guess; lower/upper: bounds;
    unit: SI unit for texts; role: "effect" (new) or "coestimated"."""

    name: str
    x0: float
    lower: float
    upper: float
    unit: str = ""
    role: str = "effect"
    before: float | None = None
    grid: tuple[float, ...] = ()  # multipliers of x0 tried before the local fit (non-smooth costs)
    optional: bool = False  # left at x0 in quick fits (diagnose)

    def clipped_x0(self) -> float:
        span = self.upper - self.lower
        eps = 1e-6 * (span if np.isfinite(span) else max(abs(self.x0), 1.0))
        lo = self.lower + eps if np.isfinite(self.lower) else -np.inf
        hi = self.upper - eps if np.isfinite(self.upper) else np.inf
        return float(min(max(self.x0, lo), hi))


Changes = tuple[dict[str, Any], dict[str, Any]]


@dataclass
class Effect:
    name: str
    blocks: tuple[str, ...]
    summary: str
    signature_text: str
    present: Callable[[Any], bool]
    columns: Callable[[Any], list[tuple[str, np.ndarray, tuple[float, float]]]]
    parameters: Callable[[Any, Any], list[FitParam]]
    build: Callable[[Any, dict[str, float]], Changes]
    report: Callable[[Any], dict[str, Any]]
    unavailable: Callable[[Any], str | None] = lambda model: None
    n_params: int = 1


def _rig_key_unit(model: Any) -> tuple[str, str]:
    return ("N*m", "N*m/(rad/s)") if mk.block_name(model) == "simple_gear" else ("N", "N/(m/s)")


# ---------------------------------------------------------------- helpers


def _visc_key(model: Any) -> str:
    return (
        "viscous_coefficients[1]"
        if mk.block_name(model) == "simple_gear"
        else "rack_viscous_coefficient"
    )


def _set_viscous(model: Any, value: float, block: dict) -> None:
    if mk.block_name(model) == "simple_gear":
        vc = list(mk.block_values(model)["viscous_coefficients"])
        vc[1] = float(value)
        block["viscous_coefficients"] = vc
    else:
        block["rack_viscous_coefficient"] = float(value)


def _bound_delta(current: float, lower: float, upper: float) -> tuple[float, float]:
    return (lower - current, upper - current)


def _seed(screen: Any, name: str, default: float = 0.0) -> float:
    if screen is None or name not in screen.names:
        return default
    return screen.coefficient(name)


def _robust(x: np.ndarray, q: float = 99.0) -> float:
    return float(np.percentile(np.abs(x), q)) if x.size else 0.0


def _force_scale(ctx: Any) -> float:
    """A typical driven-side force: robust max of the transmitted torque."""
    return max(_robust(ctx.T), _robust(ctx.meas[ctx.torque_output] / ctx.kin), 1e-9)


def _speed_scale(ctx: Any) -> float:
    return max(_robust(ctx.v), 1e-9)


# ---------------------------------------------------------------- effects


def _has_visc(model: Any) -> bool:
    return mk.viscous_value(model) > 0.0 or mk.base_viscous_value(model) > 0.0


def _visc_columns(ctx: Any):
    cur = mk.viscous_value(ctx.model)
    return [("speed", ctx.columns["speed"], _bound_delta(cur, 0.0, np.inf))]


def _visc_params(ctx: Any, screen: Any) -> list[FitParam]:
    cur = mk.viscous_value(ctx.model)
    x0 = max(cur + _seed(screen, "speed"), 0.0)
    hi = 20.0 * _force_scale(ctx) / _speed_scale(ctx)
    return [
        FitParam(
            _visc_key(ctx.model), x0, 0.0, max(hi, 10 * x0), _rig_key_unit(ctx.model)[1], before=cur
        )
    ]


def _visc_build(ctx: Any, values: dict[str, float]) -> Changes:
    block: dict[str, Any] = {}
    _set_viscous(ctx.model, values[_visc_key(ctx.model)], block)
    return block, {}


def _visc_report(model: Any) -> dict[str, Any]:
    v = mk.block_values(model)
    if mk.block_name(model) == "simple_gear":
        return {"viscous_coefficients": list(v["viscous_coefficients"])}
    return {
        "rack_viscous_coefficient": v["rack_viscous_coefficient"],
        "pinion_viscous_coefficient": v["pinion_viscous_coefficient"],
    }


def _coul_columns(ctx: Any):
    cur = float(mk.rig_values(ctx.model)["load_coulomb_friction"])
    return [("sign", ctx.columns["sign"], _bound_delta(cur, 0.0, np.inf))]


def _coul_params(ctx: Any, screen: Any) -> list[FitParam]:
    cur = float(mk.rig_values(ctx.model)["load_coulomb_friction"])
    x0 = max(cur + _seed(screen, "sign"), 0.0)
    f = _force_scale(ctx)
    return [
        FitParam(
            "load_coulomb_friction",
            x0,
            0.0,
            max(5.0 * f, 10 * x0),
            _rig_key_unit(ctx.model)[0],
            before=cur,
        )
    ]


def _coul_build(ctx: Any, values: dict[str, float]) -> Changes:
    return {}, {"load_coulomb_friction": float(values["load_coulomb_friction"])}


def _offset_columns(ctx: Any):
    return [("constant", ctx.columns["constant"], (-np.inf, np.inf))]


def _offset_params(ctx: Any, screen: Any) -> list[FitParam]:
    cur = float(mk.rig_values(ctx.model)["load_offset"])
    x0 = cur + _seed(screen, "constant")
    f = _force_scale(ctx)
    lim = max(5.0 * f, 10 * abs(x0))
    return [FitParam("load_offset", x0, -lim, lim, _rig_key_unit(ctx.model)[0], before=cur)]


def _offset_build(ctx: Any, values: dict[str, float]) -> Changes:
    return {}, {"load_offset": float(values["load_offset"])}


def present_mesh_loss(model: Any) -> float:
    """Present constant meshing loss 1 - eta (0 without an efficiency model)."""
    if mk.friction_model(model) == "constant_efficiency":
        return 1.0 - float(mk.block_values(model)["efficiency_const"])
    return 0.0


def _has_eff(model: Any) -> bool:
    return mk.friction_model(model) in _EFFICIENCY_MODELS


def _eff_columns(ctx: Any):
    return [("mesh", ctx.columns["mesh"], (0.0, 0.7))]


def _eff_from_loss(L: float) -> float:
    # the screening coefficient L mixes 1-eta (overrunning) and 1/eta-1
    # (driving); their mean is ~ (1-eta)(1+1/eta)/2, close to 1-eta
    return float(min(max(1.0 - L, 0.3), 1.0))


def _eff_params(ctx: Any, screen: Any) -> list[FitParam]:
    x0 = _eff_from_loss(_seed(screen, "mesh", 0.02))
    return [FitParam("efficiency_const", min(x0, 0.999), 0.3, 1.0, "")]


def _eff_build(ctx: Any, values: dict[str, float]) -> Changes:
    return {
        "friction_model": "constant_efficiency",
        "efficiency_const": float(values["efficiency_const"]),
    }, {}


def _eff_report(model: Any) -> dict[str, Any]:
    v = mk.block_values(model)
    return {"efficiency_const": v["efficiency_const"]}


# load-dependent efficiency (Simple Gear): tau_mesh = (g*tau_idle + k*|T|)*sgn(w)


def _ld_unavailable(model: Any) -> str | None:
    if mk.block_name(model) != "simple_gear":
        return "the rack and pinion has no load-dependent efficiency model"
    if mk.friction_model(model) in (
        "temperature_dependent_efficiency",
        "temperature_load_dependent_efficiency",
    ):
        return (
            "the model has a temperature-dependent efficiency; combining it with a load dependence "
            "needs the 2-D efficiency_matrix, which is not fitted automatically"
        )
    return None


def _ld_present(model: Any) -> bool:
    return mk.friction_model(model) in (
        "load_dependent_efficiency",
        "temperature_load_dependent_efficiency",
    )


def _ld_columns(ctx: Any):
    L0 = present_mesh_loss(ctx.model)
    return [
        ("idle", ctx.columns["idle"], (0.0, np.inf)),
        ("mesh", ctx.columns["mesh"], (-L0, 0.7 - L0)),
    ]


def _ld_params(ctx: Any, screen: Any) -> list[FitParam]:
    g = float(mk.block_values(ctx.model)["teeth_ratio"])
    idle_f = max(_seed(screen, "idle", 0.0), 0.0)  # follower-referred g*tau_idle
    k = max(present_mesh_loss(ctx.model) + _seed(screen, "mesh", 0.02), 0.0)
    f = _force_scale(ctx)
    return [
        FitParam("idle_torque", idle_f / g, 0.0, max(2.0 * f / g, 10 * idle_f / g), "N*m"),
        FitParam("load_slope", k, 0.0, 2.0, ""),
    ]


def _ld_build(ctx: Any, values: dict[str, float]) -> Changes:
    g = float(mk.block_values(ctx.model)["teeth_ratio"])
    tnom = ctx.nominal_torque
    idle = float(values["idle_torque"])
    k = float(values["load_slope"])
    # eq. 2.5: k = 1/eta_nom - 1 - g*tau_idle/tau_nom  =>  eta_nom; keep k >= 0
    # and eta_nom < 1 strictly against rounding
    eta = 1.0 / (1.0 + k + g * idle / tnom + 1e-12)
    eta = min(eta, 1.0 - 1e-9)
    return {
        "friction_model": "load_dependent_efficiency",
        "idle_torque": idle,
        "nominal_output_torque": tnom,
        "efficiency_nominal": eta,
    }, {}


def _ld_report(model: Any) -> dict[str, Any]:
    v = mk.block_values(model)
    return {
        "idle_torque": v["idle_torque"],
        "nominal_output_torque": v["nominal_output_torque"],
        "efficiency_nominal": v["efficiency_nominal"],
    }


# temperature-dependent efficiency


def _td_present(model: Any) -> bool:
    return mk.friction_model(model) in (
        "temperature_dependent_efficiency",
        "temperature_load_dependent_efficiency",
    )


def _td_unavailable(model: Any) -> str | None:
    if mk.friction_model(model) in ("load_dependent_efficiency",):
        return (
            "the model has a load-dependent efficiency; combining it with a temperature dependence "
            "needs the 2-D efficiency_matrix, which is not fitted automatically"
        )
    return None


def _td_breakpoints(ctx: Any) -> np.ndarray:
    from .signatures import temperature_breakpoints

    return temperature_breakpoints(ctx.temperature)


def _td_columns(ctx: Any):
    from .signatures import temperature_hats

    bp = _td_breakpoints(ctx)
    if float(np.ptp(ctx.temperature)) < 2.0:
        return []
    hats = temperature_hats(ctx.temperature, bp)
    mesh = ctx.columns["mesh"]
    L0 = present_mesh_loss(ctx.model)
    return [(f"mesh@{t:.1f}K", mesh * hats[:, i], (-L0, 0.7 - L0)) for i, t in enumerate(bp)]


def _td_params(ctx: Any, screen: Any) -> list[FitParam]:
    bp = _td_breakpoints(ctx)
    L0 = present_mesh_loss(ctx.model)
    out = []
    for i, t in enumerate(bp):
        # screening coefficients are changes of the present loss 1 - eta
        dL = _seed(screen, f"mesh@{t:.1f}K", 0.02 if L0 == 0 else 0.0)
        eta = _eff_from_loss(L0 + dL)
        out.append(FitParam(f"efficiency_vector[{i}]", min(eta, 0.999), 0.3, 1.0, ""))
    return out


def _td_build(ctx: Any, values: dict[str, float]) -> Changes:
    bp = _td_breakpoints(ctx)
    eff = [float(values[f"efficiency_vector[{i}]"]) for i in range(bp.size)]
    return {
        "friction_model": "temperature_dependent_efficiency",
        "temperature_vector": [float(x) for x in bp],
        "efficiency_vector": eff,
    }, {}


def _td_report(model: Any) -> dict[str, Any]:
    v = mk.block_values(model)
    return {
        "temperature_vector": list(v["temperature_vector"]),
        "efficiency_vector": list(v["efficiency_vector"]),
    }


# backlash


def _bl_present(model: Any) -> bool:
    return bool(mk.block_values(model).get("backlash_enabled", False))


def _bl_params(ctx: Any, screen: Any) -> list[FitParam]:
    gap = getattr(screen, "gap_estimate", None) if screen is not None else None
    if not gap or not np.isfinite(gap) or gap <= 0:
        gap = 1e-3
    v = mk.block_values(ctx.model)
    k0 = float(v["stiffness"])
    d0 = float(v["damping"])
    return [
        FitParam(
            "linear_backlash",
            float(gap),
            1e-7,
            max(100.0 * gap, 0.05),
            "m",
            grid=(0.3, 0.5, 0.7, 1.0, 1.4, 2.0, 3.0),
        ),
        FitParam(
            "stiffness", k0, 1e-3 * k0, 1e3 * k0, "N/m", grid=(0.1, 0.3, 1.0, 3.0), optional=True
        ),
        FitParam(
            "damping", d0, 0.0, 1e3 * max(d0, 1.0), "N*s/m", grid=(0.3, 1.0, 3.0), optional=True
        ),
    ]


def _bl_build(ctx: Any, values: dict[str, float]) -> Changes:
    b = float(values["linear_backlash"])
    v = mk.block_values(ctx.model)
    block = {"backlash_enabled": True, "linear_backlash": b}
    for key in ("stiffness", "damping"):
        if key in values:
            block[key] = float(values[key])
    d = float(v.get("transition_region", 1e-4))
    if v.get("hard_stop_model", "smooth") == "smooth" and d >= 0.25 * b:
        block["transition_region"] = 0.25 * b
    return block, {}


def _bl_report(model: Any) -> dict[str, Any]:
    v = mk.block_values(model)
    out = {
        "linear_backlash": v["linear_backlash"],
        "stiffness": v["stiffness"],
        "damping": v["damping"],
    }
    if mk.block_name(model) == "simple_gear":
        out["base_radius"] = v["base_radius"]
    return out


EFFECTS: dict[str, Effect] = {
    "meshing_efficiency": Effect(
        "meshing_efficiency",
        ("simple_gear", "rack_pinion"),
        "constant meshing efficiency (friction_model = constant_efficiency)",
        "residual proportional to |transmitted torque| with the sign of the speed: the "
        "drive needs more "
        "torque while it drives the load and less while the load overruns",
        _has_eff,
        _eff_columns,
        _eff_params,
        _eff_build,
        _eff_report,
    ),
    "load_dependent_efficiency": Effect(
        "load_dependent_efficiency",
        ("simple_gear",),
        "load-dependent efficiency: idle torque plus a loss proportional to load",
        "a Coulomb-like part at no load plus a part growing with |transmitted torque|: the "
        "efficiency "
        "falls at low load",
        _ld_present,
        _ld_columns,
        _ld_params,
        _ld_build,
        _ld_report,
        _ld_unavailable,
        n_params=2,
    ),
    "temperature_dependent_efficiency": Effect(
        "temperature_dependent_efficiency",
        ("simple_gear", "rack_pinion"),
        "efficiency interpolated over temperature (friction_model = "
        "temperature_dependent_efficiency)",
        "the torque-proportional meshing loss changes with temperature",
        _td_present,
        _td_columns,
        _td_params,
        _td_build,
        _td_report,
        _td_unavailable,
        n_params=3,
    ),
    "viscous_friction": Effect(
        "viscous_friction",
        ("simple_gear", "rack_pinion"),
        "viscous friction on the driven side",
        "residual proportional to the speed",
        _has_visc,
        _visc_columns,
        _visc_params,
        _visc_build,
        _visc_report,
    ),
    "backlash": Effect(
        "backlash",
        ("simple_gear", "rack_pinion"),
        "backlash with its gap (stiffness and damping kept)",
        "residual concentrated right after reversals of the transmitted torque, with a "
        "driven-speed "
        "residual whose integral is the gap",
        _bl_present,
        lambda ctx: [],
        _bl_params,
        _bl_build,
        _bl_report,
    ),
    "coulomb_friction": Effect(
        "coulomb_friction",
        ("simple_gear", "rack_pinion"),
        "Coulomb friction on the driven side (rig load_coulomb_friction)",
        "residual follows the sign of the speed: a constant-magnitude step at each "
        "direction reversal",
        lambda m: float(mk.rig_values(m)["load_coulomb_friction"]) > 0.0,
        _coul_columns,
        _coul_params,
        _coul_build,
        lambda m: {"load_coulomb_friction": mk.rig_values(m)["load_coulomb_friction"]},
    ),
    "load_offset": Effect(
        "load_offset",
        ("simple_gear", "rack_pinion"),
        "constant load offset on the driven side (rig load_offset)",
        "constant bias of the residual in every regime",
        lambda m: float(mk.rig_values(m)["load_offset"]) != 0.0,
        _offset_columns,
        _offset_params,
        _offset_build,
        lambda m: {"load_offset": mk.rig_values(m)["load_offset"]},
    ),
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
    blk = mk.block_name(model)
    out, skipped = [], {}
    for name, eff in EFFECTS.items():
        if blk not in eff.blocks:
            skipped[name] = f"does not apply to the {blk} rig"
        elif eff.present(model):
            skipped[name] = "already in the model"
        elif why := eff.unavailable(model):
            skipped[name] = str(why)
        else:
            out.append(eff)
    return out, skipped


# ---------------------------------------------------------------- co-estimation


def coestimated(ctx: Any, effect: Effect, screen: Any = None) -> list[FitParam]:
    """Existing parameters re-estimated together with effect (see module doc)."""
    model = ctx.model
    out: list[FitParam] = []
    if effect.name == "backlash":
        return out
    key = mk.driven_inertia_key(model)
    j0 = float(mk.rig_values(model)[key])
    j = j0 + _seed(screen, "acceleration", 0.0)
    j = j if j > 0 else j0
    unit = "kg*m^2" if key == "follower_inertia" else "kg"
    out.append(FitParam(key, j, j0 * 1e-3, j0 * 1e3, unit, role="coestimated", before=j0))
    if _has_visc(model) and effect.name != "viscous_friction":
        p = _visc_params(ctx, screen)[0]
        p.role = "coestimated"
        out.append(p)
    if (
        float(mk.rig_values(model)["load_coulomb_friction"]) > 0
        and effect.name != "coulomb_friction"
    ):
        p = _coul_params(ctx, screen)[0]
        p.role = "coestimated"
        out.append(p)
    if float(mk.rig_values(model)["load_offset"]) != 0 and effect.name != "load_offset":
        p = _offset_params(ctx, screen)[0]
        p.role = "coestimated"
        out.append(p)
    if mk.friction_model(model) == "constant_efficiency" and effect.name not in (
        "meshing_efficiency",
        "load_dependent_efficiency",
        "temperature_dependent_efficiency",
    ):
        cur = float(mk.block_values(model)["efficiency_const"])
        L = (1.0 - cur) + _seed(screen, "mesh", 0.0)
        out.append(
            FitParam(
                "efficiency_const",
                min(_eff_from_loss(L), 0.999),
                0.3,
                1.0,
                "",
                role="coestimated",
                before=cur,
            )
        )
    return out


def nuisance_columns(
    ctx: Any, effect: Effect | None
) -> list[tuple[str, np.ndarray, tuple[float, float]]]:
    """Signature columns of the co-estimated parameters (screening)."""
    model = ctx.model
    key = mk.driven_inertia_key(model)
    j0 = float(mk.rig_values(model)[key])
    cols = [("acceleration", ctx.columns["acceleration"], (-0.999 * j0, 1e3 * j0))]
    name = effect.name if effect is not None else ""
    if name == "backlash":
        return cols
    if _has_visc(model) and name != "viscous_friction":
        cols += _visc_columns(ctx)
    if float(mk.rig_values(model)["load_coulomb_friction"]) > 0 and name != "coulomb_friction":
        cols += _coul_columns(ctx)
    if float(mk.rig_values(model)["load_offset"]) != 0 and name != "load_offset":
        cols += _offset_columns(ctx)
    if mk.friction_model(model) == "constant_efficiency" and name not in (
        "load_dependent_efficiency",
        "temperature_dependent_efficiency",
    ):
        cur = float(mk.block_values(model)["efficiency_const"])
        cols.append(("mesh", ctx.columns["mesh"], (-(1.0 - cur), 0.7 - (1.0 - cur))))
    return cols


def build_changes(ctx: Any, effect: Effect, values: dict[str, float]) -> Changes:
    """Block and rig changes for effect + co-estimated parameter values."""
    block, rig = effect.build(ctx, values)
    block = dict(block)
    rig = dict(rig)
    model = ctx.model
    key = mk.driven_inertia_key(model)
    if key in values:
        rig[key] = float(values[key])
    vk = _visc_key(model)
    if vk in values and effect.name != "viscous_friction":
        _set_viscous(model, values[vk], block)
    if "load_coulomb_friction" in values:
        rig["load_coulomb_friction"] = float(values["load_coulomb_friction"])
    if "load_offset" in values:
        rig["load_offset"] = float(values["load_offset"])
    if "efficiency_const" in values and effect.name != "meshing_efficiency":
        block["efficiency_const"] = float(values["efficiency_const"])
    return block, rig

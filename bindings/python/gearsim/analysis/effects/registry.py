"""The registry of effects (EFFECTS, in the order they are offered) and what
the engine does with all of them at once: which apply to a model, which
parameters are re-estimated together, how a fit's values become model
changes, and what excitation separates two of them."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .. import modelkit as mk
from ..errors import EffectError
from .backlash import Backlash
from .base import INERTIA, Column, Effect, FitParam, Screening
from .compliance import Compliance
from .coulomb_friction import CoulombFriction
from .load_dependent_efficiency import LoadDependentEfficiency
from .load_offset import LoadOffset
from .meshing_efficiency import MeshingEfficiency
from .sensor_delay import SensorDelay
from .stribeck_friction import StribeckFriction
from .temperature_dependent_efficiency import TemperatureDependentEfficiency
from .torque_ripple import TorqueRipple
from .viscous_friction import ViscousFriction

__all__ = [
    "EFFECTS",
    "EFFECT_NAMES",
    "get_effect",
    "applicable_effects",
    "coestimated",
    "nuisance_columns",
    "three_changes",
    "apply_changes",
    "build_changes",
    "separating_excitation",
]

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


def present_effects(model: Any) -> list[Effect]:
    """The effects the model has, in registry order."""
    return [e for e in EFFECTS.values() if e.present(model)]


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


def coestimated(
    ctx: Any, effect: Effect | None, screening: Screening | None = None
) -> list[FitParam]:
    """Existing parameters re-estimated together with effect: the driven
    inertia and the present parameters of the effects the model has (effect
    None: every present one, a joint re-fit)."""
    out = [INERTIA.parameter(ctx, screening)]
    for other in _present_others(ctx.model, effect):
        out += other.coestimated(ctx, screening)
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
    ctx: Any, effect: Effect | None, values: Mapping[str, float]
) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Block, rig and [analysis] changes for effect + co-estimated parameter
    values (effect None: the present effects alone)."""
    block: dict[str, Any] = {}
    rig: dict[str, Any] = {}
    analysis: dict[str, Any] = {}
    key = mk.driven_inertia_key(ctx.model)
    if key in values:
        rig[key] = float(values[key])
    builders = _present_others(ctx.model, effect) + ([effect] if effect is not None else [])
    for builder in builders:
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

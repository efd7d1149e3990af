"""The analysis layer's only contact with :class:`gearsim.Model`.

Reading parameter values (given or default), building a changed copy of a
model, and the rig kinematics the residual signatures need. Everything else in
the analysis calls these helpers, so an API change of the bindings is absorbed
here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = [
    "block_name",
    "block_values",
    "rig_values",
    "changed",
    "kinematic_ratio",
    "driven_radius",
    "friction_model",
    "driven_inertia_key",
    "viscous_value",
]


def block_name(model: Any) -> str:
    """ "simple_gear" or "rack_pinion"."""
    return model.block


def block_values(model: Any) -> dict[str, Any]:
    """Every block parameter in use (given, else the default), SI units."""
    return dict(model.resolved_block_params)


def rig_values(model: Any) -> dict[str, Any]:
    """Every rig parameter in use (given, else the default), SI units."""
    return dict(model.resolved_rig_params)


def changed(
    model: Any, block: Mapping[str, Any] | None = None, rig: Mapping[str, Any] | None = None
) -> Any:
    """A new Model with some block and rig parameters changed (validated by
    the C core: an invalid value raises gearsim.ParameterError)."""
    return model.replace(block_params=dict(block or {}), rig_params=dict(rig or {}))


def friction_model(model: Any) -> str:
    return str(block_values(model).get("friction_model", "none"))


def driven_inertia_key(model: Any) -> str:
    return "follower_inertia" if block_name(model) == "simple_gear" else "rack_mass"


def pinion_radius(values: Mapping[str, Any]) -> float:
    if values.get("parameterization", "pinion_radius") == "tooth_parameters":
        return float(values["teeth_count"]) * float(values["spacing"]) / (2.0 * math.pi)
    return float(values["pinion_radius"])


def kinematic_ratio(model: Any) -> float:
    """driven speed / base speed of the rigid mesh (signed): s/g for the gear
    (rad/s per rad/s), s_R*r_P for the rack (m/s per rad/s)."""
    v = block_values(model)
    if block_name(model) == "simple_gear":
        s = 1.0 if v.get("output_shaft_rotates", "opposite") == "same" else -1.0
        return s / float(v["teeth_ratio"])
    s = 1.0 if v.get("rack_directionality", "positive") == "positive" else -1.0
    return s * pinion_radius(v)


def driven_radius(model: Any) -> float:
    """Metres of pitch-line travel per unit of driven position: r_F = g*r_B for
    the gear (m/rad), 1 for the rack (m/m). Converts a driven displacement
    into backlash gap units."""
    v = block_values(model)
    if block_name(model) == "simple_gear":
        return float(v["teeth_ratio"]) * float(v["base_radius"])
    return 1.0


def viscous_value(model: Any) -> float:
    """Driven-side viscous coefficient (follower mu_F, or rack mu_R)."""
    v = block_values(model)
    if block_name(model) == "simple_gear":
        return float(v["viscous_coefficients"][1])
    return float(v["rack_viscous_coefficient"])


def base_viscous_value(model: Any) -> float:
    v = block_values(model)
    if block_name(model) == "simple_gear":
        return float(v["viscous_coefficients"][0])
    return float(v["pinion_viscous_coefficient"])

"""The analysis layer's only contact with :class:`gearsim.Model`.

Reading parameter values (given or default), building a changed copy of a
model, and the rig kinematics the residual signatures need. Everything else in
the analysis calls these helpers, so an API change of the bindings is absorbed
here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from os import PathLike
from typing import Any

from ..model import Model

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
    "AnalysisModel",
    "ANALYSIS_KEYS",
    "load_model",
    "torque_delay",
]

#: Keys of the model file's [analysis] table: what the analysis applies to
#: the simulated outputs before comparing them (no C rig parameter).
#: torque_delay: s, how much the measured torque lags the speed channels.
ANALYSIS_KEYS = {"torque_delay": "s"}
#: A delay longer than this (s) is refused: a logger lag is milliseconds, a
#: second would be a misread unit.
MAX_TORQUE_DELAY = 1.0


def _analysis_value(key: str, value: Any) -> float:
    """An [analysis] value in SI: a number, or a unit string read with pint."""
    from ..errors import ModelFileError
    from ..units import UnitConversionError, to_si

    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ModelFileError(f"[analysis] {key} must be a number or a unit string", parameter=key)
    try:
        si = to_si(value, ANALYSIS_KEYS[key]) if isinstance(value, str) else value
    except (UnitConversionError, TypeError) as exc:
        raise ModelFileError(f"[analysis] {key}: {exc}", parameter=key) from None
    if isinstance(si, list):  # "[1, 2] s": a list, as a TOML array above
        raise ModelFileError(f"[analysis] {key} must be a number or a unit string", parameter=key)
    x = float(si)
    if not (math.isfinite(x) and abs(x) <= MAX_TORQUE_DELAY):
        raise ModelFileError(
            f"[analysis] {key} = {x:g} s is outside [-{MAX_TORQUE_DELAY:g}, "
            f"{MAX_TORQUE_DELAY:g}] s",
            parameter=key,
        )
    return x


class AnalysisModel(Model):
    """A Model plus the analysis-only settings of the model file's
    ``[analysis]`` table (:data:`ANALYSIS_KEYS`), e.g. ``torque_delay = "6 ms"``.
    They change how the simulated outputs are compared, not the C rig:
    gearsim.Model reads, carries and writes the table as it is; this class
    validates it into SI values. Everything else is the Model's."""

    def __init__(
        self,
        block: str = "simple_gear",
        block_params: Mapping[str, Any] | None = None,
        rig_params: Mapping[str, Any] | None = None,
        *,
        file: str | PathLike[str] | None = None,
        analysis: Mapping[str, Any] | None = None,
    ) -> None:
        super().__init__(block, block_params, rig_params, file=file)
        from ..errors import GearsimError, ModelFileError, with_file

        self.analysis: dict[str, float] = {}
        try:
            if analysis is not None and not isinstance(analysis, Mapping):
                raise ModelFileError("analysis must be a table ([analysis])", parameter="analysis")
            for key, value in (analysis or {}).items():
                if key not in ANALYSIS_KEYS:
                    raise ModelFileError(
                        f"unknown [analysis] key {key!r}; known: {', '.join(ANALYSIS_KEYS)}",
                        parameter=str(key),
                    )
                x = _analysis_value(key, value)
                if x != 0.0:
                    self.analysis[key] = x
        except GearsimError as exc:
            if file is None:
                raise
            raise with_file(exc, file) from None

    @classmethod
    def of(cls, model: Any, analysis: Mapping[str, Any] | None = None) -> AnalysisModel:
        """model (a Model or an AnalysisModel) with its [analysis] settings
        updated by `analysis` (a value of 0 or None removes the key)."""
        merged = dict(getattr(model, "analysis", {}))
        for key, value in (analysis or {}).items():
            if value is None:
                merged.pop(key, None)
            else:
                merged[key] = value
        return cls(model.block, model.block_params, model.rig_params, analysis=merged)

    def replace(self, *, block_params=None, rig_params=None) -> AnalysisModel:
        new = super().replace(block_params=block_params, rig_params=rig_params)
        return AnalysisModel.of(new, self.analysis)

    def _key(self) -> Any:
        return (super()._key(), tuple(sorted(self.analysis.items())))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Model):
            return NotImplemented
        return self._key() == AnalysisModel.of(other)._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return f"{super().__repr__()[:-1]}, analysis={self.analysis!r})"


def load_model(path: str | PathLike[str]) -> AnalysisModel:
    """Read a model file with its optional [analysis] table validated (exit-2
    errors name the file and key, like Model.load, which does the reading:
    its from_dict hands the table to AnalysisModel)."""
    return AnalysisModel.load(path)


def torque_delay(model: Any) -> float:
    """The delay (s) of the measured torque relative to the speed channels
    that the model says to apply to its simulated torque (0: none)."""
    return float(getattr(model, "analysis", {}).get("torque_delay", 0.0))


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
    model: Any,
    block: Mapping[str, Any] | None = None,
    rig: Mapping[str, Any] | None = None,
    analysis: Mapping[str, Any] | None = None,
) -> Any:
    """A new model with some block, rig and [analysis] parameters changed
    (block and rig validated by the C core: an invalid value raises
    gearsim.ParameterError). Always an AnalysisModel, so that what the
    analysis sets survives every later change."""
    new = model.replace(block_params=dict(block or {}), rig_params=dict(rig or {}))
    if analysis or not isinstance(new, AnalysisModel):
        new = AnalysisModel.of(new, analysis)
    return new


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

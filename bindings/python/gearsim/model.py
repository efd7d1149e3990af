"""Model: a block, its parameters and the rig parameters; read from and written
to the TOML model files of docs/measurement-format.md section 2.

```toml
[rig]
block = "simple_gear"          # or "rack_pinion"
follower_inertia = 0.05        # kg*m^2 (rack rig: rack_mass, kg)
...
[block]
teeth_ratio = 3.0
friction_model = "constant_efficiency"
```

Plain numbers are SI; unit strings ("100 mm", "3000 rpm", "80 degC") are
converted by pint to the parameter's SI unit (gearsim.params). A missing
parameter takes its default. An unknown key or a value of the wrong type raises
ModelFileError, an invalid value ParameterError (also a ModelFileError when read
from a file); both carry .file and .parameter.

An optional ``[analysis]`` table (``torque_delay = "6 ms"``, written by
``gearsim fit --add sensor_delay``) says how the analysis compares simulated and
measured outputs. Model keeps it (``Model.analysis``) and writes it back, so a
fitted model file loads everywhere; gearsim.analysis.load_model validates it.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any, Self

import tomli_w

from . import params as P
from .blocks import Block, make_block
from .errors import GearsimError, ModelFileError, with_file
from .rig import GearRig, RackRig, Rig

__all__ = ["Model"]

_TOP_KEYS = ("rig", "block", "analysis")


class Model:
    """A gear or rack model: block name, block parameters, rig parameters.

    Args:
        block: "simple_gear" or "rack_pinion".
        block_params: block parameters (docs/physics.md section 9 names).
        rig_params: rig parameters (follower_inertia or rack_mass,
            load_coulomb_friction, load_offset, thermal_resistance,
            ambient_temperature, base_inertia, load_coulomb_speed_threshold,
            accel_filter_time_constant, contact_substeps, base_drive,
            initial_base_speed).
        file: where the model was read from (for error messages), if anywhere.

    Values are normalised to SI at construction and validated by the C core.
    ``block_params`` and ``rig_params`` keep only the parameters given; the
    others take their defaults (``resolved_block_params``,
    ``resolved_rig_params``). Two models are equal when their resolved
    parameters are.
    """

    def __init__(
        self,
        block: str = "simple_gear",
        block_params: Mapping[str, Any] | None = None,
        rig_params: Mapping[str, Any] | None = None,
        *,
        file: str | PathLike[str] | None = None,
        analysis: Mapping[str, Any] | None = None,
    ) -> None:
        self.file: Path | None = None if file is None else Path(file)
        # The optional [analysis] table (e.g. torque_delay): settings of how
        # gearsim.analysis compares simulated with measured outputs, not rig
        # parameters. Carried through replace/to_dict unread; gearsim.analysis
        # (load_model) validates it.
        self.analysis: dict[str, Any] = dict(analysis or {})
        try:
            self._init(block, block_params, rig_params)
        except GearsimError as exc:
            if file is None:
                raise
            raise with_file(exc, file) from exc.__cause__

    def _init(
        self,
        block: str,
        block_params: Mapping[str, Any] | None,
        rig_params: Mapping[str, Any] | None,
    ) -> None:
        if not isinstance(block, str) or block not in P.BLOCKS:
            raise ModelFileError(
                f"unknown block {block!r}; expected 'simple_gear' or 'rack_pinion'",
                parameter="block",
            )
        rig_params = dict(rig_params or {})
        rig_block = rig_params.pop("block", block)
        if rig_block != block:
            raise ModelFileError(
                f"rig block {rig_block!r} differs from block {block!r}", parameter="block"
            )
        block_obj = make_block(block, block_params)
        rig_specs = {p.name: p for p in P.BLOCKS[block][1]}
        given_rig = P.normalize_all(rig_specs, rig_params, f"{block} rig")
        # Validate the rig parameters in the C core (the dt here is irrelevant).
        Rig(block_obj, **given_rig)
        self.block: str = block
        self._block_obj = block_obj
        self._rig_params = given_rig

    # -- parameters ----------------------------------------------------------------
    @property
    def block_params(self) -> dict[str, Any]:
        """The block parameters given (SI)."""
        return self._block_obj.given_params

    @property
    def rig_params(self) -> dict[str, Any]:
        """The rig parameters given (SI), without "block"."""
        return dict(self._rig_params)

    @property
    def resolved_block_params(self) -> dict[str, Any]:
        """Every block parameter, given or default (SI)."""
        return self._block_obj.params

    @property
    def resolved_rig_params(self) -> dict[str, Any]:
        """Every rig parameter, given or default (SI); thermal_resistance None = adiabatic."""
        return {**P.rig_defaults(self.block), **self._rig_params}

    def make_block(self) -> Block:
        """The block (a SimpleGear or RackPinion) with these parameters."""
        return make_block(self.block, self.block_params)

    def replace(
        self,
        *,
        block_params: Mapping[str, Any] | None = None,
        rig_params: Mapping[str, Any] | None = None,
    ) -> Model:
        """A new model with parameters changed (merged into the given ones); a
        value of None removes the parameter (back to its default)."""
        new_block = {**self.block_params, **(block_params or {})}
        new_rig = {**self._rig_params, **(rig_params or {})}
        return Model(
            self.block,
            {k: v for k, v in new_block.items() if v is not None},
            {k: v for k, v in new_rig.items() if v is not None},
            analysis=self.analysis,
        )

    # -- simulation -------------------------------------------------------------------
    def rig(
        self, dt: float | str = 1e-3, temperature_input: bool = False, **rig_overrides: Any
    ) -> Rig:
        """A GearRig or RackRig (C rig inside) with step dt (s); rig_overrides
        replace rig parameters for this rig only (e.g. base_drive="torque")."""
        params = {**self._rig_params, **rig_overrides}
        cls = GearRig if self.block == "simple_gear" else RackRig
        rig = cls(self.make_block(), dt=dt, temperature_input=temperature_input, **params)
        rig.model = self
        return rig

    # -- dict / TOML ---------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """{"rig": {"block": ..., **rig_params}, "block": {**block_params}} (SI)."""
        rig = {"block": self.block}
        rig.update({k: v for k, v in self._rig_params.items() if v is not None})
        out = {"rig": rig, "block": self.block_params}
        if self.analysis:
            out["analysis"] = dict(self.analysis)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], file: str | PathLike[str] | None = None) -> Self:
        """A model from the parsed TOML structure ({"rig": {...}, "block": {...}})."""
        try:
            if not isinstance(data, Mapping):
                raise ModelFileError("a model is a table with [rig] and [block]")
            for key in data:
                if key not in _TOP_KEYS:
                    raise ModelFileError(
                        f"unknown table {key!r}; expected [rig], [block] and optionally [analysis]",
                        parameter=str(key),
                    )
            rig = data.get("rig", {})
            block_params = data.get("block", {})
            analysis = data.get("analysis", {})
            for name, table in (("rig", rig), ("block", block_params), ("analysis", analysis)):
                if not isinstance(table, Mapping):
                    raise ModelFileError(f"{name} must be a table ([{name}])", parameter=name)
            if "block" not in rig:
                raise ModelFileError(
                    '[rig] needs block = "simple_gear" or "rack_pinion"', parameter="block"
                )
            block = rig["block"]
            rig_params = {k: v for k, v in rig.items() if k != "block"}
        except GearsimError as exc:
            raise with_file(exc, file) from None
        return cls(block, block_params, rig_params, file=file, analysis=analysis)

    @classmethod
    def loads(cls, text: str, file: str | PathLike[str] | None = None) -> Self:
        """A model from TOML text."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ModelFileError(f"TOML syntax: {exc}", file=file) from None
        return cls.from_dict(data, file=file)

    @classmethod
    def load(cls, path: str | PathLike[str]) -> Self:
        """Read a TOML model file."""
        try:
            text = Path(path).read_bytes().decode("utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ModelFileError(f"cannot read the model file: {exc}", file=path) from None
        return cls.loads(text, file=path)

    def dumps(self) -> str:
        """TOML text of the model (SI numbers); Model.loads() gives an equal model."""
        return tomli_w.dumps(self.to_dict())

    def save(self, path: str | PathLike[str]) -> None:
        """Write the model as TOML; Model.load(path) gives an equal model."""
        Path(path).write_text(self.dumps(), encoding="utf-8")

    # -- comparison ------------------------------------------------------------------
    def _key(self) -> Any:
        return (
            self.block,
            P.canonical(self.resolved_block_params),
            P.canonical(self.resolved_rig_params),
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Model):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return (
            f"Model(block={self.block!r}, block_params={self.block_params!r}, "
            f"rig_params={self.rig_params!r})"
        )

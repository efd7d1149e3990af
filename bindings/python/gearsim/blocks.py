"""The two blocks, SimpleGear and RackPinion: validated parameter sets around the
C blocks of include/gearsim/simple_gear.h and rack_pinion.h, each an opaque
constants block (``gs_simple_gear_consts`` / ``gs_rack_pinion_consts``, filled
once by init) and a ``gs_block_state`` (docs/physics.md sections 1-6, 9, 10).

Most users step a rig (gearsim.rig); the blocks also step on their own with the
block's causal forms (physics.md section 8): rigid mesh takes a speed and the
far-side torque/force, backlash takes both speeds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

from . import params as P
from ._lib import check, ffi, lib
from .errors import InputError, ModelFileError

__all__ = ["Block", "SimpleGear", "RackPinion", "make_block"]


class Block:
    """Common part of SimpleGear and RackPinion.

    Construct with keyword parameters (program names of docs/physics.md section
    9, SI numbers or unit strings); missing parameters take the C defaults. The
    C core validates them at construction: a bad value raises ParameterError
    naming the parameter, an unknown name or a wrong type ModelFileError.
    """

    kind: ClassVar[str] = ""
    _consts_ctype: ClassVar[str] = ""
    _specs: ClassVar[dict[str, P.Param]] = {}

    def __init__(self, **params: Any) -> None:
        given = P.normalize_all(self._specs, params, self.kind)
        full = {**self.defaults(), **given}
        P.check_table_shapes(self.kind, full)
        specs, _, ctype, default_fn = P.BLOCKS[self.kind]
        c_params = P.new_struct(ctype)
        c_params[0] = getattr(lib, default_fn)()
        P.write_struct(specs, full, c_params)
        consts = ffi.new(self._consts_ctype + " *")
        state = ffi.new("gs_block_state *")
        err = ffi.new("gs_error *")
        status = self._init(consts, state, c_params, err)
        check(status, err, value_of=full.__getitem__)
        self._given = given
        self._full = full
        self._c_params = c_params
        self._consts = consts  # read-only after init
        self._state = state

    # -- parameters ---------------------------------------------------------
    @classmethod
    def defaults(cls) -> dict[str, Any]:
        """Default of every parameter, read from the C core (SI units)."""
        return P.block_defaults(cls.kind)

    @classmethod
    def parameter_names(cls) -> tuple[str, ...]:
        return tuple(cls._specs)

    @classmethod
    def units(cls) -> dict[str, str]:
        """SI unit (pint syntax, "" = dimensionless) of each numeric parameter."""
        return P.units_of(cls._specs.values())

    @property
    def params(self) -> dict[str, Any]:
        """Every parameter value in use (given or default), SI units."""
        return _copy(self._full)

    @property
    def given_params(self) -> dict[str, Any]:
        """The parameters given at construction (normalised to SI)."""
        return _copy(self._given)

    def replace(self, **changes: Any) -> Block:
        """A new block with some parameters changed."""
        return type(self)(**{**self._given, **changes})

    def __getattr__(self, name: str) -> Any:
        full = self.__dict__.get("_full")
        if full is not None and name in full:
            value = full[name]
            return list(value) if isinstance(value, list) else value
        raise AttributeError(f"{type(self).__name__!s} has no attribute {name!r}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Block):
            return NotImplemented
        return self.kind == other.kind and P.canonical(self._full) == P.canonical(other._full)

    def __hash__(self) -> int:
        return hash((self.kind, P.canonical(self._full)))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._given.items())
        return f"{type(self).__name__}({args})"

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild_block, (type(self), self._given))

    # -- block-level stepping -------------------------------------------------
    def reset(self) -> None:
        """Back to the initial state (temperature, backlash position)."""
        self._reset(self._consts, self._state)

    def snapshot(self) -> bytes:
        """The block's state (the C gs_block_state, plain data) as bytes."""
        return bytes(ffi.buffer(self._state))

    def restore(self, state: bytes) -> None:
        """Restore a snapshot() of this block (or of a block of the same kind)."""
        size = ffi.sizeof("gs_block_state")
        if len(state) != size:
            raise ValueError(f"snapshot of {len(state)} bytes, expected {size}")
        ffi.memmove(self._state, state, len(state))

    # implemented by the subclasses
    def _init(self, consts: Any, state: Any, c_params: Any, err: Any) -> int:  # pragma: no cover
        raise NotImplementedError

    def _reset(self, consts: Any, state: Any) -> None:  # pragma: no cover
        raise NotImplementedError


def _copy(values: Mapping[str, Any]) -> dict[str, Any]:
    return {
        k: ([list(r) if isinstance(r, list) else r for r in v] if isinstance(v, list) else v)
        for k, v in values.items()
    }


def _rebuild_block(cls: type[Block], given: dict[str, Any]) -> Block:
    return cls(**given)


def _temperature_in(c_in: Any, temperature: float | None) -> None:
    if temperature is None:
        c_in.temperature_K = 0.0
        c_in.use_temperature_input = 0
    else:
        c_in.temperature_K = temperature
        c_in.use_temperature_input = 1


def _check_step(dt: float, **values: float | None) -> None:
    """The inputs of a block step: dt and each value finite (None = not given),
    then dt > 0; the first bad one is named."""
    for name, value in {"dt": dt, **values}.items():
        if value is not None and not math.isfinite(value):
            raise InputError(f"must be finite, got {value!r}", parameter=name)
    if not dt > 0:
        raise InputError(f"must be > 0, got {dt!r}", parameter="dt")


class SimpleGear(Block):
    """Simple Gear block (base B, follower F): teeth_ratio, output_shaft_rotates,
    friction_model, ... (docs/physics.md section 9, python-api.md)."""

    kind = "simple_gear"
    _consts_ctype = "gs_simple_gear_consts"
    _specs = {p.name: p for p in P.SIMPLE_GEAR_PARAMS}

    def _init(self, consts: Any, state: Any, c_params: Any, err: Any) -> int:
        return int(lib.gs_simple_gear_init(consts, state, c_params, err))

    def _reset(self, consts: Any, state: Any) -> None:
        lib.gs_simple_gear_reset(consts, state)

    def step(
        self,
        dt: float,
        base_speed: float,
        follower_torque: float = 0.0,
        *,
        follower_speed: float = 0.0,
        heat_flow: float = 0.0,
        temperature: float | None = None,
    ) -> dict[str, float]:
        """One block step of dt seconds (gs_simple_gear_step).

        Rigid mesh: base_speed (rad/s) and follower_torque (N*m, applied by the
        outside at F) are used. Backlash: base_speed and follower_speed (rad/s).
        heat_flow (W) enters through the thermal port; temperature (K), when
        given, replaces the thermal state in the temperature-dependent models.
        Returns base_torque, follower_torque (N*m, applied by the outside),
        follower_speed, mesh_loss_torque, mesh_loss_power, loss_power (W),
        temperature (K), backlash_position (m), contact_force (N).
        """
        _check_step(
            dt,
            base_speed=base_speed,
            follower_torque=follower_torque,
            follower_speed=follower_speed,
            heat_flow=heat_flow,
            temperature=temperature,
        )
        c_in = ffi.new("gs_gear_ports_in *")
        c_in.base_speed_rad_s = base_speed
        c_in.follower_speed_rad_s = follower_speed
        c_in.follower_torque_Nm = follower_torque
        c_in.heat_flow_W = heat_flow
        _temperature_in(c_in, temperature)
        out = ffi.new("gs_gear_ports_out *")
        lib.gs_simple_gear_step(self._consts, self._state, dt, c_in, out)
        return {
            "base_torque": out.base_torque_Nm,
            "follower_torque": out.follower_torque_Nm,
            "follower_speed": out.follower_speed_rad_s,
            "mesh_loss_torque": out.mesh_loss_torque_Nm,
            "mesh_loss_power": out.mesh_loss_power_W,
            "loss_power": out.loss_power_W,
            "temperature": out.temperature_K,
            "backlash_position": out.backlash_position_m,
            "contact_force": out.contact_force_N,
        }


class RackPinion(Block):
    """Rack & Pinion block (pinion P, rack R): parameterization, pinion_radius,
    teeth_count, spacing, rack_directionality, friction_model, ... (docs/physics.md
    section 9, the seed's program names)."""

    kind = "rack_pinion"
    _consts_ctype = "gs_rack_pinion_consts"
    _specs = {p.name: p for p in P.RACK_PINION_PARAMS}

    def _init(self, consts: Any, state: Any, c_params: Any, err: Any) -> int:
        return int(lib.gs_rack_pinion_init(consts, state, c_params, err))

    def _reset(self, consts: Any, state: Any) -> None:
        lib.gs_rack_pinion_reset(consts, state)

    @property
    def radius(self) -> float:
        """Pinion radius in use (m): pinion_radius, or teeth_count*spacing/(2*pi)."""
        return float(lib.gs_rack_pinion_radius(self._c_params))

    def step(
        self,
        dt: float,
        pinion_speed: float,
        rack_force: float = 0.0,
        *,
        rack_velocity: float = 0.0,
        heat_flow: float = 0.0,
        temperature: float | None = None,
    ) -> dict[str, float]:
        """One block step of dt seconds (gs_rack_pinion_step).

        Rigid mesh: pinion_speed (rad/s) and rack_force (N, applied by the outside
        at R). Backlash: pinion_speed and rack_velocity (m/s). Returns
        pinion_torque (N*m), rack_force (N), rack_velocity (m/s),
        mesh_loss_force (N), mesh_loss_power, loss_power (W), temperature (K),
        backlash_position (m), contact_force (N).
        """
        _check_step(
            dt,
            pinion_speed=pinion_speed,
            rack_force=rack_force,
            rack_velocity=rack_velocity,
            heat_flow=heat_flow,
            temperature=temperature,
        )
        c_in = ffi.new("gs_rack_ports_in *")
        c_in.pinion_speed_rad_s = pinion_speed
        c_in.rack_velocity_m_s = rack_velocity
        c_in.rack_force_N = rack_force
        c_in.heat_flow_W = heat_flow
        _temperature_in(c_in, temperature)
        out = ffi.new("gs_rack_ports_out *")
        lib.gs_rack_pinion_step(self._consts, self._state, dt, c_in, out)
        return {
            "pinion_torque": out.pinion_torque_Nm,
            "rack_force": out.rack_force_N,
            "rack_velocity": out.rack_velocity_m_s,
            "mesh_loss_force": out.mesh_loss_force_N,
            "mesh_loss_power": out.mesh_loss_power_W,
            "loss_power": out.loss_power_W,
            "temperature": out.temperature_K,
            "backlash_position": out.backlash_position_m,
            "contact_force": out.contact_force_N,
        }


for _cls in (SimpleGear, RackPinion):
    _cls.__doc__ = f"{_cls.__doc__}\n\n    Parameters:\n\n{P.describe(_cls._specs.values())}\n"
del _cls

BLOCK_CLASSES: dict[str, type[Block]] = {"simple_gear": SimpleGear, "rack_pinion": RackPinion}


def make_block(block: str, params: Mapping[str, Any] | None = None) -> Block:
    """SimpleGear or RackPinion from a block name ("simple_gear", "rack_pinion")."""
    try:
        cls = BLOCK_CLASSES[block]
    except (KeyError, TypeError):
        raise ModelFileError(
            f"unknown block {block!r}; expected 'simple_gear' or 'rack_pinion'", parameter="block"
        ) from None
    return cls(**dict(params or {}))

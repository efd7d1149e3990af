"""The rig's DBC: which frames are commands and which are feedback, what each
signal means, and range-checked encoding and decoding (cantools).

The DBC is the only source of frame IDs, lengths, scaling, ranges and cycle
times. What a signal *means* is written in the DBC too, as the string attribute
``GsRole`` of the signal (docs/hil.md, "Signal roles"), so that the DBC of a
real rig can be used once its signals are tagged:

- ``cmd.base_speed``, ``cmd.base_torque``, ``cmd.load``, ``cmd.mode``: command
  signals (frames holding them are command frames);
- ``out.<RigResult field>`` (``out.base_torque``, ``out.follower_speed``, ...) and
  ``out.follower_angle`` (the follower angle modulo 2*pi, in [0, 2*pi));
- ``in.base_speed``, ``in.base_torque``, ``in.load``: the inputs the rig applied
  during the last frame period (after the safe-state logic);
- ``status.counter`` (rolling), ``status.flag.<flag>``, ``status.count.<counter>``.

Frames holding ``out.``/``in.``/``status.`` signals are feedback frames; each
needs a ``GenMsgCycleTime``. The network attribute ``GsBlock``
(``"simple_gear"`` or ``"rack_pinion"``) names the rig the DBC is for.

Encoding never wraps a physical value: values are clamped into the signal's
[minimum, maximum] (reported as saturated) before ``encode(..., strict=True)``;
at load, every feedback signal's range is checked to fit its raw bits.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import can
import cantools

from ..errors import GearsimError
from ..rig import OUTPUT_NAMES
from .dbc_rules import (
    BLOCKS,
    COMMAND_ROLES,
    DEFAULT_MODE_VALUES,
    INPUT_ROLES,
    MODE_ALIASES,
    MODES,
    STATUS_COUNTS,
    STATUS_FLAGS,
    RuleError,
    frame_kind,
    signal_range,
)

__all__ = [
    "DbcError",
    "SignalSpec",
    "FrameSpec",
    "Rejection",
    "RigDbc",
    "shipped_dbc",
    "COMMAND_ROLES",
    "INPUT_ROLES",
    "OUTPUT_FIELDS",
    "STATUS_FLAGS",
    "STATUS_COUNTS",
    "MODES",
]

ROLE_ATTRIBUTE = "GsRole"
BLOCK_ATTRIBUTE = "GsBlock"

#: RigResult fields (docs/python-api.md), usable as ``out.<field>``: the rig's
#: own list, so that the two cannot drift apart.
OUTPUT_FIELDS: tuple[str, ...] = OUTPUT_NAMES
#: out.follower_angle: follower_position modulo 2*pi, in [0, 2*pi) (gear rig).
DERIVED_OUTPUTS: tuple[str, ...] = ("follower_angle",)
# The role, flag, counter and mode names and the signal and frame rules live
# in dbc_rules, which the C runner's build step reads too.

_SHIPPED = {"simple_gear": "gear_rig.dbc", "rack_pinion": "rack_rig.dbc"}
_BLOCK_ALIASES = {
    "gear": "simple_gear",
    "simple_gear": "simple_gear",
    "rack": "rack_pinion",
    "rack_pinion": "rack_pinion",
}


class DbcError(GearsimError, ValueError):
    """A DBC file cannot serve as a rig description (unreadable, unknown role,
    range wider than its bits, feedback frame without a cycle time, ...)."""


def _all_roles() -> frozenset[str]:
    roles = set(COMMAND_ROLES) | set(INPUT_ROLES)
    roles |= {f"out.{f}" for f in OUTPUT_FIELDS + DERIVED_OUTPUTS}
    roles |= {"status.counter"}
    roles |= {f"status.flag.{f}" for f in STATUS_FLAGS}
    roles |= {f"status.count.{c}" for c in STATUS_COUNTS}
    return frozenset(roles)


ALL_ROLES = _all_roles()


def block_name(name: str) -> str:
    """ "gear"/"simple_gear" -> "simple_gear", "rack"/"rack_pinion" -> "rack_pinion"."""
    try:
        return _BLOCK_ALIASES[name]
    except KeyError:
        raise DbcError(
            f"unknown rig {name!r}; expected 'gear' or 'rack'", parameter="rig"
        ) from None


def shipped_dbc(block: str) -> Path:
    """Path of the DBC shipped for a rig ("gear"/"simple_gear" or "rack"/"rack_pinion")."""
    name = _SHIPPED[block_name(block)]
    return Path(str(resources.files(__package__).joinpath("dbc", name)))


@dataclass(frozen=True)
class SignalSpec:
    """One signal with its role and the limits the bridge enforces."""

    name: str
    role: str | None
    minimum: float
    maximum: float
    scale: float
    length: int
    is_signed: bool
    is_float: bool
    choices: Mapping[int, str] | None
    """raw value -> name, for enumerated signals (decode_choices=False)"""


@dataclass(frozen=True)
class FrameSpec:
    """A frame of the DBC as the bridge sees it."""

    name: str
    frame_id: int
    is_extended: bool
    length: int
    kind: str
    """"command", "feedback" or "other" (in the DBC, not used by the bridge)"""
    cycle_time: float | None
    """GenMsgCycleTime in seconds, or None"""
    signals: tuple[SignalSpec, ...]
    message: Any = field(repr=False, compare=False)
    """the cantools Message"""

    @property
    def key(self) -> tuple[int, bool]:
        return (self.frame_id, self.is_extended)

    @property
    def roles(self) -> dict[str, SignalSpec]:
        return {s.role: s for s in self.signals if s.role}

    @property
    def is_status(self) -> bool:
        return any(s.role and s.role.startswith("status.") for s in self.signals)


@dataclass(frozen=True)
class Rejection:
    """Why a command frame was not applied (``reason`` is a counter name)."""

    reason: str
    """"bad_length", "undecodable" or "out_of_range" (the codec's part)"""
    detail: str


def _nearest_zero(s: SignalSpec) -> float:
    """The value in the signal's [minimum, maximum] nearest 0."""
    return min(max(0.0, s.minimum), s.maximum)


class RigDbc:
    """A DBC loaded for the bridge (see the module docstring for the roles).

    Args:
        path: a DBC file; None loads the one shipped for ``block``.
        block: "gear"/"simple_gear" or "rack"/"rack_pinion"; required when
            path is None, and checked against the DBC's GsBlock when both are
            known.

    Raises:
        DbcError: unreadable file or a DBC the bridge cannot use (message names
            the file, frame and signal).
    """

    def __init__(
        self, path: str | PathLike[str] | None = None, *, block: str | None = None
    ) -> None:
        if path is None:
            if block is None:
                raise DbcError("give a DBC file or a rig ('gear' or 'rack')", parameter="dbc")
            path = shipped_dbc(block)
        self.path = Path(path)
        try:
            db = cantools.database.load_file(str(self.path), database_format="dbc", strict=True)
        except FileNotFoundError:
            raise DbcError(f"{self.path}: no such file", parameter="dbc", file=self.path) from None
        except Exception as exc:  # cantools raises many kinds on a bad file
            raise DbcError(
                f"{self.path}: not a readable DBC file: {exc}", parameter="dbc", file=self.path
            ) from None
        self.database = db
        attrs = db.dbc.attributes if db.dbc is not None else {}
        dbc_block = attrs[BLOCK_ATTRIBUTE].value if BLOCK_ATTRIBUTE in attrs else ""
        if dbc_block and dbc_block not in BLOCKS:
            self._fail(f"GsBlock {dbc_block!r} is neither 'simple_gear' nor 'rack_pinion'")
        if block is not None:
            block = block_name(block)
            if dbc_block and dbc_block != block:
                self._fail(f"is for {dbc_block}, not for {block}")
        self.block: str | None = dbc_block or block

        frames = [self._frame(m) for m in db.messages]
        self.frames: tuple[FrameSpec, ...] = tuple(frames)
        self.commands: dict[tuple[int, bool], FrameSpec] = {
            f.key: f for f in frames if f.kind == "command"
        }
        self.feedback: tuple[FrameSpec, ...] = tuple(
            sorted(
                (f for f in frames if f.kind == "feedback"), key=lambda f: (f.is_status, f.frame_id)
            )
        )
        self.feedback_keys = frozenset(f.key for f in self.feedback)
        self.other_keys = frozenset(f.key for f in frames if f.kind == "other")
        self.by_key = {f.key: f for f in frames}
        seen: dict[str, str] = {}
        for f in self.commands.values():
            for s in f.signals:
                if s.role:
                    if s.role in seen:
                        self._fail(
                            f"command role {s.role!r} is on {seen[s.role]} and on {f.name}.{s.name}"
                        )
                    seen[s.role] = f"{f.name}.{s.name}"
        self.command_signals: dict[str, tuple[FrameSpec, SignalSpec]] = {
            s.role: (f, s) for f in self.commands.values() for s in f.signals if s.role
        }

    # -- loading ---------------------------------------------------------------
    def _fail(self, message: str) -> None:
        raise DbcError(f"{self.path}: {message}", parameter="dbc", file=self.path)

    def _frame(self, message: Any) -> FrameSpec:
        signals = []
        for sig in message.signals:
            role = None
            if sig.dbc is not None and ROLE_ATTRIBUTE in sig.dbc.attributes:
                role = str(sig.dbc.attributes[ROLE_ATTRIBUTE].value).strip() or None
            if role is not None and role not in ALL_ROLES:
                self._fail(f"{message.name}.{sig.name}: unknown GsRole {role!r}")
            signals.append(self._signal(message, sig, role))
        roles = [s.role for s in signals if s.role]
        try:
            kind = frame_kind(
                message.name,
                roles,
                has_cycle_time=bool(message.cycle_time),
                is_multiplexed=message.is_multiplexed(),
            )
        except RuleError as exc:
            self._fail(str(exc))
        cycle = message.cycle_time / 1000.0 if message.cycle_time else None
        return FrameSpec(
            message.name,
            message.frame_id,
            bool(message.is_extended_frame),
            message.length,
            kind,
            cycle,
            tuple(signals),
            message,
        )

    def _signal(self, message: Any, sig: Any, role: str | None) -> SignalSpec:
        scale = float(sig.scale)
        offset = float(sig.offset)
        is_float = bool(sig.is_float)
        where = f"{message.name}.{sig.name}"
        try:
            minimum, maximum = signal_range(
                where,
                role,
                length=sig.length,
                is_signed=bool(sig.is_signed),
                is_float=is_float,
                scale=scale,
                offset=offset,
                minimum=sig.minimum,
                maximum=sig.maximum,
            )
        except RuleError as exc:
            self._fail(str(exc))
        choices = None
        if sig.choices:
            choices = {int(k): str(v) for k, v in sig.choices.items()}
        if role == "cmd.mode":
            names = choices or DEFAULT_MODE_VALUES
            for raw, name in names.items():
                if str(name).strip().lower() not in MODE_ALIASES:
                    self._fail(
                        f"{where}: mode value {raw} is named {name!r}; expected one of "
                        "Disabled, Speed, Torque"
                    )
        return SignalSpec(
            sig.name,
            role,
            minimum,
            maximum,
            scale,
            sig.length,
            bool(sig.is_signed),
            is_float,
            choices,
        )

    # -- description -----------------------------------------------------------
    def __repr__(self) -> str:
        return f"RigDbc({str(self.path)!r}, block={self.block!r})"

    def has_role(self, role: str) -> bool:
        return any(s.role == role for f in self.frames for s in f.signals)

    def feedback_signals(self, role: str) -> list[tuple[FrameSpec, SignalSpec]]:
        """Every (frame, signal) of the feedback frames carrying ``role``."""
        return [(f, s) for f in self.feedback for s in f.signals if s.role == role]

    # -- commands --------------------------------------------------------------
    def decode_command(
        self, frame: FrameSpec, data: bytes | bytearray
    ) -> dict[str, Any] | Rejection:
        """Decode and check one command frame.

        Returns role -> value (physical units; ``cmd.mode`` as "disabled",
        "speed" or "torque") for the signals that have a role, or a Rejection:
        ``bad_length`` (data length differs from the DBC's), ``undecodable``
        (cantools cannot decode it, or an enumerated value has no name), or
        ``out_of_range`` (a signal, with or without a role, outside its DBC
        [minimum, maximum])."""
        if len(data) != frame.length:
            return Rejection(
                "bad_length", f"{frame.name}: {len(data)} data bytes, DBC says {frame.length}"
            )
        try:
            values = frame.message.decode(bytes(data), decode_choices=False, scaling=True)
        except Exception as exc:
            return Rejection("undecodable", f"{frame.name}: {exc}")
        out: dict[str, Any] = {}
        for s in frame.signals:
            v = values.get(s.name)
            if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
                return Rejection("undecodable", f"{frame.name}.{s.name}: {v!r}")
            if s.choices is not None and s.role == "cmd.mode" and int(v) not in s.choices:
                return Rejection(
                    "undecodable", f"{frame.name}.{s.name}: {v!r} is not a defined value"
                )
            tol = abs(s.scale) * 1e-6
            if v < s.minimum - tol or v > s.maximum + tol:
                return Rejection(
                    "out_of_range",
                    f"{frame.name}.{s.name} = {v!r} outside [{s.minimum}, {s.maximum}]",
                )
            if s.role == "cmd.mode":
                names = s.choices or DEFAULT_MODE_VALUES
                if int(v) not in names:
                    return Rejection(
                        "undecodable", f"{frame.name}.{s.name}: {v!r} is not a defined value"
                    )
                out[s.role] = MODE_ALIASES[str(names[int(v)]).strip().lower()]
            elif s.role:
                out[s.role] = float(v)
        return out

    def encode_command(self, values: Mapping[str, Any]) -> list[can.Message]:
        """Command frames from role -> value ({"cmd.base_speed": 10.0,
        "cmd.load": 0.5, "cmd.mode": "speed"}); unset signals are 0 (mode:
        "speed"). For test peers and examples; strict, so out-of-range values
        raise cantools' EncodeError."""
        msgs = []
        for frame in self.commands.values():
            data = {}
            for s in frame.signals:
                v: Any = (
                    values.get(s.role, "speed" if s.role == "cmd.mode" else 0.0) if s.role else 0.0
                )
                if s.role == "cmd.mode":
                    names = s.choices or DEFAULT_MODE_VALUES
                    v = next(
                        raw for raw, n in names.items() if MODE_ALIASES[str(n).strip().lower()] == v
                    )
                data[s.name] = v
            payload = frame.message.encode(data, scaling=True, strict=True)
            msgs.append(
                can.Message(
                    arbitration_id=frame.frame_id, is_extended_id=frame.is_extended, data=payload
                )
            )
        return msgs

    # -- feedback --------------------------------------------------------------
    def encode_feedback(
        self, frame: FrameSpec, values: Mapping[str, float]
    ) -> tuple[bytes, list[str]]:
        """Encode one feedback frame from role -> value.

        Counters (``status.count.*``, ``status.counter``) are taken modulo
        2**bits (they are rolling by definition). Every other value is clamped
        into the signal's [minimum, maximum] (NaN becomes the value in range
        nearest 0) before ``encode(strict=True)``; the names of the clamped
        signals are returned. Signals without a role are sent as the value in
        range nearest 0."""
        data: dict[str, float | int] = {}
        saturated: list[str] = []
        for s in frame.signals:
            role = s.role
            if role is None:
                data[s.name] = _nearest_zero(s)
                continue
            v = values[role]
            if role == "status.counter" or role.startswith("status.count."):
                data[s.name] = int(v) % (1 << s.length)
                continue
            if role.startswith("status.flag."):
                data[s.name] = 1 if v else 0
                continue
            x = float(v)
            if not math.isfinite(x):
                x = _nearest_zero(s) if math.isnan(x) else (s.maximum if x > 0 else s.minimum)
                saturated.append(s.name)
            elif x < s.minimum:
                x = s.minimum
                saturated.append(s.name)
            elif x > s.maximum:
                x = s.maximum
                saturated.append(s.name)
            data[s.name] = x
        return frame.message.encode(data, scaling=True, strict=True), saturated

    def decode_feedback(self, frame: FrameSpec, data: bytes | bytearray) -> dict[str, float] | None:
        """role -> value of one feedback frame, or None if it does not decode
        (wrong length, cantools error)."""
        if len(data) != frame.length:
            return None
        try:
            values = frame.message.decode(bytes(data), decode_choices=False, scaling=True)
        except Exception:
            return None
        return {s.role: float(values[s.name]) for s in frame.signals if s.role}

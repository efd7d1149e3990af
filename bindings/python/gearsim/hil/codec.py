"""The rig's DBC: which frames are commands and which are feedback, what each
signal means, and range-checked encoding and decoding.

cantools reads the DBC file, the only source of frame IDs, lengths, scaling,
ranges and cycle times. What a signal *means* is written in the DBC too, as
the string attribute ``GsRole`` of the signal (docs/hil.md, "Signal roles"),
so that the DBC of a real rig can be used once its signals are tagged:

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

The DBC's facts go into a C frame table (gs_hil_dbc of gearsim/hil.h), the
one the bridge runs on. Everything else is the C library's: the role names
(gs_hil_role_parse), the rules a DBC must follow (gs_hil_dbc_check, which
names the frame and signal), which frames are commands or feedback, and the
codec: commands are decoded and range-checked, feedback values are clamped
into their range and never wrap. The C runner gearsim-hil uses the same
library on tables made from the same DBC files at build time.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import can
import cantools

from .._lib import ffi, lib
from ..errors import GearsimError
from .names import (
    COMMAND_ROLES,
    DERIVED_OUTPUTS,
    INPUT_ROLES,
    MODES,
    OUTPUT_FIELDS,
    STATUS_COUNTS,
    STATUS_FLAGS,
)

__all__ = [
    "DbcError",
    "SignalSpec",
    "FrameSpec",
    "Rejection",
    "RigDbc",
    "shipped_dbc",
    "block_name",
    "COMMAND_ROLES",
    "INPUT_ROLES",
    "OUTPUT_FIELDS",
    "DERIVED_OUTPUTS",
    "STATUS_FLAGS",
    "STATUS_COUNTS",
    "MODES",
]

ROLE_ATTRIBUTE = "GsRole"
BLOCK_ATTRIBUTE = "GsBlock"

#: The rigs a DBC may be for (GsBlock) and their C gs_rig_block.
BLOCKS: dict[str, int] = {
    "simple_gear": lib.GS_RIG_SIMPLE_GEAR,
    "rack_pinion": lib.GS_RIG_RACK_PINION,
}
_SHIPPED = {"simple_gear": "gear_rig.dbc", "rack_pinion": "rack_rig.dbc"}
_BLOCK_ALIASES = {
    "gear": "simple_gear",
    "simple_gear": "simple_gear",
    "rack": "rack_pinion",
    "rack_pinion": "rack_pinion",
}
_KINDS = {
    lib.GS_HIL_FRAME_COMMAND: "command",
    lib.GS_HIL_FRAME_FEEDBACK: "feedback",
    lib.GS_HIL_FRAME_OTHER: "other",
    lib.GS_HIL_FRAME_PARAM: "param",
    lib.GS_HIL_FRAME_ACK: "ack",
}


class DbcError(GearsimError, ValueError):
    """A DBC file cannot serve as a rig description (unreadable, unknown role,
    range wider than its bits, feedback frame without a cycle time, ...)."""


def block_name(name: str) -> str:
    """ "gear"/"simple_gear" -> "simple_gear", "rack"/"rack_pinion" -> "rack_pinion"."""
    try:
        return _BLOCK_ALIASES[name]
    except KeyError:
        raise DbcError(
            f"unknown rig {name!r}; expected 'gear' or 'rack'", parameter="rig"
        ) from None


def shipped_dbc(block: str) -> Path:
    """Path of the DBC shipped for a rig ("gear"/"simple_gear" or "rack"/"rack_pinion"):
    the package data gearsim.hil.dbc, installed from the repository's hil/dbc."""
    name = _SHIPPED[block_name(block)]
    return Path(str(resources.files(f"{__package__}.dbc").joinpath(name)))


@dataclass(frozen=True)
class SignalSpec:
    """One signal with its role and the limits the bridge enforces."""

    name: str
    role: str | None
    minimum: float
    """the DBC's minimum, or what the signal's bits hold"""
    maximum: float
    scale: float
    length: int
    is_signed: bool
    is_float: bool
    choices: Mapping[int, str] | None
    """raw value -> name, for enumerated signals"""
    index: int = field(default=0, compare=False)
    """position in its frame"""


@dataclass(frozen=True)
class FrameSpec:
    """A frame of the DBC as the bridge sees it."""

    name: str
    frame_id: int
    is_extended: bool
    length: int
    kind: str
    """"command", "feedback", "param" (a parameter request from the host),
    "ack" (its answer from the rig) or "other" (in the DBC, not used by the
    bridge)"""
    cycle_time: float | None
    """GenMsgCycleTime in seconds, or None"""
    signals: tuple[SignalSpec, ...]
    message: Any = field(repr=False, compare=False)
    """the cantools Message"""
    spec: Any = field(repr=False, compare=False, default=None)
    """its gs_hil_frame_spec in the C table"""

    @property
    def key(self) -> tuple[int, bool]:
        return (self.frame_id, self.is_extended)

    @property
    def roles(self) -> dict[str, SignalSpec]:
        return {s.role: s for s in self.signals if s.role}

    @property
    def is_status(self) -> bool:
        return bool(lib.gs_hil_frame_is_status(self.spec))


@dataclass(frozen=True)
class Rejection:
    """Why a command frame was not applied (``reason`` is a counter name)."""

    reason: str
    """"bad_length", "undecodable" or "out_of_range" (the codec's part)"""
    detail: str


def _role_of(sig: Any) -> str | None:
    if sig.dbc is not None and ROLE_ATTRIBUTE in sig.dbc.attributes:
        return str(sig.dbc.attributes[ROLE_ATTRIBUTE].value).strip() or None
    return None


class _Table:
    """The C frame table (gs_hil_dbc) of a cantools database: the DBC's facts
    as they are, each role resolved by gs_hil_role_parse. Owns the C memory
    (keep it alive as long as the table is used)."""

    def __init__(self, db: Any, block: str | None, fail: Any, name: str = "dbc") -> None:
        self._keep: list[Any] = []
        messages = db.messages
        self.frames = ffi.new("gs_hil_frame_spec[]", max(1, len(messages)))
        self.dbc = ffi.new("gs_hil_dbc *")
        self.dbc.name = self._text(name)  # the file's stem, as the runner's built-in tables
        self.dbc.block = BLOCKS.get(block or "", lib.GS_RIG_SIMPLE_GEAR)
        self.dbc.frames = self.frames
        self.dbc.frame_count = len(messages)
        self.roles: list[list[str | None]] = []
        role = ffi.new("gs_hil_role *")
        aux = ffi.new("size_t *")
        for i, msg in enumerate(messages):
            signals = ffi.new("gs_hil_signal[]", max(1, len(msg.signals)))
            self._keep.append(signals)
            roles = []
            for k, sig in enumerate(msg.signals):
                text = _role_of(sig)
                if text is not None and lib.gs_hil_role_parse(text.encode(), role, aux) != 0:
                    fail(f"{msg.name}.{sig.name}: unknown GsRole {text!r}")
                roles.append(text)
                if text is None:
                    role[0], aux[0] = lib.GS_HIL_ROLE_NONE, 0
                self._signal(signals[k], sig, role[0], aux[0])
            self.roles.append(roles)
            f = self.frames[i]
            f.name = self._text(msg.name)
            f.id = msg.frame_id
            f.is_extended = int(bool(msg.is_extended_frame))
            f.length = msg.length
            f.cycle_ms = int(msg.cycle_time or 0)
            f.is_multiplexed = int(bool(msg.is_multiplexed()))
            f.signals = signals
            f.signal_count = len(msg.signals)

    def _text(self, text: str) -> Any:
        data = ffi.new("char[]", text.encode("utf-8"))
        self._keep.append(data)
        return data

    def _signal(self, c: Any, sig: Any, role: int, aux: int) -> None:
        c.name = self._text(sig.name)
        c.start = sig.start
        c.length = sig.length
        c.is_signed = int(bool(sig.is_signed))
        c.is_big_endian = int(sig.byte_order == "big_endian")
        c.is_float = int(bool(sig.is_float))
        c.scale = float(sig.scale)
        c.offset = float(sig.offset)
        c.minimum = -float("inf") if sig.minimum is None else float(sig.minimum)
        c.maximum = float("inf") if sig.maximum is None else float(sig.maximum)
        c.role = role
        c.aux = aux
        if sig.choices:
            choices = ffi.new("gs_hil_choice[]", len(sig.choices))
            for j, (value, name) in enumerate(sig.choices.items()):
                choices[j].value = int(value)
                choices[j].name = self._text(str(name))
            self._keep.append(choices)
            c.choices = choices
            c.choice_count = len(sig.choices)


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
        self.table = _Table(db, self.block, self._fail, self.path.stem)
        err = ffi.new("gs_hil_error *")
        if lib.gs_hil_dbc_check(self.table.dbc, err) != lib.GS_HIL_OK:
            self._fail(ffi.string(err.message).decode("utf-8", "replace"))

        frames = [self._frame(i, m) for i, m in enumerate(db.messages)]
        self.frames: tuple[FrameSpec, ...] = tuple(frames)
        self.commands: dict[tuple[int, bool], FrameSpec] = {
            f.key: f for f in frames if f.kind == "command"
        }
        order = ffi.new("unsigned[]", lib.GS_HIL_MAX_FRAMES)
        count = lib.gs_hil_feedback_order(self.table.dbc, order)
        #: feedback frames in the order the bridge sends them
        self.feedback: tuple[FrameSpec, ...] = tuple(frames[order[i]] for i in range(count))
        self.feedback_keys = frozenset(f.key for f in self.feedback)
        self.other_keys = frozenset(f.key for f in frames if f.kind == "other")
        self.by_key = {f.key: f for f in frames}
        self.command_signals: dict[str, tuple[FrameSpec, SignalSpec]] = {
            s.role: (f, s) for f in self.commands.values() for s in f.signals if s.role
        }
        #: the parameter request and acknowledgement frames (None without)
        self.param_frame: FrameSpec | None = next((f for f in frames if f.kind == "param"), None)
        self.ack_frame: FrameSpec | None = next((f for f in frames if f.kind == "ack"), None)

    # -- loading ---------------------------------------------------------------
    def _fail(self, message: str) -> None:
        raise DbcError(f"{self.path}: {message}", parameter="dbc", file=self.path)

    def _frame(self, index: int, message: Any) -> FrameSpec:
        spec = self.table.frames + index
        signals = []
        low, high = ffi.new("double *"), ffi.new("double *")
        for k, sig in enumerate(message.signals):
            lib.gs_hil_signal_limits(spec.signals + k, low, high)
            signals.append(
                SignalSpec(
                    sig.name,
                    self.table.roles[index][k],
                    low[0],
                    high[0],
                    float(sig.scale),
                    sig.length,
                    bool(sig.is_signed),
                    bool(sig.is_float),
                    {int(v): str(n) for v, n in sig.choices.items()} if sig.choices else None,
                    k,
                )
            )
        cycle = message.cycle_time / 1000.0 if message.cycle_time else None
        return FrameSpec(
            message.name,
            message.frame_id,
            bool(message.is_extended_frame),
            message.length,
            _KINDS[lib.gs_hil_frame_kind_of(spec)],
            cycle,
            tuple(signals),
            message,
            spec,
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
        """Decode and check one command frame (gs_hil_decode_command).

        Returns role -> value (physical units; ``cmd.mode`` as "disabled",
        "speed" or "torque") for the signals that have a role, or a Rejection:
        ``bad_length`` (data length differs from the DBC's), ``undecodable``
        (not a finite number, or a mode value without a name), or
        ``out_of_range`` (a signal, with or without a role, outside its DBC
        [minimum, maximum])."""
        data = bytes(data)
        cmd = ffi.new("gs_hil_command *")
        reason = lib.gs_hil_decode_command(frame.spec, data, len(data), cmd)
        if reason != lib.GS_HIL_PENDING:
            name = ffi.string(lib.gs_hil_reason_name(reason)).decode().split(".", 1)[1]
            return Rejection(name, self._rejection_detail(frame, data, name, cmd.signal))
        out: dict[str, Any] = {}
        for slot, role in enumerate(COMMAND_ROLES):
            if cmd.present[slot]:
                value = cmd.value[slot]
                out[role] = MODES[int(value)] if role == "cmd.mode" else float(value)
        return out

    @staticmethod
    def _rejection_detail(frame: FrameSpec, data: bytes, reason: str, index: int) -> str:
        if reason == "bad_length":
            return f"{frame.name}: {len(data)} data bytes, DBC says {frame.length}"
        s = frame.signals[index]
        padded = (data + bytes(8))[:8]
        v = lib.gs_hil_signal_value(frame.spec.signals + index, padded)
        if reason == "out_of_range":
            return f"{frame.name}.{s.name} = {v!r} outside [{s.minimum}, {s.maximum}]"
        return f"{frame.name}.{s.name}: {v!r} is not a defined value"

    def encode_command(self, values: Mapping[str, Any]) -> list[can.Message]:
        """Command frames from role -> value ({"cmd.base_speed": 10.0,
        "cmd.load": 0.5, "cmd.mode": "speed"}); unset signals are 0 (mode:
        "speed"). For test peers and examples: encoded by cantools, strict,
        so out-of-range values raise cantools' EncodeError."""
        msgs = []
        for frame in self.commands.values():
            data = {}
            for s in frame.signals:
                v: Any = (
                    values.get(s.role, "speed" if s.role == "cmd.mode" else 0.0) if s.role else 0.0
                )
                if s.role == "cmd.mode":
                    v = self._mode_raw(s, v)
                data[s.name] = v
            payload = frame.message.encode(data, scaling=True, strict=True)
            msgs.append(
                can.Message(
                    arbitration_id=frame.frame_id, is_extended_id=frame.is_extended, data=payload
                )
            )
        return msgs

    def encode_param(self, name: str, value: float) -> can.Message:
        """The parameter frame that asks the rig to set ``name`` ("key",
        "key[i]" or "key[i][j]" of a tunable parameter of the DBC's rig,
        gearsim.hil.names.tunable_parameters) to ``value`` (SI units). Encoded
        by cantools, strict. DbcError without a parameter frame or for a
        name that is no tunable parameter."""
        from .names import parse_parameter

        if self.param_frame is None or self.block is None:
            self._fail("has no parameter frame (GsRole param.id and param.value)")
        assert self.param_frame is not None and self.block is not None
        try:
            index, element = parse_parameter(self.block, name)
        except ValueError as exc:
            raise DbcError(str(exc), parameter="param") from None
        values = {"param.id": index, "param.element": element, "param.value": float(value)}
        data = {s.name: values.get(s.role or "", 0) for s in self.param_frame.signals}
        payload = self.param_frame.message.encode(data, scaling=True, strict=True)
        return can.Message(
            arbitration_id=self.param_frame.frame_id,
            is_extended_id=self.param_frame.is_extended,
            data=payload,
        )

    @staticmethod
    def _mode_raw(s: SignalSpec, mode: str) -> int:
        """The value of a cmd.mode signal that names ``mode``."""
        want = MODES.index(mode)
        if not s.choices:
            return want
        names = s.choices.items()
        return next(raw for raw, n in names if lib.gs_hil_mode_parse(n.encode()) == want)

    # -- feedback --------------------------------------------------------------
    def encode_feedback(
        self, frame: FrameSpec, values: Mapping[str, float]
    ) -> tuple[bytes, list[str]]:
        """Encode one feedback frame from role -> value, as the bridge does.

        Counters (``status.count.*``, ``status.counter``) are taken modulo
        2**bits (they are rolling by definition), flags are 0 or 1. Every
        other value is clamped into the signal's [minimum, maximum] (NaN
        becomes the value in range nearest 0); the names of the clamped
        signals are returned. Signals without a role are sent as the value in
        range nearest 0."""
        data = ffi.new("uint8_t[]", lib.GS_HIL_MAX_DATA)
        saturated: list[str] = []
        for s in frame.signals:
            c = frame.spec.signals + s.index
            role = s.role
            if role is None:
                lib.gs_hil_put_value(c, 0.0, data)
            elif role == "status.counter" or role.startswith("status.count."):
                lib.gs_hil_put_raw(c, int(values[role]) % (1 << s.length), data)
            elif role.startswith("status.flag."):
                lib.gs_hil_put_raw(c, 1 if values[role] else 0, data)
            elif lib.gs_hil_put_value(c, float(values[role]), data):
                saturated.append(s.name)
        return bytes(ffi.buffer(data, frame.length)), saturated

    def decode_feedback(self, frame: FrameSpec, data: bytes | bytearray) -> dict[str, float] | None:
        """role -> value of one feedback frame, or None if its length is not
        the DBC's."""
        if len(data) != frame.length:
            return None
        padded = (bytes(data) + bytes(8))[:8]
        return {
            s.role: float(lib.gs_hil_signal_value(frame.spec.signals + s.index, padded))
            for s in frame.signals
            if s.role
        }

"""Helpers of the HIL tests: models and a test peer on the virtual bus."""

from __future__ import annotations

import itertools
import math
from typing import Any

import pytest

can = pytest.importorskip("can")
pytest.importorskip("cantools")
gearsim = pytest.importorskip("gearsim")

from gearsim.hil import Bridge, RigDbc  # noqa: E402

_channels = itertools.count()


def gear_model(**rig: Any) -> Any:
    return gearsim.Model(
        block="simple_gear",
        block_params={
            "teeth_ratio": 3.0,
            "friction_model": "constant_efficiency",
            "efficiency_const": 0.95,
        },
        rig_params={
            "follower_inertia": 0.05,
            "load_coulomb_friction": 0.02,
            "thermal_resistance": 2.0,
            "ambient_temperature": 293.15,
            **rig,
        },
    )


def rack_model(**rig: Any) -> Any:
    return gearsim.Model(
        block="rack_pinion",
        block_params={"pinion_radius": 0.02},
        rig_params={"rack_mass": 2.0, "load_coulomb_friction": 0.5, **rig},
    )


class Peer:
    """The test host: sends commands, collects feedback, on its own bus."""

    def __init__(self, channel: str, dbc: RigDbc) -> None:
        self.bus = can.Bus(interface="virtual", channel=channel, preserve_timestamps=True)
        self.dbc = dbc

    def command(self, t: float = 0.0, **values: Any) -> list[Any]:
        """Send the command frames for role values (base_speed=..., load=...,
        mode=...); stamped t. Returns the messages sent."""
        roles = {f"cmd.{k}": v for k, v in values.items()}
        msgs = self.dbc.encode_command(roles)
        for m in msgs:
            m.timestamp = t
            self.bus.send(m)
        return msgs

    def send(self, msg: Any) -> None:
        self.bus.send(msg)

    def drain(self) -> list[Any]:
        out = []
        while (m := self.bus.recv(timeout=0.0)) is not None:
            out.append(m)
        return out

    def decoded(self, msgs: list[Any]) -> list[tuple[str, dict[str, float]]]:
        """(frame name, role -> value) of each message, decoded by cantools:
        a check of the bridge's C encoder that does not use it."""
        out = []
        for m in msgs:
            frame = self.dbc.by_key[(m.arbitration_id, bool(m.is_extended_id))]
            out.append((frame.name, roles_by_cantools(frame, m.data)))
        return out

    def close(self) -> None:
        self.bus.shutdown()


def roles_by_cantools(frame: Any, data: bytes) -> dict[str, Any]:
    """role -> value of a frame's role signals as cantools decodes them
    (cmd.mode as the name of its value)."""
    values = frame.message.decode(bytes(data), decode_choices=False)
    out: dict[str, Any] = {}
    for s in frame.signals:
        if s.role == "cmd.mode":
            name = (s.choices or {}).get(int(values[s.name]), "")
            out[s.role] = name.strip().lower()
        elif s.role:
            out[s.role] = float(values[s.name])
    return out


def status_of(peer: Peer, msgs: list[Any]) -> dict[str, float]:
    """Merged role values of the last status frames in msgs."""
    out: dict[str, float] = {}
    for _, values in peer.decoded(msgs):
        if any(r.startswith("status.") for r in values):
            out.update(values)
    return out


def wrap_angle(x: float) -> float:
    return math.fmod(x, 2 * math.pi) % (2 * math.pi)


def record_session(
    model: Any,
    dbc: RigDbc,
    log_path: Any,
    profile: Any,
    *,
    periods: int = 600,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.05,
    silent: Any = lambda k: False,
) -> tuple[list[tuple[float, int, bytes]], dict]:
    """A live session back to back on the virtual bus, recorded with python-can's
    Logger: the peer sends the commands of profile(k) (a dict of role values
    without the "cmd." prefix) every 10 periods unless silent(k); the log holds
    the commands and the feedback, stamped with simulated time. Returns the
    feedback as (time, ID, data) and the bridge summary."""
    channel = next_channel("session")
    bridge_bus = can.Bus(interface="virtual", channel=channel, preserve_timestamps=True)
    peer = Peer(channel, dbc)
    logger = can.Logger(str(log_path))
    feedback: list[tuple[float, int, bytes]] = []
    try:
        bridge = Bridge.from_model(
            model,
            dbc,
            period=period,
            substeps=substeps,
            timeout=timeout,
            bus=bridge_bus,
            stamp=lambda t: t,
        )
        for k in range(periods):
            if k % 10 == 0 and not silent(k):
                for m in peer.command(t=k * period, **profile(k)):
                    m.is_rx = False
                    logger.on_message_received(m)
            bridge.tick()
            for m in peer.drain():
                feedback.append((m.timestamp, m.arbitration_id, bytes(m.data)))
                logger.on_message_received(m)
        summary = bridge.close()
    finally:
        logger.stop()
        peer.close()
        bridge_bus.shutdown()
    return feedback, summary


def read_frames(path: Any) -> list[tuple[float, int, bytes]]:
    """(time, ID, data) of every frame of a log, times relative to the first frame."""
    msgs = list(can.LogReader(str(path)))
    t0 = msgs[0].timestamp if msgs else 0.0
    return [(m.timestamp - t0, m.arbitration_id, bytes(m.data)) for m in msgs]


def next_channel(name: str) -> str:
    """A virtual-bus channel name used by nobody else in this process."""
    return f"gearsim-hil-test-{name}-{next(_channels)}"


__all__ = [
    "Peer",
    "gear_model",
    "rack_model",
    "status_of",
    "wrap_angle",
    "roles_by_cantools",
    "next_channel",
    "record_session",
    "read_frames",
    "Bridge",
    "RigDbc",
    "can",
    "gearsim",
]

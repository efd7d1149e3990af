"""Fixtures of the HIL tests (helpers in hil_helpers.py)."""

from __future__ import annotations

from typing import Any

import pytest

pytest.importorskip("can")
pytest.importorskip("cantools")
pytest.importorskip("gearsim")

from hil_helpers import Bridge, Peer, RigDbc, can, gear_model, next_channel, rack_model  # noqa: E402


@pytest.fixture
def channel(request: pytest.FixtureRequest) -> str:
    """A virtual-bus channel of its own for each test."""
    return next_channel(request.node.name)


@pytest.fixture
def gear() -> Any:
    return gear_model()


@pytest.fixture
def rack() -> Any:
    return rack_model()


@pytest.fixture
def gear_dbc() -> RigDbc:
    return RigDbc(block="gear")


@pytest.fixture
def rack_dbc() -> RigDbc:
    return RigDbc(block="rack")


@pytest.fixture
def link(channel: str, gear: Any, gear_dbc: RigDbc):
    """(bridge, peer) back to back on a virtual bus: gear rig, 1 ms x 1 substep,
    timeout 50 ms."""
    bridge_bus = can.Bus(interface="virtual", channel=channel)
    peer = Peer(channel, gear_dbc)
    bridge = Bridge.from_model(
        gear, gear_dbc, period=1e-3, substeps=1, timeout=0.05, bus=bridge_bus
    )
    yield bridge, peer
    peer.close()
    bridge_bus.shutdown()

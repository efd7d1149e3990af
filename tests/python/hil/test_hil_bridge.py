"""The bridge back to back with a test peer on the virtual bus.

Simulated time is driven with Bridge.tick()/advance() only: nothing sleeps and
no assertion depends on the wall clock."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hil_helpers import (
    Bridge,
    Peer,
    RigDbc,
    can,
    gear_model,
    rack_model,
    roles_by_cantools,
    status_of,
    wrap_angle,
)

from gearsim.hil import BridgeError, Counters


def _sum_classes(c: Counters, pending: int = 0) -> int:
    return c.rx_used + c.rx_rejected + c.rx_late + c.rx_ignored + pending


def _check_against_reference(
    bridge: Bridge, peer: Peer, model: Any, periods: int, profile: Any, mode: str
) -> dict[int, int]:
    """Peer sends profile(k) every 10 periods; every feedback value, decoded by
    cantools, must equal the reference rig, stepped directly with the same
    (decoded) commands, to within half a DBC step. Returns frames received per ID."""
    dbc = peer.dbc
    ref = model.rig(dt=bridge.dt)
    frame = next(iter(dbc.commands.values()))
    held: dict[str, Any] | None = None
    seen: dict[int, int] = {}
    drive = "base_speed" if mode == "speed" else "base_torque"
    for k in range(periods):
        if k % 10 == 0:
            msgs = peer.command(t=k * bridge.period, mode=mode, **profile(k))
            held = roles_by_cantools(frame, msgs[0].data)
        bridge.tick()
        for _ in range(bridge.substeps):
            res = ref.step(load=held["cmd.load"], **{drive: held[f"cmd.{drive}"]})
        expected = {f"out.{f}": getattr(res, f) for f in res.keys()}
        expected["out.follower_angle"] = wrap_angle(res.follower_position)
        expected["in.load"] = held["cmd.load"]
        for msg in peer.drain():
            seen[msg.arbitration_id] = seen.get(msg.arbitration_id, 0) + 1
            fb = dbc.by_key[(msg.arbitration_id, False)]
            values = roles_by_cantools(fb, msg.data)
            for s in fb.signals:
                role = s.role
                if not role.startswith(("out.", "in.")):
                    continue
                want = expected[role]
                tol = abs(s.scale) / 2 + 1e-9
                got = values[role]
                if role == "out.follower_angle":
                    diff = abs(got - want)
                    diff = min(diff, 2 * math.pi - diff)
                    assert diff <= tol, (k, fb.name, s.name, got, want)
                else:
                    assert got == pytest.approx(want, abs=tol), (k, fb.name, s.name)
    return seen


def _profile_speed(k: int) -> dict[str, float]:
    return {
        "base_speed": 40.0 * math.sin(2 * math.pi * k / 300),
        "load": 0.8 * math.cos(2 * math.pi * k / 170),
    }


def test_gear_feedback_matches_the_rig_stepped_directly(
    link: tuple[Bridge, Peer], gear: Any
) -> None:
    bridge, peer = link
    seen = _check_against_reference(bridge, peer, gear, 600, _profile_speed, "speed")
    # feedback at the DBC cycle times: 10 ms and 100 ms frames over 600 periods of 1 ms
    assert seen == {0x200: 60, 0x201: 60, 0x202: 6, 0x210: 6, 0x211: 6, 0x212: 6}
    c = bridge.counters
    assert c.rx_total == c.rx_used == 60 and c.timeouts == 0 and c.saturations == 0
    assert c.tx_frames == 144 and c.periods == 600 and c.steps == 600


def test_rack_feedback_matches_with_substeps(channel: str, rack_dbc: RigDbc) -> None:
    model = rack_model()
    bus = can.Bus(interface="virtual", channel=channel)
    peer = Peer(channel, rack_dbc)
    try:
        bridge = Bridge.from_model(model, rack_dbc, period=2e-3, substeps=4, bus=bus)
        assert bridge.dt == pytest.approx(5e-4)
        seen = _check_against_reference(
            bridge,
            peer,
            model,
            300,
            lambda k: {"base_speed": 25.0 * math.sin(k / 40.0), "load": 60.0 * math.cos(k / 25.0)},
            "speed",
        )
        assert seen == {0x300: 60, 0x301: 60, 0x302: 6, 0x310: 6, 0x311: 6, 0x312: 6}
        assert bridge.counters.steps == 1200
    finally:
        peer.close()
        bus.shutdown()


def test_torque_driven_gear(channel: str, gear_dbc: RigDbc) -> None:
    model = gear_model(base_drive="torque", base_inertia=0.01)
    bus = can.Bus(interface="virtual", channel=channel)
    peer = Peer(channel, gear_dbc)
    try:
        bridge = Bridge.from_model(model, gear_dbc, period=1e-3, bus=bus)
        _check_against_reference(
            bridge,
            peer,
            model,
            300,
            lambda k: {"base_torque": 0.5 * math.sin(k / 30.0), "load": 0.2},
            "torque",
        )
        # a speed command on a torque-driven rig is refused
        peer.command(mode="speed", base_speed=5.0)
        bridge.tick()
        assert bridge.counters.reasons == {"rejected.mode_mismatch": 1}
    finally:
        peer.close()
        bus.shutdown()


def test_every_fault_is_counted_and_never_applied(link: tuple[Bridge, Peer]) -> None:
    bridge, peer = link
    dbc = peer.dbc
    frame = dbc.commands[(0x100, False)]
    peer.command(t=1.0, base_speed=10.0, load=0.1)
    bridge.tick()
    good = dbc.encode_command({"cmd.base_speed": 10.0, "cmd.load": 0.1})[0].data
    bad_mode = bytearray(good)
    bad_mode[7] = 0x03
    out_of_range = frame.message.encode(
        {"BaseSpeedCmd": 1500.0, "MotorTorqueCmd": 0.0, "LoadTorqueCmd": 0.0, "DriveMode": 1},
        strict=False,
    )
    torque_mode = dbc.encode_command({"cmd.base_torque": 1.0, "cmd.mode": "torque"})[0].data

    def std(arbitration_id: int, **kw: Any) -> can.Message:
        return can.Message(arbitration_id=arbitration_id, is_extended_id=False, timestamp=1.1, **kw)

    faults = [
        std(0x123, data=good),  # unknown ID
        can.Message(
            arbitration_id=0x100, is_extended_id=True, data=good, timestamp=1.1
        ),  # extended
        std(0x100, data=good[:5]),  # wrong length
        std(0x100, data=bad_mode),  # undecodable: no such DriveMode
        std(0x100, data=out_of_range),  # out of the DBC range
        std(0x100, data=torque_mode),  # torque mode on a speed rig
        std(0x100, is_remote_frame=True, dlc=8),  # remote frame
        can.Message(is_error_frame=True, timestamp=1.1),  # error frame
        std(0x200, data=bytes(8)),  # one of the rig's feedback IDs
    ]
    for m in faults:
        peer.send(m)
    bridge.tick()
    # two valid commands before one period: the first is superseded
    peer.command(t=1.2, base_speed=20.0, load=0.2)
    peer.command(t=1.3, base_speed=30.0, load=0.3)
    bridge.tick()
    # older than the command held: out of order
    peer.command(t=1.25, base_speed=99.0, load=0.0)
    bridge.tick()
    c = bridge.counters
    assert c.reasons == {
        "rejected.unknown_id": 2,
        "rejected.bad_length": 1,
        "rejected.undecodable": 1,
        "rejected.out_of_range": 1,
        "rejected.mode_mismatch": 1,
        "ignored.remote_frame": 1,
        "ignored.error_frame": 1,
        "ignored.feedback_id": 1,
        "late.superseded": 1,
        "late.out_of_order": 1,
    }
    assert (c.rx_total, c.rx_used, c.rx_rejected, c.rx_late, c.rx_ignored) == (13, 2, 6, 2, 3)
    assert _sum_classes(c, bridge.pending) == c.rx_total
    assert bridge.inputs["base_speed"] == 30.0 and bridge.inputs["load"] == pytest.approx(0.3)
    # the rig keeps answering; the status frames carry the counters and the latched flags
    for k in range(4, 200):
        if k % 10 == 0:
            peer.command(t=1.3 + k * 1e-3, base_speed=30.0, load=0.3)
        bridge.tick()
        if k == 99:
            first = status_of(peer, peer.drain())
            assert first["status.flag.cmd_rejected"] == 1 and first["status.flag.cmd_late"] == 1
            assert first["status.count.rx_rejected"] == 6 and first["status.count.rx_late"] == 2
            assert first["status.count.rx_ignored"] == 3
    msgs = peer.drain()
    status = status_of(peer, msgs)
    assert status["status.flag.cmd_rejected"] == 0 and status["status.flag.cmd_late"] == 0
    assert status["status.count.rx_used"] == c.rx_used == 2 + 19
    assert sum(1 for m in msgs if m.arbitration_id == 0x200) == 10
    speeds = [v["out.base_speed"] for n, v in peer.decoded(msgs) if n == "GearFbBase"]
    assert speeds[-1] == 30.0
    summary = bridge.close()
    assert (
        summary["rx_total"]
        == summary["rx_used"] + summary["rx_rejected"] + summary["rx_late"] + summary["rx_ignored"]
    )


def test_pending_commands_at_stop_count_as_late(link: tuple[Bridge, Peer]) -> None:
    bridge, peer = link
    peer.command(base_speed=1.0)
    bridge.poll()
    assert bridge.pending == 1
    summary = bridge.close()
    assert summary["reasons"] == {"late.after_stop": 1} and summary["rx_late"] == 1
    with pytest.raises(BridgeError):
        bridge.advance(1)


def test_command_timeout_safe_state_and_recovery(link: tuple[Bridge, Peer]) -> None:
    bridge, peer = link
    assert bridge.timeout_periods == 50
    bridge.tick()
    assert bridge.state == {
        "cmd_timeout": True,
        "safe_state": True,
        "drive_disabled": False,
        "fault_active": False,
    }
    assert bridge.counters.timeouts == 0  # no command yet is not a timeout event
    states = {}
    for k in range(1, 400):
        if k <= 90 and k % 10 == 0 or k >= 250 and k % 10 == 0:
            peer.command(t=k * 1e-3, base_speed=12.0, load=0.5)
        bridge.tick()
        states[k] = (
            bridge.state["cmd_timeout"],
            bridge.inputs["base_speed"],
            bridge.inputs["load"],
        )
    # last command handled at period 90: stale from period 90 + 50 + 1 on
    assert states[140] == (False, 12.0, 0.5)
    assert states[141] == (True, 0.0, 0.0)
    assert states[249] == (True, 0.0, 0.0)
    assert states[250] == (False, 12.0, 0.5)
    c = bridge.counters
    assert (c.timeouts, c.recoveries) == (1, 1)
    # the feedback shows it: base speed 0 in the safe state, flags in the status frame
    bridge2_msgs = peer.drain()
    decoded = peer.decoded(bridge2_msgs)
    status = [v for n, v in decoded if n == "GearStatus"]
    # status frames at 100, 200, 300, 400 ms (this test drained none before)
    assert [s["status.flag.cmd_timeout"] for s in status] == [0, 1, 0, 0]
    assert [s["status.flag.safe_state"] for s in status] == [0, 1, 0, 0]
    counters = [v for n, v in decoded if n == "GearCounters"]
    assert [s["status.count.timeouts"] for s in counters] == [0, 1, 1, 1]
    base = [v["out.base_speed"] for n, v in decoded if n == "GearFbBase"]
    assert base[13] == 12.0 and base[14] == 0.0 and base[24] == 0.0 and base[25] == 12.0


def test_disabled_mode_is_the_safe_state_without_timeout(link: tuple[Bridge, Peer]) -> None:
    bridge, peer = link
    peer.command(base_speed=8.0, load=0.2, mode="speed")
    bridge.tick()
    assert bridge.inputs["base_speed"] == 8.0
    peer.command(base_speed=8.0, load=0.2, mode="disabled")
    bridge.tick()
    assert bridge.state == {
        "cmd_timeout": False,
        "safe_state": True,
        "drive_disabled": True,
        "fault_active": False,
    }
    assert bridge.inputs == {"base_speed": 0.0, "base_torque": 0.0, "load": 0.0}
    assert bridge.counters.rx_used == 2 and bridge.counters.rx_rejected == 0


def test_saturated_feedback_is_clamped_and_flagged(channel: str, gear_dbc: RigDbc) -> None:
    from hil_helpers import gearsim

    model = gearsim.Model(
        block="simple_gear",
        block_params={"teeth_ratio": 0.1},
        rig_params={"follower_inertia": 0.05},
    )
    bus = can.Bus(interface="virtual", channel=channel)
    peer = Peer(channel, gear_dbc)
    try:
        bridge = Bridge.from_model(model, gear_dbc, bus=bus)
        for k in range(100):
            if k % 10 == 0:
                peer.command(base_speed=1000.0)
            bridge.tick()
        msgs = peer.drain()
        follower = [v["out.follower_speed"] for n, v in peer.decoded(msgs) if n == "GearFbFollower"]
        assert follower[-1] == pytest.approx(
            -8388.608
        )  # opposite rotation; clamped at the DBC maximum, not wrapped
        assert bridge.counters.saturated["GearFbFollower.FollowerSpeed"] == 10
        assert status_of(peer, msgs)["status.flag.fb_saturated"] == 1
    finally:
        peer.close()
        bus.shutdown()


def test_send_failures_are_counted(gear: Any, gear_dbc: RigDbc) -> None:
    sent: list[can.Message] = []

    def send(msg: can.Message) -> None:
        if msg.arbitration_id == 0x202:
            raise can.CanOperationError("transmit buffer full")
        sent.append(msg)

    bridge = Bridge.from_model(gear, gear_dbc, send=send, stamp=lambda t: t)
    bridge.advance(200)
    assert bridge.counters.tx_errors == 2
    status = [
        roles_by_cantools(gear_dbc.by_key[(m.arbitration_id, False)], m.data)
        for m in sent
        if m.arbitration_id == 0x210
    ]
    assert [s["status.flag.tx_error"] for s in status] == [1, 1]
    assert [m.timestamp for m in sent if m.arbitration_id == 0x210] == pytest.approx([0.1, 0.2])


def test_batched_and_single_periods_send_the_same_frames(gear: Any, gear_dbc: RigDbc) -> None:
    def session(chunked: bool) -> list[tuple[float, int, bytes]]:
        out: list[can.Message] = []
        bridge = Bridge.from_model(gear, gear_dbc, send=out.append, stamp=lambda t: t, timeout=0.2)
        cmds = [
            gear_dbc.encode_command({"cmd.base_speed": 5.0 * j, "cmd.load": 0.1 * j})[0]
            for j in range(8)
        ]
        for j, cmd in enumerate(cmds):
            bridge.handle(cmd)
            if chunked:
                bridge.advance(60 if j < 7 else 400)  # the last span crosses the timeout
            else:
                for _ in range(60 if j < 7 else 400):
                    bridge.advance(1)
        assert bridge.counters.timeouts == 1
        return [(m.timestamp, m.arbitration_id, bytes(m.data)) for m in out]

    assert session(True) == session(False)


def test_setup_errors(gear: Any, gear_dbc: RigDbc, rack_dbc: RigDbc) -> None:
    with pytest.raises(BridgeError, match="whole number of frame periods"):
        Bridge.from_model(gear, gear_dbc, period=3e-3)
    with pytest.raises(BridgeError, match="rack_pinion"):
        Bridge.from_model(gear, rack_dbc)
    with pytest.raises(BridgeError, match="substeps"):
        Bridge.from_model(gear, gear_dbc, substeps=0)
    with pytest.raises(BridgeError, match="timeout"):
        Bridge.from_model(gear, gear_dbc, timeout=0.0)
    with pytest.raises(BridgeError, match="needs a bus"):
        Bridge.from_model(gear, gear_dbc).run(duration=0.01)


def test_counters_are_the_c_bridges_own(gear: Any, gear_dbc: RigDbc) -> None:
    """Counters reads the C bridge's counters by the names of gearsim/hil.h's
    list (the one list, which the status frames use too): every name, in its
    order, each the C count."""
    from gearsim._lib import lib
    from gearsim.hil.names import STATUS_COUNTS

    assert Counters.NAMES == (*STATUS_COUNTS, "steps")
    assert STATUS_COUNTS[0] == "rx_total" and STATUS_COUNTS[-1] == "log_dropped"
    bridge = Bridge.from_model(gear, gear_dbc, period=1e-3, substeps=3)
    bridge.advance(250)
    counts = bridge._b.counters.count
    for i, name in enumerate(STATUS_COUNTS):
        assert getattr(bridge.counters, name) == counts[i], name
    assert bridge.counters.periods == counts[lib.GS_HIL_COUNT_PERIODS] == 250
    assert bridge.counters.steps == 750
    # 10 ms frames x 2 over 250 ms, 100 ms frames x 4 at 100 and 200 ms
    assert bridge.counters.tx_frames == 2 * 25 + 4 * 2

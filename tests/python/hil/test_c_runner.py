"""The C HIL runner gearsim-hil (hil/, docs/hil-runner.md) against the Python
bridge and against the rig stepped directly: replay identity, the codec frame
for frame against cantools, a live cross-process run on pipes, every fault
class, timeout and recovery, the SocketCAN failure path, bad parameter files.
Skipped when the runner is not built."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import pytest
from c_runner_helpers import (
    RUNNER,
    PipePeer,
    candump_line,
    command,
    needs_runner,
    read_log,
    run,
    summary,
    write_log,
)
from hil_helpers import can, gear_model, rack_model

from gearsim.hil import RigDbc, replay
from gearsim.hil import runner as runner_mod

pytestmark = needs_runner

T0 = 1_700_000_000.0  # epoch-like log time base, as a bench recording has


@pytest.fixture
def gear_params(tmp_path: Path) -> Path:
    return runner_mod.write_params(gear_model(), tmp_path / "gear.params")


def faulty_gear_log(dbc: RigDbc) -> list[Any]:
    """A speed profile every 10 ms with every fault class once, a 0.25 s gap
    (timeout) and a disabled span."""
    msgs: list[Any] = []
    for k in range(260):
        if 120 <= k < 145:
            continue  # no command for 250 ms: timeout, then recovery
        t = T0 + k * 0.01 + 0.0003 * (k % 4)
        speed = 20.0 * math.sin(2 * math.pi * 0.7 * k * 0.01)
        mode = "disabled" if 160 <= k < 170 else "speed"
        msgs += command(dbc, t, base_speed=speed, load=0.3 * math.cos(k / 9), mode=mode)
        if k == 30:  # superseded: a second command before the next period boundary
            msgs += command(dbc, t + 0.0001, base_speed=5.0, load=0.1)
    std = dict(is_extended_id=False)
    faults = [
        can.Message(arbitration_id=0x123, data=b"\x01\x02", **std),  # unknown_id
        can.Message(arbitration_id=0x100, data=b"\x01\x02\x03\x04", **std),  # bad_length
        can.Message(
            arbitration_id=0x100, data=bytes([0, 0, 0, 0, 0, 0, 0, 3]), **std
        ),  # undecodable
        can.Message(
            arbitration_id=0x100, data=bytes([0xFF, 0xFF, 0x7F, 0, 0, 0, 0, 1]), **std
        ),  # out_of_range
        can.Message(
            arbitration_id=0x100, data=bytes([0, 0, 0, 0, 0, 0, 0, 2]), **std
        ),  # mode_mismatch
        can.Message(arbitration_id=0x200, data=bytes(8), **std),  # feedback_id
        can.Message(arbitration_id=0x100, is_remote_frame=True, **std),  # remote_frame
        can.Message(is_error_frame=True),  # error_frame
        can.Message(
            arbitration_id=0x100, data=bytes(8), is_extended_id=True
        ),  # unknown_id (29-bit)
    ]
    for i, m in enumerate(faults):
        m.timestamp = T0 + 0.5 + i * 0.0307
        msgs.append(m)
    msgs.sort(key=lambda m: m.timestamp)
    # out of order: in file order after a command, stamped before it
    at = next(i for i, m in enumerate(msgs) if m.timestamp >= T0 + 0.40)
    msgs[at + 1 : at + 1] = command(dbc, msgs[at].timestamp - 0.005, base_speed=1.0)
    return msgs


def assert_same_answers(c_log: Path, py_log: Path) -> int:
    c_msgs, py_msgs = read_log(c_log), read_log(py_log)
    assert len(c_msgs) == len(py_msgs) > 0
    for c, p in zip(c_msgs, py_msgs, strict=True):
        assert (c.arbitration_id, c.is_extended_id, bytes(c.data)) == (
            p.arbitration_id,
            p.is_extended_id,
            bytes(p.data),
        )
        assert c.timestamp == pytest.approx(p.timestamp, abs=1.5e-6)
    return len(c_msgs)


COMPARED = (
    "rx_total rx_used rx_rejected rx_late rx_ignored tx_frames tx_errors timeouts recoveries "
    "saturations periods steps pending reasons state"
).split()


def replay_both(tmp_path: Path, model: Any, log: Path, **opts: Any) -> tuple[dict, dict]:
    params = runner_mod.write_params(model, tmp_path / "model.params")
    c_out, py_out = tmp_path / "c.log", tmp_path / "py.log"
    res = run(runner_mod.replay_command(params, log, c_out, runner=RUNNER, **opts))
    assert res.returncode == 0, res.stderr
    py = replay(model, log, py_out, **opts)
    assert_same_answers(c_out, py_out)
    return summary(res.stderr), py.summary


def test_replay_is_bit_identical_to_the_python_bridge(tmp_path: Path) -> None:
    dbc = RigDbc(block="gear")
    log = write_log(tmp_path / "in.log", faulty_gear_log(dbc))
    c, py = replay_both(tmp_path, gear_model(), log, tail=0.3)
    for key in COMPARED:
        assert c[key] == py[key], key
    # the log exercises what it should: every class but after_stop, a timeout
    assert set(c["reasons"]) == {
        "rejected.unknown_id",
        "rejected.bad_length",
        "rejected.undecodable",
        "rejected.out_of_range",
        "rejected.mode_mismatch",
        "late.superseded",
        "late.out_of_order",
        "ignored.feedback_id",
        "ignored.remote_frame",
        "ignored.error_frame",
    }
    assert c["reasons"]["rejected.unknown_id"] == 2
    assert (
        c["timeouts"] == 2 and c["recoveries"] == 1
    )  # the gap, then the tail after the last command


def test_replay_identity_rack_torque_driven_with_substeps(tmp_path: Path) -> None:
    """Torque-driven rack, 2 sub-steps, 2 ms period: another DBC, drive and
    time base; full motor torque for 0.4 s drives the rack past the 83.9 m/s
    of RackVelocity (saturated and flagged, both alike)."""
    model = rack_model(base_drive="torque", base_inertia=1e-3)
    dbc = RigDbc(block="rack")
    msgs = []
    for k in range(150):
        torque = 30.0 if 40 <= k < 80 else -30.0 if 80 <= k < 120 else 2.0 * math.sin(k / 7.0)
        msgs += command(
            dbc, T0 + k * 0.01, base_torque=torque, load=-40.0 * math.cos(k / 11.0), mode="torque"
        )
    log = write_log(tmp_path / "rack.log", msgs)
    c, py = replay_both(tmp_path, model, log, period=2e-3, substeps=2, timeout=0.05)
    for key in COMPARED:
        assert c[key] == py[key], key
    assert c["rx_used"] == 150 and c["steps"] == 2 * c["periods"]
    assert c["saturations"] > 0


def test_feedback_bytes_are_cantools_encoding_of_the_rig(tmp_path: Path) -> None:
    """Frame for frame: each answer of a replay decoded with cantools equals
    the Python Rig stepped directly with the held command, within the DBC's
    quantisation (the period is the feedback cycle, so every period answers)."""
    model = gear_model()
    dbc = RigDbc(block="gear")
    speeds = [3.0 * k - 0.5 * k * k / 10 for k in range(40)]
    msgs = []
    for k, s in enumerate(speeds):
        msgs += command(dbc, T0 + k * 0.01, base_speed=round(s, 3), load=round(0.1 * (k % 5), 3))
    log = write_log(tmp_path / "in.log", msgs)
    params = runner_mod.write_params(model, tmp_path / "m.params")
    out = tmp_path / "c.log"
    res = run(runner_mod.replay_command(params, log, out, period=0.01, substeps=10, runner=RUNNER))
    assert res.returncode == 0, res.stderr
    rig = model.rig(dt=1e-3)
    answers = [m for m in read_log(out) if m.arbitration_id in (0x200, 0x201)]
    base = [
        dbc.database.decode_message(0x200, m.data) for m in answers if m.arbitration_id == 0x200
    ]
    follower = [
        dbc.database.decode_message(0x201, m.data) for m in answers if m.arbitration_id == 0x201
    ]
    assert len(base) == len(follower) == len(speeds)
    for k, s in enumerate(speeds):
        for _ in range(10):
            r = rig.step(base_speed=round(s, 3), load=round(0.1 * (k % 5), 3))
        assert base[k]["BaseSpeed"] == pytest.approx(round(s, 3), abs=5e-4)
        assert base[k]["LoadTorque"] == pytest.approx(round(0.1 * (k % 5), 3), abs=5e-4)
        assert base[k]["BaseTorque"] == pytest.approx(r.base_torque, abs=0.5e-4 + 1e-9)
        assert follower[k]["FollowerSpeed"] == pytest.approx(r.follower_speed, abs=0.5e-3 + 1e-9)
        angle = math.fmod(r.follower_position, 2 * math.pi) % (2 * math.pi)
        assert follower[k]["FollowerAngle"] == pytest.approx(angle, abs=0.5e-6 + 1e-9)


def test_live_pipe_run_matches_the_rig_stepped_directly(tmp_path: Path, gear_params: Path) -> None:
    """A pipe peer drives a live runner (10 ms periods, 10 sub-steps): each
    period's feedback, decoded with cantools, carries the input it applied
    (BaseSpeed, LoadTorque) and the outputs; a Python Rig fed those inputs
    gives the same outputs."""
    dbc = RigDbc(block="gear")
    peer = PipePeer(gear_params, "--spin-us", "0", period=0.01, substeps=10, timeout=0.1)
    try:
        for k in range(40):
            lines = [
                candump_line(m)
                for m in command(dbc, time.time(), base_speed=0.5 * k, load=0.05 * (k % 4))
            ]
            peer.send(lines)
            peer.collect(0.02)
        rc, result, err = peer.stop()
    finally:
        peer.kill()
    assert rc == 0, err
    assert result["rx_total"] == 40 and result["rx_used"] + result["rx_late"] == 40
    msgs = peer.messages()
    base = [dbc.database.decode_message(0x200, m.data) for m in msgs if m.arbitration_id == 0x200]
    follower = [
        dbc.database.decode_message(0x201, m.data) for m in msgs if m.arbitration_id == 0x201
    ]
    assert len(base) == len(follower) == result["periods"] >= 60
    rig = gear_model().rig(dt=1e-3)
    moving = 0
    for b, f in zip(base, follower, strict=True):
        for _ in range(10):
            r = rig.step(base_speed=b["BaseSpeed"], load=b["LoadTorque"])
        assert b["BaseTorque"] == pytest.approx(r.base_torque, abs=0.5e-4 + 1e-9)
        assert f["FollowerSpeed"] == pytest.approx(r.follower_speed, abs=0.5e-3 + 1e-9)
        moving += abs(r.follower_speed) > 1.0
    assert moving > 20  # the rig really moved under the peer's commands


def test_live_fault_classes_are_counted_and_the_rig_keeps_answering(gear_params: Path) -> None:
    dbc = RigDbc(block="gear")
    good = lambda: [candump_line(m) for m in command(dbc, time.time(), base_speed=4.0)]  # noqa: E731
    bad = [
        "(0.0) can0 123#0102\n",  # unknown_id
        "(0.0) can0 100#01020304\n",  # bad_length
        "(0.0) can0 100#0000000000000003\n",  # undecodable (DriveMode 3)
        "(0.0) can0 100#FFFF7F0000000001\n",  # out_of_range (BaseSpeedCmd 8388.607)
        "(0.0) can0 100#0000000000000002\n",  # mode_mismatch (Torque on a speed rig)
        "(0.0) can0 200#0000000000000000\n",  # feedback_id
        "(0.0) can0 100#R\n",  # remote_frame
        "(0.0) can0 200000FF#\n",  # error_frame
        "this is not a frame\n",  # malformed line
    ]
    peer = PipePeer(gear_params, timeout=0.1)
    try:
        for _ in range(10):
            peer.send(good())
            peer.collect(0.01)
        peer.send(bad + good() + good())  # the last two in one period: superseded
        before = len(peer.lines)
        for _ in range(20):
            peer.send(good())
            peer.collect(0.01)
        answered_after = len(peer.lines) - before
        rc, result, err = peer.stop()
    finally:
        peer.kill()
    assert rc == 0, err
    reasons = result["reasons"]
    for key in (
        "rejected.unknown_id",
        "rejected.bad_length",
        "rejected.undecodable",
        "rejected.out_of_range",
        "rejected.mode_mismatch",
        "ignored.feedback_id",
        "ignored.remote_frame",
        "ignored.error_frame",
    ):
        assert reasons.get(key) == 1, key
    assert reasons.get("late.superseded", 0) >= 1
    assert result["malformed_lines"] == 1
    total = result["rx_used"] + result["rx_rejected"] + result["rx_late"] + result["rx_ignored"]
    assert total == result["rx_total"] == 8 + 32  # 8 bad frames, 32 commands; nothing pending
    assert answered_after >= 20  # feedback kept coming after the bad frames
    status = [
        dbc.database.decode_message(0x210, m.data)
        for m in peer.messages()
        if m.arbitration_id == 0x210
    ]
    assert any(s["CmdRejected"] == 1 for s in status)
    assert status[-1]["RxRejected"] == 5


def test_live_timeout_enters_the_safe_state_and_recovers(gear_params: Path) -> None:
    dbc = RigDbc(block="gear")
    peer = PipePeer(gear_params, "--spin-us", "0", period=0.01, timeout=0.05)
    phases = []
    try:
        for count, send in [(25, True), (35, False), (25, True)]:
            start = len(peer.lines)
            for _ in range(count):
                if send:
                    peer.send([candump_line(m) for m in command(dbc, time.time(), base_speed=7.0)])
                peer.collect(0.01)
            phases.append((start, len(peer.lines)))
        rc, result, err = peer.stop()
    finally:
        peer.kill()
    assert rc == 0, err
    assert result["timeouts"] >= 1 and result["recoveries"] >= 1
    decoded = peer.decoded(dbc)  # (frame ID, values), in the order received

    def statuses(lo: int, hi: int) -> list[dict[str, Any]]:
        return [values for ident, values in decoded[lo:hi] if ident == 0x210]

    def speeds(lo: int, hi: int) -> list[float]:
        return [values["BaseSpeed"] for ident, values in decoded[lo:hi] if ident == 0x200]

    on1, off, on2 = phases
    assert speeds(*on1)[-1] == pytest.approx(7.0)
    # silent phase: after the timeout, the safe state holds the base at 0 rad/s
    quiet = statuses(*off)[1:]
    assert quiet and all(s["CmdTimeout"] == 1 and s["SafeState"] == 1 for s in quiet)
    assert speeds(*off)[-1] == 0.0
    # commands back: normal again
    assert statuses(*on2)[-1]["CmdTimeout"] == 0 and statuses(*on2)[-1]["SafeState"] == 0
    assert speeds(*on2)[-1] == pytest.approx(7.0)


def test_socketcan_failure_is_one_line_and_exit_2(gear_params: Path) -> None:
    """This kernel has no AF_CAN (socket() fails); where it has one, the
    interface does not exist. Both: exit 2, one line naming the channel."""
    cmd = runner_mod.live_command(
        gear_params, transport="socketcan", channel="gsnone0", runner=RUNNER
    )
    res = run(cmd, timeout=20)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "--channel gsnone0" in lines[0]
    assert "SocketCAN" in lines[0] or "no such CAN interface" in lines[0]


@pytest.mark.parametrize(
    "body, expected",
    [
        (
            "block = simple_gear\nblock.teeth_ratio = two\n",
            ":2: block.teeth_ratio: not a finite number",
        ),
        ("block = simple_gear\nblock.gear_ratio = 2\n", ":2: block.gear_ratio: unknown key"),
        (
            "block = simple_gear\nblock.friction_model = GS_FRICTION_MAGIC\n",
            ":2: block.friction_model: unknown option",
        ),
        ("block = simple_gear\n\nrig.dt_s = 0.001\n", ":3: rig.dt_s: the step is set by --period"),
        ("block.teeth_ratio = 2\n", ":1: block.teeth_ratio: comes before the 'block"),
        (
            "block = simple_gear\nrig.driven_inertia = 1\nrig.driven_inertia = 2\n",
            ":3: rig.driven_inertia: given twice",
        ),
        ("block = simple_gear\nblock.teeth_ratio = -2\n", ": teeth_ratio: "),
        ("block = worm_gear\n", ":1: block: must be simple_gear or rack_pinion"),
        ("# nothing\n", ": no 'block = simple_gear|rack_pinion' line"),
    ],
)
def test_bad_parameter_file_is_one_line_and_exit_2(
    tmp_path: Path, body: str, expected: str
) -> None:
    path = tmp_path / "bad.params"
    path.write_text(body)
    res = run(runner_mod.replay_command(path, tmp_path / "none.log", runner=RUNNER))
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert str(path) in lines[0] and expected in lines[0]


def test_bad_options_and_outputs_are_refused(tmp_path: Path, gear_params: Path) -> None:
    log = write_log(tmp_path / "in.log", command(RigDbc(block="gear"), T0, base_speed=1.0))
    cases = [
        (["--period", "-1"], "--period -1"),
        (["--period", "0.003"], "--period: feedback frame GearFbBase: cycle time 10 ms"),
        (["--replay", str(log), "-o", str(log)], "is an input of the command"),
        (["--replay", str(log), "-o", str(tmp_path / "out.blf")], "candump .log"),
        (["--fifo", "100"], "--fifo 100"),
    ]
    for args, expected in cases:
        res = run([str(RUNNER), "--params", str(gear_params), *args], timeout=20)
        assert res.returncode == 2, args
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and expected in lines[0], (args, res.stderr)
    assert log.read_text().count("#") == 1  # the input was not overwritten


def test_parameter_file_covers_every_key_the_runner_reads(tmp_path: Path) -> None:
    res = run([str(RUNNER), "--list-params"])
    assert res.returncode == 0
    accepted: dict[str, set[str]] = {}
    for line in res.stdout.splitlines():
        group, key = line.split()
        accepted.setdefault(group, set()).add(key)
    for model in (gear_model(), rack_model()):
        text = runner_mod.params_text(model)
        keys = {
            line.split(" = ")[0]
            for line in text.splitlines()
            if " = " in line and not line.startswith("#")
        }
        block = model.block
        expected = accepted[block] | accepted["rig"] | accepted["run"] | {"block"}
        assert keys == expected

"""A HIL test campaign (docs/hil.md, "Test campaigns"): fault injection,
scenarios with their JUnit verdict, rig parameters changed at run time, the
C runner's own recording, its socketcand server with python-can's own client.

The controller emulators here are Python on python-can buses (the virtual
bus with the Python bridge, python-can's socketcand client with the C
runner); the feedback they receive is decoded with cantools, independently
of the C encoder."""

from __future__ import annotations

import json
import math
import re
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from c_runner_helpers import RUNNER, command, needs_runner, read_log, run, summary, write_log
from hil_helpers import Bridge, Peer, RigDbc, can, gear_model, next_channel, roles_by_cantools

from gearsim.hil import replay
from gearsim.hil import runner as runner_mod
from gearsim.hil.names import FAULTS, tunable_parameters

HERE = Path(__file__).resolve().parent
WINDOW = (0.1, 0.25)  # s: periods 100..249, the frames stamped (0.1, 0.25]
PERIODS = 300


def speed_at(k: int) -> float:
    """The emulator's speed command of period k (every 10 ms): a ramp, so that
    every feedback frame carries another base speed."""
    return 10.0 + 0.01 * (k // 10) * 10


def write_scenario(path: Path, *steps: str, duration: float = 0.3, name: str = "campaign") -> Path:
    text = f'[scenario]\nname = "{name}"\nduration = {duration}\n'
    text += "".join(f"\n[[step]]\n{step.strip()}\n" for step in steps)
    path.write_text(text)
    return path


def session(scenario: Path | None, periods: int = PERIODS) -> tuple[list[Any], dict, Bridge]:
    """The Python bridge and a controller emulator on a virtual bus: the
    emulator commands speed_at(k) every 10 ms and collects the feedback
    (stamped with simulated time)."""
    dbc = RigDbc(block="gear")
    channel = next_channel("campaign")
    bus = can.Bus(interface="virtual", channel=channel, preserve_timestamps=True)
    peer = Peer(channel, dbc)
    try:
        bridge = Bridge.from_model(
            gear_model(), dbc, timeout=0.05, bus=bus, stamp=lambda t: t, scenario=scenario
        )
        got: list[Any] = []
        for k in range(periods):
            if k % 10 == 0:
                peer.command(t=k * 1e-3, base_speed=speed_at(k), mode="speed")
            bridge.tick()
            got += peer.drain()
        out = bridge.close()
    finally:
        peer.close()
        bus.shutdown()
    return got, out, bridge


_REFERENCE: list[Any] = []


def reference() -> list[Any]:
    if not _REFERENCE:
        _REFERENCE.extend(session(None)[0])
    return _REFERENCE


def frames(msgs: list[Any], frame_id: int) -> dict[float, list[Any]]:
    """Messages of one ID by their stamp (ms rounded), in order."""
    out: dict[float, list[Any]] = {}
    for m in msgs:
        if m.arbitration_id == frame_id:
            out.setdefault(round(m.timestamp, 6), []).append(m)
    return out


def value(dbc: RigDbc, m: Any, role: str) -> float:
    frame = dbc.by_key[(m.arbitration_id, False)]
    return roles_by_cantools(frame, m.data)[role]


def inside(t: float) -> bool:
    return WINDOW[0] < t <= WINDOW[1] + 1e-9


FAULT_STEPS = {
    "offset": ('signal = "BaseSpeed"\nvalue = 0.5', 0x200),
    "gain": ('signal = "BaseSpeed"\nvalue = 2.0', 0x200),
    "noise": ('signal = "BaseSpeed"\nvalue = 0.2\nseed = 11', 0x200),
    "freeze": ('signal = "BaseSpeed"', 0x200),
    "stuck": ('signal = "BaseSpeed"\nvalue = 3.0', 0x200),
    "dropout": ('signal = "BaseSpeed"', 0x200),
    "delay": ('signal = "BaseSpeed"\nperiods = 20', 0x200),
    "quantise": ('signal = "BaseSpeed"\nvalue = 0.5', 0x200),
    "clamp": ('signal = "BaseSpeed"\nmax = 10.6', 0x200),
    "drop": ('frame = "GearFbFollower"', 0x201),
    "duplicate": ('frame = "GearFbFollower"', 0x201),
    "corrupt": ('frame = "GearFbBase"\nbits = 2', 0x200),
    "counter_stop": ('frame = "GearStatus"', 0x210),
}


def test_every_fault_class_has_a_test() -> None:
    assert set(FAULT_STEPS) == set(FAULTS)


def _check_window(kind: str, ref: dict, got: dict, dbc: RigDbc) -> None:
    """The faulted frames inside the window, as the fault class says."""
    stamps = sorted(set(ref) | set(got))
    before = [t for t in stamps if t <= WINDOW[0] + 1e-9]
    for t in [t for t in stamps if inside(t)]:
        r, g = ref[t], got.get(t, [])
        if kind in ("dropout", "drop"):
            assert g == [], t
            continue
        if kind == "duplicate":
            assert len(g) == 2 and all(bytes(m.data) == bytes(r[0].data) for m in g), t
            continue
        if kind == "counter_stop":
            assert value(dbc, g[0], "status.counter") == value(
                dbc, ref[before[-1]][0], "status.counter"
            )
            assert value(dbc, g[0], "status.flag.fault_active") == 1.0
            continue
        if kind == "corrupt":
            flipped = sum(bin(a ^ b).count("1") for a, b in zip(g[0].data, r[0].data, strict=False))
            assert flipped == 2, t
            continue
        x, want = value(dbc, g[0], "out.base_speed"), value(dbc, r[0], "out.base_speed")
        expected = {
            "offset": want + 0.5,
            "gain": 2.0 * want,
            "freeze": value(dbc, ref[before[-1]][0], "out.base_speed"),
            "stuck": 3.0,
            "delay": value(dbc, ref[round(t - 0.02, 6)][0], "out.base_speed"),
            "quantise": round(want / 0.5) * 0.5,
            "clamp": min(want, 10.6),
        }.get(kind)
        if expected is None:  # noise: differs, seeded (checked below)
            continue
        assert x == pytest.approx(expected, abs=1.1e-3), (kind, t)


@pytest.mark.parametrize("kind", sorted(FAULT_STEPS))
def test_fault_applied_counted_flagged_and_cleared(tmp_path: Path, kind: str) -> None:
    """A controller emulator sees the fault in exactly the frames of the
    periods the scenario puts it on, and the reference frames everywhere else;
    it is counted and flagged in the status frame; it never touches the rig."""
    target, frame_id = FAULT_STEPS[kind]
    scenario = write_scenario(
        tmp_path / "s.toml", f'at = {WINDOW[0]}\nfault = "{kind}"\n{target}\nuntil = {WINDOW[1]}'
    )
    got, out, bridge = session(scenario)
    dbc = RigDbc(block="gear")
    ref_all, got_all = reference(), got
    ref, faulted = frames(ref_all, frame_id), frames(got_all, frame_id)
    # outside the window: every frame of every ID as without the fault
    for fid in {m.arbitration_id for m in ref_all}:
        r, g = frames(ref_all, fid), frames(got_all, fid)
        for t in r:
            if not inside(t) and fid not in (0x210, 0x211, 0x212):
                assert [bytes(m.data) for m in g.get(t, [])] == [bytes(m.data) for m in r[t]], (
                    fid,
                    t,
                )
    _check_window(kind, ref, faulted, dbc)
    if kind == "noise":
        noisy = [
            value(dbc, faulted[t][0], "out.base_speed") - value(dbc, ref[t][0], "out.base_speed")
            for t in faulted
            if inside(t)
        ]
        assert max(abs(d) for d in noisy) > 0.05
        assert [bytes(m.data) for m in session(scenario)[0]] == [bytes(m.data) for m in got]
    # counted: a frame or a value per frame the window covers
    per_window = {0x200: 15, 0x201: 15, 0x210: 1}[frame_id]
    assert out["faults"] == per_window
    # flagged: the status frames of 0.1 and 0.3 s say no fault, that of 0.2 s a fault
    status = {
        t: value(dbc, m[0], "status.flag.fault_active") for t, m in frames(got, 0x210).items()
    }
    assert status == {0.1: 0.0, 0.2: 1.0, 0.3: 0.0}
    assert out["state"]["fault_active"] is False  # cleared at its end
    # the model's outputs are those of the reference run
    assert bridge.last_output == session(None, PERIODS)[2].last_output


@needs_runner
def test_c_runner_applies_the_faults_as_the_python_bridge(tmp_path: Path) -> None:
    """One scenario with several faults, a trigger, a load profile and a
    parameter change, replayed by the C runner and by the Python bridge on
    the same log: the same bytes and the same verdict (one library)."""
    dbc = RigDbc(block="gear")
    log = write_log(
        tmp_path / "host.log",
        [
            m
            for k in range(0, 600, 10)
            for m in command(dbc, 1.7e9 + k * 1e-3, base_speed=speed_at(k))
        ],
    )
    scenario = write_scenario(
        tmp_path / "s.toml",
        'at = 0.05\nfault = "noise"\nsignal = "FollowerSpeed"\nvalue = 0.3\nduration = 0.2',
        'at = 0.1\nfault = "stuck"\nsignal = "BaseSpeed"\nvalue = 0\n'
        'when = "BaseSpeed > 10.25"\nduration = 0.05',
        'at = 0.2\nfault = "duplicate"\nframe = "GearFbThermal"\nuntil = 0.4',
        "at = 0.3\nload = 0.2\nover = 0.1",
        'at = 0.35\nparam = "load_coulomb_friction"\nvalue = 0.05',
        'at = 0.4\nexpect = "BaseSpeedCmd"\nmin = 13.95\nmax = 14.95\nuntil = 0.5',
        'at = 0.45\nexpect = "safe_state"\nequals = true',
        duration=0.7,
    )
    params = runner_mod.write_params(gear_model(), tmp_path / "gear.params")
    c_out, c_xml = tmp_path / "c.log", tmp_path / "c.xml"
    res = run(
        [
            *runner_mod.replay_command(params, log, c_out, runner=RUNNER),
            "--scenario",
            str(scenario),
            "--junit",
            str(c_xml),
        ]
    )
    assert res.returncode == 3, res.stderr  # safe_state at 0.45 s: the emulator is still commanding
    py = replay(
        gear_model(), log, tmp_path / "py.log", scenario=scenario, junit=tmp_path / "py.xml"
    )
    c_msgs, py_msgs = read_log(c_out), read_log(tmp_path / "py.log")
    assert [(m.arbitration_id, bytes(m.data)) for m in c_msgs] == [
        (m.arbitration_id, bytes(m.data)) for m in py_msgs
    ]
    assert c_xml.read_text() == (tmp_path / "py.xml").read_text() == py.junit
    c = summary(res.stderr)
    assert c["verdict"] == py.summary["verdict"] == {"passed": 1, "failed": 1}
    assert c["faults"] == py.summary["faults"] > 0 and c["param_changes"] == 1
    # 700 periods: 10 ms frames x 2, 100 ms frames x 4, GearFbThermal twice more
    # (0.3 and 0.4 s, duplicated), one acknowledgement of the parameter change
    assert len(c_msgs) == 70 * 2 + 7 * 4 + 2 + 1


# -- scenarios and verdicts -----------------------------------------------------------


STUCK_SENSOR = (
    'at = 0.2\nexpect = "DriveMode"\nequals = "speed"\nuntil = 0.3\n'
    'name = "drives before the fault"',
    'at = 0.3\nfault = "stuck"\nsignal = "BaseSpeed"\nvalue = 0.0',
    'at = 0.3\nexpect = "DriveMode"\nequals = "disabled"\nwithin = 0.1\n'
    'name = "disables within 100 ms of a stuck speed sensor"',
)


class Controller:
    """A controller under test: commands 10 rad/s every 10 ms; a good one
    disables the drive after two feedback frames whose base speed is off by
    more than 1 rad/s (a sensor fault)."""

    def __init__(self, dbc: RigDbc, good: bool) -> None:
        self.dbc, self.good, self.bad_frames, self.disabled = dbc, good, 0, False

    def feedback(self, m: Any) -> None:
        frame = self.dbc.by_key.get((m.arbitration_id, bool(m.is_extended_id)))
        if frame is None or frame.name != "GearFbBase":
            return
        speed = roles_by_cantools(frame, m.data)["out.base_speed"]
        self.bad_frames = self.bad_frames + 1 if abs(speed - 10.0) > 1.0 else 0
        if self.good and self.bad_frames >= 2:
            self.disabled = True

    def commands(self) -> list[Any]:
        return self.dbc.encode_command(
            {
                "cmd.base_speed": 0.0 if self.disabled else 10.0,
                "cmd.mode": "disabled" if self.disabled else "speed",
            }
        )


def _validate(xml: str) -> Any:
    xmlschema = pytest.importorskip("xmlschema")
    schema = xmlschema.XMLSchema(str(HERE / "junit.xsd"))
    schema.validate(xml)
    import xml.etree.ElementTree as ET

    return ET.fromstring(xml)


@pytest.mark.parametrize("good", [True, False], ids=["passing", "failing"])
def test_verdict_of_a_controller_emulator(tmp_path: Path, good: bool) -> None:
    scenario = write_scenario(tmp_path / "s.toml", *STUCK_SENSOR, duration=0.6, name="stuck sensor")
    dbc = RigDbc(block="gear")
    channel = next_channel("verdict")
    bus = can.Bus(interface="virtual", channel=channel)
    host = can.Bus(interface="virtual", channel=channel)
    ctl = Controller(dbc, good)
    try:
        bridge = Bridge.from_model(gear_model(), dbc, timeout=0.05, bus=bus, scenario=scenario)
        for k in range(600):
            if k % 10 == 0:
                for m in ctl.commands():
                    host.send(m)
            bridge.tick()
            while (m := host.recv(timeout=0.0)) is not None:
                ctl.feedback(m)
        bridge.close()
    finally:
        host.shutdown()
        bus.shutdown()
    root = _validate(bridge.junit())
    cases = {c.get("name"): c.find("failure") for c in root.iter("testcase")}
    assert set(cases) == {
        "drives before the fault",
        "disables within 100 ms of a stuck speed sensor",
    }
    assert cases["drives before the fault"] is None
    if good:
        assert cases["disables within 100 ms of a stuck speed sensor"] is None
        assert root.get("failures") == "0" and bridge.verdict()["passed"] == 2
    else:
        failure = cases["disables within 100 ms of a stuck speed sensor"]
        assert failure is not None and failure.get("type") == "expectation"
        assert "never DriveMode == disabled from 0.3 s to 0.4 s (last: 1)" in failure.get("message")
        assert root.get("failures") == "1"


def _socketcand_runner(tmp_path: Path, *args: str) -> tuple[subprocess.Popen, int]:
    params = runner_mod.write_params(gear_model(), tmp_path / "gear.params")
    cmd = runner_mod.live_command(
        params, transport="socketcand", listen="127.0.0.1:0", timeout=0.05, runner=RUNNER
    )
    proc = subprocess.Popen([*cmd, *args], stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()
    found = re.search(r"socketcand on 127\.0\.0\.1:(\d+)", line)
    if found is None:
        proc.kill()
        pytest.fail(f"no socketcand address: {line!r} {proc.communicate()[1]}")
    return proc, int(found.group(1))


def _drive(bus: Any, ctl: Controller, seconds: float, sent: list[int]) -> None:
    end = time.monotonic() + seconds
    next_t = time.monotonic()
    while time.monotonic() < end:
        if time.monotonic() >= next_t:
            for m in ctl.commands():
                bus.send(m)
                sent[0] += 1
            next_t += 0.01
        m = bus.recv(timeout=max(0.0, min(0.005, next_t - time.monotonic())))
        if m is not None:
            ctl.feedback(m)


@needs_runner
@pytest.mark.parametrize("good", [True, False], ids=["passing", "failing"])
def test_live_c_runner_verdict_over_socketcand(tmp_path: Path, good: bool) -> None:
    """The same campaign live: the C runner paced at 1 kHz, the emulator in
    this process on python-can's socketcand client, no kernel CAN."""
    scenario = write_scenario(tmp_path / "s.toml", *STUCK_SENSOR, duration=0.8, name="stuck sensor")
    xml = tmp_path / "verdict.xml"
    proc, port = _socketcand_runner(
        tmp_path, "--scenario", str(scenario), "--junit", str(xml), "--duration", "3600"
    )
    dbc = RigDbc(block="gear")
    ctl = Controller(dbc, good)
    sent = [0]
    try:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0")
        try:
            _drive(bus, ctl, 0.75, sent)
        finally:
            bus.shutdown()
        proc.send_signal(2)
        err = proc.communicate(timeout=20)[1]
    finally:
        if proc.poll() is None:
            proc.kill()
    s = summary(err)
    root = _validate(xml.read_text())
    failures = int(root.get("failures"))
    # the live run's timing is the machine's: the window of 100 ms holds
    # several frames of 10 ms, so a reacting controller passes
    assert failures == (0 if good else 1), xml.read_text()
    assert proc.returncode == (0 if good else 3)
    assert s["frames_in"] == sent[0] and s["client_connects"] == 1


# -- parameters at run time ------------------------------------------------------------


def test_parameter_change_continues_as_a_rig_with_the_new_parameters() -> None:
    """From the period after the request on, the outputs are those of a rig
    built with the new parameters and the state at that boundary; at constant
    speed the base torque is, by hand, F_C tanh(4 w_F / v_th) / (g eta)
    (ideal rigid mesh, docs/physics.md 11): 0.02 -> 0.05 N*m of Coulomb
    friction on the follower, g = 3, eta = 0.95."""
    model = gear_model()
    dbc = RigDbc(block="gear")
    bridge = Bridge.from_model(model, dbc, timeout=1.0, send=lambda m: None)
    cmd = dbc.encode_command({"cmd.base_speed": 10.0, "cmd.mode": "speed"})
    for k in range(300):
        for m in cmd:
            m.timestamp = k * 1e-3
            bridge.handle(m)
        if k == 200:
            assert bridge.request_param("load_coulomb_friction", 0.05) == "pending"
        bridge.advance(1)
        if k == 200:
            old = bridge.last_output["base_torque"]
            snap = bridge.rig.snapshot()
            new_rig = gear_model(load_coulomb_friction=0.05).rig(dt=1e-3)
            new_rig.restore(snap)
        if k > 200:
            expected = new_rig.step(base_speed=10.0, ambient_temperature=293.15)
            assert (
                bridge.last_output == expected.as_dict() if hasattr(expected, "as_dict") else True
            )
            assert bridge.last_output["base_torque"] == expected.base_torque
    w_f, v_th = 10.0 / 3.0, 0.001
    hand_old = 0.02 * math.tanh(4 * w_f / v_th) / (3 * 0.95)
    hand_new = 0.05 * math.tanh(4 * w_f / v_th) / (3 * 0.95)
    assert old == pytest.approx(hand_old, rel=1e-12)
    assert bridge.last_output["base_torque"] == pytest.approx(hand_new, rel=1e-12)
    assert bridge.counters.param_changes == 1
    assert bridge.rig_params.rig.load_coulomb_friction == 0.05


def test_parameter_frames_refused_are_counted_and_acknowledged() -> None:
    dbc = RigDbc(block="gear")
    acks: list[Any] = []
    bridge = Bridge.from_model(gear_model(), dbc, send=acks.append)
    keys = tunable_parameters("simple_gear")
    assert "load_coulomb_friction" in keys and "teeth_ratio" not in keys
    bad = dbc.encode_param("load_coulomb_friction", -1.0)  # the rig's init refuses < 0
    assert bridge.handle(bad) == "pending"
    unknown = can.Message(
        arbitration_id=dbc.param_frame.frame_id,
        data=bytes([200, 0, 0, 0, 0, 0, 0, 0]),
        is_extended_id=False,
    )
    assert bridge.handle(unknown) == "rejected.bad_param"
    bridge.advance(2)
    out = bridge.close()
    assert out["param_refused"] == 2 and out["reasons"]["rejected.bad_param"] == 2
    results = [
        roles_by_cantools(dbc.ack_frame, m.data)["ack.result"]
        for m in acks
        if m.arbitration_id == dbc.ack_frame.frame_id
    ]
    assert results == [1.0, 3.0]  # unknown_param at once, invalid_value when derived
    with pytest.raises(Exception, match="no tunable parameter"):
        dbc.encode_param("teeth_ratio", 2.0)


# -- the runner's recording -------------------------------------------------------------


@needs_runner
def test_runner_recording_reproduces_the_run(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A live run over socketcand recorded by the runner itself: to-csv then
    compare reproduce it (nrmse <= 1e-3); two replays of the recording, each
    recording itself, are byte-identical."""
    pytest.importorskip("gearsim.analysis")
    from gearsim.cli import main

    rec = tmp_path / "rec.log"
    proc, port = _socketcand_runner(tmp_path, "--log", str(rec), "--duration", "3600")
    sent = [0]
    try:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0")
        dbc = RigDbc(block="gear")
        try:
            start, next_t = time.monotonic(), time.monotonic()
            while (now := time.monotonic()) < start + 1.6:
                if now >= next_t:
                    t = now - start
                    for m in dbc.encode_command(
                        {
                            "cmd.base_speed": 20 * math.sin(2 * math.pi * 0.8 * t) + 5,
                            "cmd.load": 0.3 if int(t / 0.4) % 2 else -0.3,
                            "cmd.mode": "speed",
                        }
                    ):
                        bus.send(m)
                        sent[0] += 1
                    next_t += 0.01
                bus.recv(timeout=0.002)
        finally:
            bus.shutdown()
        proc.send_signal(2)
        err = proc.communicate(timeout=20)[1]
    finally:
        if proc.poll() is None:
            proc.kill()
    s = summary(err)
    assert s["log_dropped"] == 0 and s["log_written"] == s["frames_in"] + s["frames_out"]
    assert s["frames_in"] == sent[0]
    csv, toml = tmp_path / "rec.csv", tmp_path / "model.toml"
    gear_model().save(toml)
    assert main(["hil", "to-csv", str(rec), "--rig", "gear", "-o", str(csv), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["time_base"] == "rig"
    assert main(["compare", str(csv), "--model", str(toml), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["nrmse"] <= 1e-3, report["outputs"]
    params = tmp_path / "gear.params"
    outs = []
    for i in (1, 2):
        answers, again = tmp_path / f"answers{i}.log", tmp_path / f"again{i}.log"
        res = run(
            [*runner_mod.replay_command(params, rec, answers, runner=RUNNER), "--log", str(again)]
        )
        assert res.returncode == 0, res.stderr
        outs.append((answers.read_bytes(), again.read_bytes()))
    assert outs[0] == outs[1] and len(outs[0][1]) > 0


# -- socketcand --------------------------------------------------------------------------


@needs_runner
def test_socketcand_client_disconnect_and_reconnect_lose_nothing(tmp_path: Path) -> None:
    """python-can's socketcand client drives the runner; it goes away and
    comes back: every frame it sent arrived, both connections are counted,
    the rig ran on in between (the commands timed out, then recovered)."""
    proc, port = _socketcand_runner(tmp_path, "--duration", "3600")
    dbc = RigDbc(block="gear")
    sent, received = [0], []
    try:
        for _ in range(2):
            bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0")
            try:
                end = time.monotonic() + 0.4
                while time.monotonic() < end:
                    for m in dbc.encode_command({"cmd.base_speed": 7.0, "cmd.mode": "speed"}):
                        bus.send(m)
                        sent[0] += 1
                    deadline = time.monotonic() + 0.01
                    while (left := deadline - time.monotonic()) > 0:
                        m = bus.recv(timeout=left)
                        if m is not None:
                            received.append(m)
            finally:
                bus.shutdown()
            time.sleep(0.3)  # no client: the rig answers nobody and times out
        proc.send_signal(2)
        err = proc.communicate(timeout=20)[1]
    finally:
        if proc.poll() is None:
            proc.kill()
    s = summary(err)
    assert s["client_connects"] == 2 and s["client_disconnects"] == 2
    assert s["frames_in"] == s["rx_total"] == sent[0] and s["malformed_lines"] == 0
    assert s["timeouts"] >= 1 and s["recoveries"] >= 1
    speeds = [
        roles_by_cantools(dbc.by_key[(0x200, False)], m.data)["out.base_speed"]
        for m in received
        if m.arbitration_id == 0x200
    ]
    assert speeds and max(speeds) == pytest.approx(7.0)


# -- bad input -------------------------------------------------------------------------------


BAD = [
    (
        "[scenario]\nduration = 1\n[[step]]\n"
        'at = 0.1\nfault = "offset"\nsignal = "Nope"\nvalue = 1\n',
        "s.toml:6: signal: 'Nope' is no feedback signal of gear_rig",
    ),
    (
        "[scenario]\nduration = 1\n[[step]]\nat = 0.1\nload = [1, 2]\n",
        "s.toml:5: load: arrays and inline tables are not used in a scenario",
    ),
    (
        '[scenario]\nduration = 1\n[[step]]\nat = 0.1\nparam = "load_offset"\nvalue = "x"\n',
        "s.toml:6: value: expected a number",
    ),
    (
        "[scenario]\nduration = 1\n[[step]]\n"
        'at = 0.2\nparam = "load_coulomb_friction"\nvalue = -1\n',
        "s.toml:6: value: load_coulomb_friction = -1 refused by the rig",
    ),
]


@pytest.mark.parametrize("text, message", BAD, ids=["signal", "array", "type", "refused"])
def test_bad_scenarios_exit_2_with_one_line(tmp_path: Path, text: str, message: str) -> None:
    scenario = tmp_path / "s.toml"
    scenario.write_text(text)
    log = write_log(tmp_path / "in.log", command(RigDbc(block="gear"), 1.7e9, base_speed=1.0))
    shown = str(scenario)
    py = subprocess.run(
        [*_python(), "replay", str(log), "--model", str(_model(tmp_path)), "--scenario", shown],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert py.returncode == 2 and py.stderr.count("\n") == 1, py.stderr
    assert message.replace("s.toml", shown) in py.stderr
    if RUNNER is not None:
        params = runner_mod.write_params(gear_model(), tmp_path / "gear.params")
        c = run([*runner_mod.replay_command(params, log, runner=RUNNER), "--scenario", shown])
        assert c.returncode == 2 and c.stderr.count("\n") == 1, c.stderr
        assert message.replace("s.toml", shown) in c.stderr


def _python() -> list[str]:
    import sys

    return [sys.executable, "-m", "gearsim.hil"]


def _model(tmp_path: Path) -> Path:
    path = tmp_path / "model.toml"
    gear_model().save(path)
    return path


@needs_runner
def test_runner_parameter_frames_recorded_and_replayed(tmp_path: Path) -> None:
    """Parameter frames through the runner: a good one takes effect (and is
    acknowledged a period later), a bad one is a counted refusal; the
    runner's recording holds the request and the acknowledgement around the
    change, and a replay of the recording gives the same answers."""
    dbc = RigDbc(block="gear")
    msgs = [m for k in range(0, 300, 10) for m in command(dbc, 1.7e9 + k * 1e-3, base_speed=10.0)]
    good = dbc.encode_param("load_coulomb_friction", 0.25)
    bad = dbc.encode_param("load_coulomb_friction", -1.0)
    good.timestamp, bad.timestamp = 1.7e9 + 0.1005, 1.7e9 + 0.2005
    log = write_log(tmp_path / "in.log", sorted([*msgs, good, bad], key=lambda m: m.timestamp))
    params = runner_mod.write_params(gear_model(), tmp_path / "gear.params")
    rec, out = tmp_path / "rec.log", tmp_path / "out.log"
    res = run([*runner_mod.replay_command(params, log, out, runner=RUNNER), "--log", str(rec)])
    assert res.returncode == 0, res.stderr
    s = summary(res.stderr)
    assert s["param_changes"] == 1 and s["param_refused"] == 1
    assert s["reasons"]["rejected.bad_param"] == 1
    lines = rec.read_text().splitlines()
    request = next(i for i, line in enumerate(lines) if " 120#" in line and line.endswith(" R"))
    acks = [line for line in lines if " 220#" in line]
    assert len(acks) == 2 and all(line.endswith(" T") for line in acks)
    # the request at the start of period 101, its acknowledgement at the end of period 102
    t_req = float(lines[request].split(")")[0][1:]) - 1.7e9
    t_ack = float(acks[0].split(")")[0][1:]) - 1.7e9
    assert t_req == pytest.approx(0.101, abs=2e-6) and t_ack == pytest.approx(0.103, abs=2e-6)
    ack = roles_by_cantools(dbc.ack_frame, bytes.fromhex(acks[0].split("#")[1].split()[0]))
    assert ack["ack.result"] == 0.0 and ack["ack.value"] == pytest.approx(0.25)
    again = tmp_path / "again.log"
    res2 = run(runner_mod.replay_command(params, rec, again, runner=RUNNER))
    assert res2.returncode == 0, res2.stderr
    # the replay of the recording: the same answers, but for RxIgnored (GearCounters), which
    # counts the recorded answers the replay reads back
    first = [(m.arbitration_id, bytes(m.data)) for m in read_log(out) if m.arbitration_id != 0x211]
    second = [
        (m.arbitration_id, bytes(m.data)) for m in read_log(again) if m.arbitration_id != 0x211
    ]
    assert second == first


def test_python_run_with_a_scenario_writes_its_verdict(tmp_path: Path) -> None:
    """gearsim hil run --scenario: paced, as long as the scenario, the verdict
    to --junit; exit 3 when an expectation fails."""
    scenario = write_scenario(
        tmp_path / "s.toml",
        'at = 0.05\nexpect = "cmd_timeout"\nequals = true\nname = "no host: timed out"',
        'at = 0.1\nexpect = "DriveMode"\nequals = "speed"\nname = "no host: no command"',
        duration=0.2,
    )
    xml = tmp_path / "v.xml"
    res = subprocess.run(
        [
            *_python(),
            "run",
            "--model",
            str(_model(tmp_path)),
            "-i",
            "virtual",
            "-c",
            next_channel("run"),
            "--scenario",
            str(scenario),
            "--junit",
            str(xml),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 3, res.stderr
    out = json.loads(res.stdout)
    assert out["periods"] == 200 and out["verdict"] == {"passed": 1, "failed": 1}
    root = _validate(xml.read_text())
    assert root.get("tests") == "2" and root.get("failures") == "1"

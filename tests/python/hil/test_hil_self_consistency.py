"""The Python bridge around the C runner: the DBC shipped from hil/dbc,
python-can's configuration for `gearsim hil run`, `--runner c`, and a recording
in rig time that converts into a CSV the same model reproduces."""

from __future__ import annotations

import csv
import json
import math
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hil_helpers import Peer, RigDbc, can, gear_model, next_channel

from gearsim.cli import main
from gearsim.hil import Bridge, RigTimeRecorder, shipped_dbc

REPO = Path(__file__).resolve().parents[3]


# -- the DBC: one source -----------------------------------------------------------
@pytest.mark.parametrize("rig, name", [("gear", "gear_rig.dbc"), ("rack", "rack_rig.dbc")])
def test_shipped_dbc_is_the_one_in_hil_dbc(rig: str, name: str) -> None:
    source = REPO / "hil" / "dbc" / name
    if not source.is_file():
        pytest.skip("not a repository checkout (no hil/dbc)")
    shipped = shipped_dbc(rig)
    assert shipped.is_file() and shipped.name == name
    assert shipped.read_bytes() == source.read_bytes()


# -- python-can's configuration ----------------------------------------------------
def _run_briefly(capsys: pytest.CaptureFixture, model: Path, *extra: str) -> tuple[int, str]:
    capsys.readouterr()
    rc = main(["hil", "run", "--model", str(model), "--duration", "0.02", "--json", *extra])
    out, err = capsys.readouterr()
    return rc, out + err


@pytest.fixture
def model_file(tmp_path: Path) -> Path:
    path = tmp_path / "model.toml"
    gear_model().save(path)
    return path


@pytest.fixture
def no_can_config(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No python-can configuration anywhere: an empty HOME, no CAN_* variables."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    for var in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(var, raising=False)
    if Path("/etc/can.conf").exists():
        pytest.skip("/etc/can.conf configures python-can on this machine")
    return home


def test_run_without_any_bus_configuration_says_how(
    no_can_config: Path, model_file: Path, capsys: pytest.CaptureFixture
) -> None:
    rc, text = _run_briefly(capsys, model_file)
    assert rc == 2
    lines = text.strip().splitlines()
    assert len(lines) == 1 and "no CAN interface configured" in lines[0]
    assert "CAN_INTERFACE" in lines[0] and "~/.canrc" in lines[0]


def test_run_takes_the_bus_from_the_environment(
    no_can_config: Path,
    model_file: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture,
) -> None:
    channel = next_channel("env")
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", channel)
    rc, text = _run_briefly(capsys, model_file)
    assert rc == 0, text
    assert f"on virtual:{channel}" in text
    # a command-line flag wins over the environment
    rc, text = _run_briefly(capsys, model_file, "-c", "flagged")
    assert rc == 0 and "on virtual:flagged" in text


def test_run_takes_the_bus_from_the_config_file(
    no_can_config: Path, model_file: Path, capsys: pytest.CaptureFixture
) -> None:
    (no_can_config / ".canrc").write_text(
        "[default]\ninterface = virtual\nchannel = from-canrc\n\n"
        "[bench]\ninterface = virtual\nchannel = from-bench-section\n"
    )
    rc, text = _run_briefly(capsys, model_file)
    assert rc == 0, text
    assert "on virtual:from-canrc" in text
    rc, text = _run_briefly(capsys, model_file, "--can-context", "bench")
    assert rc == 0 and "on virtual:from-bench-section" in text
    other = no_can_config / "other.ini"
    other.write_text("[default]\ninterface = virtual\nchannel = from-other\n")
    rc, text = _run_briefly(capsys, model_file, "--can-config", str(other))
    assert rc == 0 and "on virtual:from-other" in text


# -- the C runner --------------------------------------------------------------------
def _fake_runner(path: Path, precision: str = "double") -> Path:
    """An executable that answers --version as gearsim-hil does (locating a
    runner runs nothing else)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'#!/bin/sh\necho "gearsim-hil 0.1.0 {precision}"\n')
    path.chmod(0o755)
    return path


@pytest.fixture
def no_runner_anywhere(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No runner on PATH, in the environment or in a source tree; the working
    directory is an empty folder (returned)."""
    runner = pytest.importorskip("gearsim.hil.runner")
    work = tmp_path / "work"
    (work / "bin").mkdir(parents=True)
    monkeypatch.setenv("PATH", str(work / "bin"))
    monkeypatch.delenv(runner.RUNNER_ENV, raising=False)
    monkeypatch.setattr(runner, "_source_tree", lambda: None)
    monkeypatch.chdir(work)
    return work


def _runner_c(capsys: pytest.CaptureFixture, model: Path, *extra: str) -> tuple[int, str, str]:
    capsys.readouterr()
    argv = ["hil", "run", "--model", str(model), "--runner", "c", "-i", "candump"]
    rc = main([*argv, "--print-command", *extra])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def test_runner_c_when_not_available_says_how(
    no_runner_anywhere: Path, model_file: Path, capsys: pytest.CaptureFixture
) -> None:
    rc, out, err = _runner_c(capsys, model_file)
    lines = err.strip().splitlines()
    assert rc == 2 and out == "" and len(lines) == 1
    for needle in ("not built or installed", "cmake -S . -B build", "build/hil/gearsim-hil"):
        assert needle in lines[0]
    assert "--runner-path" in lines[0] and "GEARSIM_HIL_RUNNER" in lines[0]


def test_runner_c_finds_the_documented_build_and_says_which(
    no_runner_anywhere: Path,
    model_file: Path,
    capsys: pytest.CaptureFixture,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """--runner c takes, in order: --runner-path, $GEARSIM_HIL_RUNNER, the
    installed gearsim-hil (PATH), the documented build build/hil/gearsim-hil
    (of the source tree, or of the working directory); never a test build
    such as build/test-double/hil; and says on stderr which it took."""
    from gearsim.hil import runner

    work = no_runner_anywhere
    params = ["--runner-params", str(work / "m.hil-params")]
    # a test build alone is not taken
    _fake_runner(work / "build" / "test-double" / "hil" / "gearsim-hil")
    rc, _, err = _runner_c(capsys, model_file, *params)
    assert rc == 2 and "not built or installed" in err
    # the documented build, in the working directory, then in the source tree
    documented = _fake_runner(work / "build" / "hil" / "gearsim-hil")
    rc, out, err = _runner_c(capsys, model_file, *params)
    assert rc == 0 and out.split()[0] == str(documented)
    assert f"C runner {documented} (built in the working directory (build/hil), double)" in err
    tree = work / "tree"
    built = _fake_runner(tree / "build" / "hil" / "gearsim-hil", precision="float")
    monkeypatch.setattr(runner, "_source_tree", lambda: tree)
    rc, out, err = _runner_c(capsys, model_file, *params)
    assert rc == 0 and out.split()[0] == str(built)
    assert "(built in the source tree (build/hil), float; float: its answers are not" in err
    # installed, on PATH
    installed = _fake_runner(work / "bin" / "gearsim-hil")
    rc, out, err = _runner_c(capsys, model_file, *params)
    assert rc == 0 and out.split()[0] == str(installed) and "(installed (on PATH), double)" in err
    # the environment, then --runner-path
    named = _fake_runner(work / "elsewhere" / "gearsim-hil")
    monkeypatch.setenv(runner.RUNNER_ENV, str(named))
    rc, out, err = _runner_c(capsys, model_file, *params)
    assert rc == 0 and out.split()[0] == str(named) and "($GEARSIM_HIL_RUNNER, double)" in err
    explicit = _fake_runner(work / "mine" / "gearsim-hil")
    rc, out, err = _runner_c(capsys, model_file, *params, "--runner-path", str(explicit))
    assert rc == 0 and out.split()[0] == str(explicit) and "(--runner-path, double)" in err
    # a named runner that is not there is an error, not a fall-back
    rc, out, err = _runner_c(capsys, model_file, *params, "--runner-path", str(work / "none"))
    lines = err.strip().splitlines()
    assert (
        rc == 2
        and len(lines) == 1
        and "--runner-path" in lines[0]
        and "not an executable" in lines[0]
    )
    # --runner-path belongs to --runner c
    capsys.readouterr()
    assert main(["hil", "run", "--model", str(model_file), "--runner-path", str(explicit)]) == 2
    assert "--runner-path needs --runner c" in capsys.readouterr().err


# -- rig time: run -> to-csv -> the same model ------------------------------------------
def _profile(t: float) -> dict[str, Any]:
    """A test host's commands (every 10 ms): a sine speed, a square load."""
    return {
        "base_speed": 20.0 * math.sin(2 * math.pi * 0.5 * t) + 5.0,
        "load": 0.4 if int(t / 0.5) % 2 == 0 else -0.4,
        "mode": "speed",
    }


def _session_in_rig_time(log: Path, seconds: float, offsets: tuple[int, ...]) -> None:
    """The bridge at 1 kHz on the virtual bus with a host sending commands; a
    command goes out in period k when k % 20 is in ``offsets`` (two commands
    per 20 ms; offsets 9 and 10 put two commands into one 10 ms feedback
    interval and none into the next, like a host's jitter across a boundary).
    Recorded the way `gearsim hil run --log` records (RigTimeRecorder, origin
    on the wall clock)."""
    dbc = RigDbc(block="gear")
    channel = next_channel("rigtime")
    bus = can.Bus(interface="virtual", channel=channel)
    peer = Peer(channel, dbc)
    logger = can.Logger(str(log))
    try:
        bridge = Bridge.from_model(gear_model(), dbc, period=1e-3, timeout=0.1, bus=bus)
        bridge.add_listener(RigTimeRecorder(bridge, logger.on_message_received, time.time()))
        for k in range(round(seconds / 1e-3)):
            if k % 20 in offsets:
                peer.command(**_profile(k * 1e-3))
            bridge.tick()
            peer.drain()
        bridge.close()
    finally:
        logger.stop()
        peer.close()
        bus.shutdown()


def _read_marked_csv(path: Path) -> tuple[dict[str, str], dict[str, np.ndarray]]:
    with open(path, newline="") as fh:
        first = fh.readline()
        rows = list(csv.reader(fh))
    assert first.startswith("# gearsim hil to-csv:")
    marker = dict(item.split("=", 1) for item in first.split(":", 1)[1].split())
    data = np.array(rows[1:], dtype=float)
    return marker, {name: data[:, i] for i, name in enumerate(rows[0])}


def _stepped_like_the_rig(model: Any, marker: dict[str, str], c: dict[str, np.ndarray]):
    """The CSV's meaning, written out independently of to-csv: step the model
    every rig_dt; in the interval that ends at row j, a step that starts before
    inputs_since[j] gets the row's <input>_before values, later steps the row's
    own inputs; compare the outputs after the interval's last step with the row.
    Returns the nrmse of each output."""
    h = float(marker["rig_dt"])
    t = c["time"]
    n = round((t[1] - t[0]) / h)
    speed, load = [], []
    for j in range(len(t)):
        for k in range(n):
            before = t[j] - (n - k) * h < c["inputs_since"][j] - h / 2
            speed.append(c["base_speed_before" if before else "base_speed"][j])
            load.append(c["load_torque_before" if before else "load_torque"][j])
    res = model.rig(dt=h).run(base_speed=np.array(speed), load=np.array(load))
    return {
        name: float(
            np.sqrt(np.mean((np.asarray(getattr(res, name))[n - 1 :: n] - c[name]) ** 2))
            / np.std(c[name])
        )
        for name in ("base_torque", "follower_speed")
    }


@pytest.mark.parametrize(
    "offsets, since",
    [
        ((0, 10), {0}),  # at the start of each feedback interval
        ((4, 14), {4}),  # in the middle
        ((9, 19), {9}),  # in its last period: the inertia spike is in the sample
        ((9, 10), {0, 9}),  # jitter: two in one interval, none in the next
    ],
)
def test_rig_time_recording_converts_to_a_csv_the_model_reproduces(
    tmp_path: Path, capsys: pytest.CaptureFixture, offsets: tuple[int, ...], since: set[int]
) -> None:
    log = tmp_path / "bench.blf"
    _session_in_rig_time(log, 1.5, offsets)
    out = tmp_path / "bench.csv"
    assert main(["hil", "to-csv", str(log), "--rig", "gear", "-o", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""  # a rig-time log: nothing to warn about
    info = json.loads(captured.out)
    assert info["time_base"] == "rig" and info["rig_dt"] == 1e-3
    marker, c = _read_marked_csv(out)
    assert marker == {"time_base": "rig", "rig_dt": "0.001", "held": "base_speed,load_torque"}
    assert np.allclose(np.diff(c["time"]), 0.01)
    # where in its interval each row's inputs started (0: held all along)
    start = np.rint((c["inputs_since"] - (c["time"] - 0.01)) / 1e-3)
    assert set(start[1:].tolist()) == since
    errors = _stepped_like_the_rig(gear_model(), marker, c)
    assert errors["base_torque"] <= 1e-3 and errors["follower_speed"] <= 1e-3, errors


def test_wall_clock_log_is_converted_with_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """A host's own recording (wall-clock stamps, jitter) cannot say at which step
    each command acted: to-csv resamples, says so on one line, marks the CSV."""
    dbc = RigDbc(block="gear")
    log = tmp_path / "host.asc"
    rng = np.random.default_rng(7)
    with can.Logger(str(log)) as logger:
        for k in range(100):
            t = 1000.0 + k * 0.01 + float(rng.uniform(0, 4e-4))
            for m in dbc.encode_command({"cmd.base_speed": 1.0, "cmd.mode": "speed"}):
                m.timestamp = t
                logger.on_message_received(m)
            values = {"out.base_torque": 0.1, "out.base_speed": 1.0, "in.load": 0.0}
            values["out.follower_speed"] = 1.0 / 3
            for frame in dbc.feedback[:2]:
                values.update({sig.role: 0.0 for sig in frame.signals if sig.role not in values})
                data, _ = dbc.encode_feedback(frame, values)
                msg = can.Message(timestamp=t + 0.0053, arbitration_id=frame.frame_id, data=data)
                msg.is_extended_id = False
                logger.on_message_received(msg)
    out = tmp_path / "host.csv"
    capsys.readouterr()
    assert main(["hil", "to-csv", str(log), "--rig", "gear", "-o", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "warning" in err[0] and "gearsim hil run --log" in err[0]
    assert out.read_text().splitlines()[0] == "# gearsim hil to-csv: time_base=wall"


@pytest.mark.parametrize("offsets", [(0, 10), (4, 14), (9, 19), (9, 10)])
def test_compare_with_default_options_reproduces_the_rig(
    tmp_path: Path, capsys: pytest.CaptureFixture, offsets: tuple[int, ...]
) -> None:
    """The recording loop: hil run --log -> to-csv -> compare, default options,
    wherever in the feedback interval the commands arrived."""
    pytest.importorskip("gearsim.analysis")
    log = tmp_path / "bench.blf"
    _session_in_rig_time(log, 1.5, offsets)
    out, toml = tmp_path / "bench.csv", tmp_path / "model.toml"
    gear_model().save(toml)
    assert main(["hil", "to-csv", str(log), "--rig", "gear", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["compare", str(out), "--model", str(toml), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["nrmse"] <= 1e-3, report["outputs"]


def test_live_run_records_in_rig_time_and_replays_to_its_answers(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`gearsim hil run --log` (paced by the wall clock, a host thread sending
    commands off the period grid) writes its log on the period grid, and
    `gearsim hil replay` of that log answers frame for frame as the live run did."""
    channel = next_channel("live")
    model, log, answers = tmp_path / "m.toml", tmp_path / "live.blf", tmp_path / "again.blf"
    gear_model().save(model)
    dbc = RigDbc(block="gear")
    stop, bus_ready = threading.Event(), threading.Event()

    def host() -> None:
        with can.Bus(interface="virtual", channel=channel) as bus:
            bus_ready.set()
            k = 0
            while not stop.is_set():
                speed = 10.0 * math.sin(k / 7.0)
                for m in dbc.encode_command({"cmd.base_speed": speed, "cmd.mode": "speed"}):
                    bus.send(m)
                k += 1
                time.sleep(0.0037)

    # A replay starts its periods at the log's first frame: the live run must
    # find a command waiting at period 0. The host's bus exists first and sends
    # every 3.7 ms; the bridge waits 10 ms between opening its bus and its first
    # period, so that one of them is queued then (the virtual bus delivers only
    # to buses that exist when a frame is sent).
    original_run = Bridge.run

    def run_after_a_command(self: Bridge, **kwargs: Any) -> Any:
        time.sleep(0.01)
        return original_run(self, **kwargs)

    monkeypatch.setattr(Bridge, "run", run_after_a_command)
    thread = threading.Thread(target=host, daemon=True)
    thread.start()
    bus_ready.wait(5.0)
    try:
        argv = ["hil", "run", "--model", str(model), "-i", "virtual", "-c", channel]
        assert main([*argv, "--duration", "0.3", "--log", str(log), "--json"]) == 0
    finally:
        stop.set()
        thread.join()
    live = list(can.LogReader(str(log)))
    times = np.array([m.timestamp for m in live])
    steps = (times - times[0]) / 1e-3
    assert len(live) > 50 and np.allclose(steps, np.rint(steps), atol=2e-3)

    argv = ["hil", "replay", str(log), "--model", str(model), "-o", str(answers), "--json"]
    assert main(argv) == 0
    capsys.readouterr()
    feedback = {f.frame_id for f in dbc.feedback}
    status = {
        f.frame_id for f in dbc.feedback if any("status" in (s.role or "") for s in f.signals)
    }

    def sent(msgs: list[Any]) -> list[tuple[float, int, bytes]]:
        # status frames differ in RxIgnored only (the log's feedback is ignored in a replay)
        return [
            (round(m.timestamp - times[0], 6), m.arbitration_id, bytes(m.data))
            for m in msgs
            if m.arbitration_id in feedback and m.arbitration_id not in status
        ]

    replayed = sent(list(can.LogReader(str(answers))))
    assert replayed == sent(live) and len(replayed) > 40


def test_runner_c_print_command_writes_the_params_and_the_command_line(
    tmp_path: Path, model_file: Path, capsys: pytest.CaptureFixture
) -> None:
    pytest.importorskip("gearsim.hil.runner")
    exe = _fake_runner(tmp_path / "bin" / "gearsim-hil")
    params = tmp_path / "rig.hil-params"
    argv = ["hil", "run", "--model", str(model_file), "--runner", "c", "--print-command"]
    argv += ["--runner-path", str(exe)]
    capsys.readouterr()
    rc = main([*argv, "-i", "candump", "--period", "0.002", "--runner-params", str(params)])
    assert rc == 0
    cmd = capsys.readouterr().out.split()
    assert cmd[0] == str(exe) and params.is_file()
    assert cmd[cmd.index("--params") + 1] == str(params)
    assert cmd[cmd.index("--period") + 1] == "0.002"
    assert cmd[cmd.index("--transport") + 1] == "candump"
    # a python-can interface the runner does not speak: one line, exit 2
    rc = main([*argv, "-i", "virtual", "-c", "x", "--runner-params", str(params)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "-i socketcan" in err[0]
    # the parameter file may not overwrite the model
    rc = main([*argv, "-i", "candump", "--runner-params", str(model_file)])
    assert rc == 2 and model_file.read_text().startswith("[")

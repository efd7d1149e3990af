"""`gearsim hil run|replay|to-csv|dbc` and SocketCAN."""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hil_helpers import RigDbc, can, gear_model, next_channel, record_session

from gearsim.cli import main
from gearsim.hil import cli as hil_cli
from gearsim.hil import shipped_dbc


def _profile(k: int) -> dict[str, Any]:
    return {"base_speed": 15.0 * math.sin(k / 50.0), "load": 0.2}


@pytest.fixture
def files(tmp_path: Path, gear_dbc: RigDbc) -> dict[str, Path]:
    model = gear_model()
    toml = tmp_path / "model.toml"
    model.save(toml)
    log = tmp_path / "session.asc"
    record_session(model, gear_dbc, log, _profile, periods=300)
    return {"model": toml, "log": log, "dir": tmp_path}


def _one_json(out: str) -> dict[str, Any]:
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert len(lines) == 1, out
    return json.loads(lines[0])


def test_dbc_command(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["hil", "dbc", "rack"]) == 0
    assert Path(capsys.readouterr().out.strip()) == shipped_dbc("rack")
    copy = tmp_path / "mine.dbc"
    assert hil_cli.main(["dbc", "gear", "-o", str(copy)]) == 0
    assert copy.read_text() == shipped_dbc("gear").read_text()


def test_replay_and_to_csv(files: dict[str, Path], capsys: pytest.CaptureFixture) -> None:
    out = files["dir"] / "answers.blf"
    capsys.readouterr()
    assert (
        main(
            [
                "hil",
                "replay",
                str(files["log"]),
                "--model",
                str(files["model"]),
                "-o",
                str(out),
                "--timeout",
                "0.05",
                "--json",
            ]
        )
        == 0
    )
    data = _one_json(capsys.readouterr().out)
    assert data["frames_in"] > 0 and data["frames_out"] == len(list(can.LogReader(str(out))))
    c = data["counters"]
    assert c["rx_total"] == c["rx_used"] + c["rx_rejected"] + c["rx_late"] + c["rx_ignored"]
    assert c["rx_used"] == 30

    csv_path = files["dir"] / "data.csv"
    assert main(["hil", "to-csv", str(out), "--rig", "gear", "-o", str(csv_path), "--json"]) == 0
    info = _one_json(capsys.readouterr().out)
    assert info["rows"] == 30 and info["columns"][0] == "time"
    # the replay's answers are on its period grid: rows in rig time, inputs held
    # at the rig's 1 ms step, said on the first line for the analysis
    marker, header = csv_path.read_text().splitlines()[:2]
    assert marker == "# gearsim hil to-csv: time_base=rig rig_dt=0.001 held=base_speed,load_torque"
    assert header == (
        "time,base_speed,load_torque,base_torque,follower_speed,"
        "inputs_since,base_speed_before,load_torque_before"
    )
    # text output
    assert (
        main(
            [
                "hil",
                "to-csv",
                str(files["log"]),
                "--model",
                str(files["model"]),
                "-o",
                str(csv_path),
            ]
        )
        == 0
    )
    assert "wrote 30 rows" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["hil", "replay", "{log}", "--model", "{dir}/missing.toml"], "missing.toml"),
        (["hil", "replay", "{dir}/missing.asc", "--model", "{model}"], "missing.asc"),
        (["hil", "replay", "{log}", "--model", "{model}", "--period", "0.003"], "whole number"),
        (["hil", "replay", "{log}", "--model", "{model}", "--dbc", "{dir}/bad.dbc"], "bad.dbc"),
        (["hil", "replay", "{log}", "--model", "{model}", "--dbc", "{rack}"], "rack_pinion"),
        (["hil", "replay", "{dir}/notes.txt2", "--model", "{model}"], "notes.txt2"),
        (["hil", "to-csv", "{log}", "-o", "{dir}/x.csv"], "--rig"),
        (["hil", "run", "-i", "no_such_interface", "--model", "{model}"], "cannot open CAN bus"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    files: dict[str, Path], capsys: pytest.CaptureFixture, argv: list[str], message: str
) -> None:
    (files["dir"] / "bad.dbc").write_text("not a dbc")
    (files["dir"] / "notes.txt2").write_text("hello")
    fmt = {k: str(v) for k, v in files.items()} | {"rack": str(shipped_dbc("rack"))}
    capsys.readouterr()
    assert main([a.format(**fmt) for a in argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and "Traceback" not in err


def test_run_on_the_virtual_bus_for_a_simulated_duration(
    files: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    log = files["dir"] / "run.log"
    capsys.readouterr()
    assert (
        main(
            [
                "hil",
                "run",
                "-i",
                "virtual",
                "-c",
                next_channel("cli"),
                "--model",
                str(files["model"]),
                "--duration",
                "0.05",
                "--log",
                str(log),
                "--json",
            ]
        )
        == 0
    )
    data = _one_json(capsys.readouterr().out)
    assert data["periods"] == 50 and data["rx_total"] == 0 and data["state"]["cmd_timeout"]
    assert data["tx_frames"] == 10  # two 10 ms frames, five times
    assert "period_error_median_us" in data["loop"]
    assert len(list(can.LogReader(str(log)))) == 10


def test_ctrl_c_stops_cleanly_and_prints_the_counters(files: dict[str, Path]) -> None:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gearsim.hil",
            "run",
            "-i",
            "virtual",
            "-c",
            "ctrl-c-test",
            "--model",
            str(files["model"]),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        # -i virtual is said to be this process only, then the run starts
        warning, banner = proc.stderr.readline(), proc.stderr.readline()
        assert "warning: -i virtual is python-can's in-process bus" in warning, warning
        assert "Ctrl-C stops" in banner, banner
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "rx_total" in out and "tx_frames" in out
    assert "Traceback" not in err


def test_run_on_the_virtual_bus_says_it_is_this_process_only(
    files: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    """python-can's virtual bus joins the buses of one process: a host started
    as another process (examples/hil/host.py) would send into nothing. The
    run says so, and what to use instead, before it starts."""
    capsys.readouterr()
    argv = ["hil", "run", "--model", str(files["model"]), "-i", "virtual", "-c", "alone"]
    assert main([*argv, "--duration", "0.005"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("gearsim hil run: warning: -i virtual is python-can's in-process")
    assert "another process" in err[0] and "-i udp_multicast" in err[0]
    assert "Ctrl-C stops" in err[1]


def test_socketcan_that_does_not_open_says_why(
    files: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    """As the C runner does: this kernel has no AF_CAN (the hint names
    modprobe and an interface that works without it); on a kernel with
    SocketCAN the interface does not exist (the hint names ip link)."""
    capsys.readouterr()
    argv = ["hil", "run", "--model", str(files["model"]), "-i", "socketcan", "-c", "gsnone0"]
    assert main([*argv, "--duration", "0.01"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "cannot open CAN bus socketcan:gsnone0" in lines[0]
    if _socketcan_unavailable() is not None:
        assert "(this kernel has no AF_CAN; load it with modprobe can_raw" in lines[0]
        assert "-i udp_multicast" in lines[0]
    else:
        assert "no such CAN interface; ip link show" in lines[0]


def _socketcan_unavailable() -> str | None:
    if not hasattr(socket, "AF_CAN"):
        return "this Python has no socket.AF_CAN"
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError as exc:
        return f"this kernel has no AF_CAN (SocketCAN): {exc}"
    s.close()
    if not Path("/sys/class/net/vcan0").exists():
        return "no vcan0 interface (ip link add dev vcan0 type vcan && ip link set up vcan0)"
    return None


@pytest.mark.skipif(_socketcan_unavailable() is not None, reason=str(_socketcan_unavailable()))
def test_socketcan_vcan0_back_to_back(gear_dbc: RigDbc) -> None:
    from hil_helpers import Bridge

    model = gear_model()
    with (
        can.Bus(interface="socketcan", channel="vcan0") as bridge_bus,
        can.Bus(interface="socketcan", channel="vcan0") as peer,
    ):
        bridge = Bridge.from_model(model, gear_dbc, bus=bridge_bus)
        for m in gear_dbc.encode_command({"cmd.base_speed": 3.0, "cmd.load": 0.1}):
            peer.send(m)
        got = None
        for _ in range(100):  # frames cross the kernel: poll until the command is there
            bridge.poll()
            if bridge.pending:
                break
            got = peer.recv(timeout=0.01)
        bridge.advance(10)
        got = peer.recv(timeout=1.0)
        assert got is not None and bridge.counters.rx_used == 1

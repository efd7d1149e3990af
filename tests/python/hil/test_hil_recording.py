"""Recording to measurement: a recorded log as the canonical CSV of
docs/measurement-format.md section 1."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hil_helpers import RigDbc, gear_model, rack_model, record_session

from gearsim.hil import RecordingError, log_to_measurement, write_csv


def _profile(k: int) -> dict[str, Any]:
    return {
        "base_speed": 20.0 * math.sin(2 * math.pi * k / 400) + 5.0,
        "load": 0.4 * math.sin(2 * math.pi * k / 230),
        "mode": "speed",
    }


def _read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def _series(dbc: RigDbc, live: list, role: str) -> dict[float, float]:
    out = {}
    for t, i, data in live:
        values = dbc.decode_feedback(dbc.by_key[(i, False)], data)
        if role in values:
            out[round(t, 9)] = values[role]
    return out


def test_gear_log_to_csv(tmp_path: Path, gear_dbc: RigDbc) -> None:
    log = tmp_path / "gear.asc"
    live, _ = record_session(gear_model(), gear_dbc, log, _profile, periods=600)
    rec = log_to_measurement(log, gear_dbc)
    assert rec.sources == {
        "base_speed": "GearFbBase.BaseSpeed",
        "load_torque": "GearFbBase.LoadTorque",
        "base_torque": "GearFbBase.BaseTorque",
        "follower_speed": "GearFbFollower.FollowerSpeed",
    }
    out = tmp_path / "gear.csv"
    write_csv(out, rec.columns)
    header, data = _read_csv(out)
    assert header == [
        "time",
        "base_speed",
        "load_torque",
        "base_torque",
        "follower_speed",
        "inputs_since",
        "base_speed_before",
        "load_torque_before",
    ]
    assert rec.dt == pytest.approx(0.01) and len(data) == 60
    # the session is stamped in simulated time: rig time base, and every command
    # (sent at the start of each 10 ms interval) was applied from the row before
    assert rec.time_base == "rig" and rec.rig_dt == 1e-3
    k_rows = np.rint(data[:, 0] / 1e-3).astype(int)
    assert data[:, 5] == pytest.approx(data[:, 0] - 0.01, abs=1e-12)
    # before each row's interval the rig held the previous command (none before 0)
    prev = [round(_profile(int(j) - 20)["base_speed"], 3) if j >= 20 else 0.0 for j in k_rows]
    assert data[:, 6] == pytest.approx(prev, abs=1e-9)
    assert np.diff(data[:, 0]) == pytest.approx(np.full(59, 0.01))
    assert data[0, 0] == pytest.approx(0.01) and data[-1, 0] == pytest.approx(0.6)
    # each row holds the feedback of that instant (the log's first frame is at t = 0)
    roles = ("out.base_speed", "in.load", "out.base_torque", "out.follower_speed")
    for col, role in enumerate(roles, start=1):
        want = _series(gear_dbc, live, role)
        assert data[:, col].tolist() == [want[round(t, 9)] for t in data[:, 0]], role

    # inputs from the commands instead: the command the rig applied in the
    # interval ending at each row, i.e. the one sent 10 periods before the row
    rec = log_to_measurement(log, gear_dbc, source="command")
    assert rec.sources["base_speed"] == "GearCmd.BaseSpeedCmd"
    k = np.rint(rec.columns["time"] / 1e-3).astype(int)
    expected = [round(_profile(int(j) - 10)["base_speed"], 3) for j in k]
    assert rec.columns["base_speed"] == pytest.approx(expected, abs=1e-9)


def test_rack_log_to_csv_with_temperature(tmp_path: Path, rack_dbc: RigDbc) -> None:
    log = tmp_path / "rack.blf"
    record_session(
        rack_model(),
        rack_dbc,
        log,
        lambda k: {"base_speed": 8.0 * math.sin(k / 60.0), "load": 30.0},
        periods=500,
    )
    rec = log_to_measurement(log, rack_dbc, temperature=True, dt=0.02)
    assert list(rec.columns) == [
        "time",
        "pinion_speed",
        "load_force",
        "pinion_torque",
        "rack_velocity",
        "temperature",
    ]
    assert rec.rows == 21 and rec.dt == 0.02  # from 0.1 s: the first temperature frame
    assert np.all(rec.columns["load_force"] == 30.0)
    assert np.all(rec.columns["temperature"] > 0)


def test_log_without_feedback_is_refused(tmp_path: Path, gear_dbc: RigDbc) -> None:
    import can

    log = tmp_path / "cmds.log"
    with can.Logger(str(log)) as logger:
        for k in range(50):
            for m in gear_dbc.encode_command({"cmd.base_speed": 1.0}):
                m.timestamp = k * 0.01
                logger.on_message_received(m)
    with pytest.raises(RecordingError, match="base_torque"):
        log_to_measurement(log, gear_dbc)


def test_analysis_judges_the_model_against_the_recording(
    tmp_path: Path, gear_dbc: RigDbc, capsys: pytest.CaptureFixture
) -> None:
    """A recording of the bridge made at the measurement's own step compares
    with the same model to within the DBC quantization; `gearsim compare`
    reads the CSV."""
    analysis = pytest.importorskip("gearsim.analysis")
    model = gear_model()
    log = tmp_path / "bench.blf"
    record_session(model, gear_dbc, log, _profile, periods=120, period=0.01, timeout=0.2)
    # to-csv is told the run's period: the rig was stepped every 10 ms
    rec = log_to_measurement(log, gear_dbc, period=0.01)
    assert rec.time_base == "rig" and rec.rig_dt == 0.01
    path = tmp_path / "bench.csv"
    write_csv(path, rec)
    meas = analysis.load_measurement(str(path), "simple_gear")
    # default options: the first line tells the analysis to feed the held
    # inputs as the rig applied them, unfiltered, one rig step per row here
    assert meas.time_base.is_rig and meas.time_base.steps_per_row == 1
    result = analysis.compare(model, meas)
    assert result.inputs.cutoffs["base_speed"] is None
    assert result.nrmse < 1e-3, result.nrmse

    from gearsim.cli import main

    toml = tmp_path / "model.toml"
    model.save(toml)
    capsys.readouterr()
    assert main(["compare", str(path), "--model", str(toml), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report["outputs"]) == {"base_torque", "follower_speed"}

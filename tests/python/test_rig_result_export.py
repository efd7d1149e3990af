"""RigResult to a CSV file, a DataFrame and a Parquet file: the values a user
reads back are the values the rig returned, bit for bit."""

from __future__ import annotations

import importlib.util
import os

import numpy as np
import pytest

import gearsim


def _run(n: int = 50) -> tuple[gearsim.RigResult, np.ndarray]:
    rig = gearsim.GearRig(dt=1e-3, friction_model="constant_efficiency", efficiency_const=0.9)
    t = np.arange(n) * 1e-3
    return rig.run(base_speed=5.0 * np.sin(2 * np.pi * 3 * t), load=0.4), t


def test_csv_round_trips_every_value(tmp_path):
    out, t = _run()
    path = tmp_path / "out.csv"
    out.to_csv(path, time=t)
    header = path.read_text().splitlines()[0].split(",")
    assert header == ["time", *gearsim.RigResult.FIELDS]
    back = np.loadtxt(path, delimiter=",", skiprows=1)
    assert back.shape == (len(t), 1 + len(gearsim.RigResult.FIELDS))
    np.testing.assert_array_equal(back[:, 0], t)
    np.testing.assert_array_equal(back[:, 1:], out.as_array())  # %.17g round-trips doubles


def test_csv_without_time_and_of_one_step(tmp_path):
    rig = gearsim.GearRig(dt=1e-3)
    one = rig.step(base_speed=2.0, load=0.1)
    path = tmp_path / "step.csv"
    one.to_csv(path)
    lines = path.read_text().splitlines()
    assert lines[0].split(",") == list(gearsim.RigResult.FIELDS)
    assert len(lines) == 2
    assert float(lines[1].split(",")[0]) == one.base_torque


def test_csv_replaces_atomically_and_refuses_a_wrong_time(tmp_path):
    out, t = _run(10)
    path = tmp_path / "out.csv"
    path.write_text("old\n")
    with pytest.raises(ValueError, match="time has 9 values for 10 output samples"):
        out.to_csv(path, time=t[:-1])
    assert path.read_text() == "old\n"  # untouched on failure
    assert os.listdir(tmp_path) == ["out.csv"]  # no temporary file left behind
    out.to_csv(path, time=t)
    assert path.read_text().startswith("time,")


@pytest.mark.skipif(importlib.util.find_spec("pandas") is None, reason="needs pandas")
def test_dataframe_has_the_outputs_indexed_by_time():
    out, t = _run()
    frame = out.to_dataframe(time=t)
    assert list(frame.columns) == list(gearsim.RigResult.FIELDS)
    assert frame.index.name == "time"
    np.testing.assert_array_equal(frame.index.to_numpy(), t)
    np.testing.assert_array_equal(frame["base_torque"].to_numpy(), out.base_torque)
    assert list(out.to_dataframe().columns) == list(gearsim.RigResult.FIELDS)


@pytest.mark.skipif(
    importlib.util.find_spec("pyarrow") is None or importlib.util.find_spec("pandas") is None,
    reason="needs pandas and pyarrow",
)
def test_parquet_round_trips_every_value(tmp_path):
    import pandas as pd

    out, t = _run()
    path = tmp_path / "out.parquet"
    out.to_parquet(path, time=t)
    back = pd.read_parquet(path)
    assert list(back.columns) == ["time", *gearsim.RigResult.FIELDS]
    np.testing.assert_array_equal(back["time"].to_numpy(), t)
    np.testing.assert_array_equal(back[list(gearsim.RigResult.FIELDS)].to_numpy(), out.as_array())

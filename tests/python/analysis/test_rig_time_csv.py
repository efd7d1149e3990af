"""A rig-time CSV of `gearsim hil to-csv` (first line ``# gearsim hil to-csv:
time_base=rig rig_dt=H held=COLUMNS``, columns ``inputs_since`` and
``<input>_before``): the loader keeps its facts, the simulation steps the
model as the rig was stepped, bad first lines are refused naming the line."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from analysis_helpers import base_model

from gearsim.analysis import MeasurementError, load_measurement
from gearsim.analysis.measurement import MeasurementWarning
from gearsim.analysis.simulate import (
    expand_to_rig_steps,
    prepare_inputs,
    rig_steps_of,
    row_samples,
    simulate,
)
from gearsim.cli import main

RIG_DT = 0.001  # s
STEPS = 4  # rig steps per row: rows every 4 ms
ROWS = 20  # the loader's minimum
HEADER = (
    "time,base_speed,load_torque,base_torque,follower_speed,"
    "inputs_since,base_speed_before,load_torque_before"
)
MARKER = "# gearsim hil to-csv: time_base=rig rig_dt=0.001 held=base_speed,load_torque"

# The first three rows, by hand: (time, speed, load, inputs_since, speed before,
# load before). Row 0: held all along. Row 1: a new speed from 6 ms, mid-interval
# (steps starting at 4 and 5 ms had the old speed). Row 2: a new speed and load
# from 11 ms (only the last step, starting at 11 ms, had them).
HAND_ROWS = (
    (0.004, 1.0, 0.5, 0.000, 0.0, 0.0),
    (0.008, 2.0, 0.5, 0.006, 1.0, 0.5),
    (0.012, 3.0, -0.5, 0.011, 2.0, 0.5),
)
# What the rig applied at each 1 ms step of those rows, written out by hand.
HAND_SPEED = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 3.0]
HAND_LOAD = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, -0.5]


def _rows() -> list[tuple[float, ...]]:
    """The hand rows, then rows holding the last inputs all along."""
    rows = list(HAND_ROWS)
    for j in range(len(HAND_ROWS), ROWS):
        t = (j + 1) * STEPS * RIG_DT
        rows.append((t, 3.0, -0.5, t - STEPS * RIG_DT, 3.0, -0.5))
    return rows


def _csv_text(
    marker: str = MARKER, header: str = HEADER, rows: list[tuple[float, ...]] | None = None
) -> str:
    lines = [marker, header] if marker else [header]
    for t, speed, load, since, speed_before, load_before in rows or _rows():
        # outputs: any numbers (the loader does not judge them)
        lines.append(f"{t!r},{speed!r},{load!r},0.1,{speed / 3!r},{since!r},")
        lines[-1] += f"{speed_before!r},{load_before!r}"
    return "\n".join(lines) + "\n"


def _write(tmp_path: Path, text: str, name: str = "rig.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _hand_fine(hand: list[float], last: float) -> np.ndarray:
    """The whole fine-grid sequence: the hand-written steps, then the held value."""
    return np.array(hand + [last] * (STEPS * (ROWS - len(HAND_ROWS))))


# -- the expansion -------------------------------------------------------------------
def test_loader_keeps_the_rig_time_facts_and_columns(tmp_path: Path) -> None:
    meas = load_measurement(_write(tmp_path, _csv_text()), "simple_gear")
    base = meas.time_base
    assert base is not None and base.is_rig
    assert base.rig_dt == 0.001 and base.held == ("base_speed", "load_torque")
    assert base.steps_per_row == 4
    assert meas["inputs_since"][:3].tolist() == [0.0, 0.006, 0.011]
    assert meas["base_speed_before"][:3].tolist() == [0.0, 1.0, 2.0]
    assert any("stepped every 0.001 s, 4 steps per row" in n for n in meas.notes)


def test_held_inputs_expand_to_the_steps_the_rig_applied(tmp_path: Path) -> None:
    meas = load_measurement(_write(tmp_path, _csv_text()), "simple_gear")
    steps = rig_steps_of(meas)
    assert steps is not None
    assert steps.steps_before[:3].tolist() == [0, 2, 3]
    speed = expand_to_rig_steps(meas["base_speed"], steps, steps.before["base_speed"])
    load = expand_to_rig_steps(meas["load_torque"], steps, steps.before["load_torque"])
    assert speed.tolist() == _hand_fine(HAND_SPEED, 3.0).tolist()
    assert load.tolist() == _hand_fine(HAND_LOAD, -0.5).tolist()
    # an input without earlier values (e.g. a temperature) is held over its row
    assert expand_to_rig_steps(np.array([5.0, 6.0]), steps.slice(0, 2)).tolist() == [
        5.0,
        5.0,
        5.0,
        5.0,
        6.0,
        6.0,
        6.0,
        6.0,
    ]
    # each row is compared with the value after its interval's last step
    assert row_samples(np.arange(12.0), steps.slice(0, 3)).tolist() == [3.0, 7.0, 11.0]


def test_inputs_since_a_hair_off_the_step_grid_counts_as_on_it(tmp_path: Path) -> None:
    """Times in the text are rounded (to-csv: 9 digits); half a step of slack."""
    rows = _rows()
    rows[1] = (0.008, 2.0, 0.5, 0.0060000004, 1.0, 0.5)
    rows[2] = (0.012, 3.0, -0.5, 0.0109999996, 2.0, 0.5)
    meas = load_measurement(_write(tmp_path, _csv_text(rows=rows)), "simple_gear")
    assert rig_steps_of(meas).steps_before[:3].tolist() == [0, 2, 3]


@pytest.mark.parametrize("input_filter", ["auto", 5.0, None])
def test_simulation_steps_the_model_as_the_rig_was_stepped(
    tmp_path: Path, input_filter: float | str | None
) -> None:
    """The outputs are those of the model's rig run at 1 ms on the hand-written
    step sequence, sampled after each row's last step; no filter touches the
    held inputs (the explicit 5 Hz cut-off included)."""
    meas = load_measurement(_write(tmp_path, _csv_text()), "simple_gear")
    model = base_model("simple_gear")
    inputs = prepare_inputs(meas, input_filter)
    assert inputs.cutoffs["base_speed"] is None and inputs.cutoffs["load_torque"] is None
    sim = simulate(model, meas, inputs)
    rig = model.rig(dt=RIG_DT)
    ref = rig.run(base_speed=_hand_fine(HAND_SPEED, 3.0), load=_hand_fine(HAND_LOAD, -0.5))
    for name in ("base_torque", "follower_speed"):
        expected = np.asarray(getattr(ref, name))[STEPS - 1 :: STEPS]
        assert sim.outputs[name].shape == (ROWS,)
        np.testing.assert_allclose(sim.outputs[name], expected, rtol=0, atol=1e-12)
    assert sim.signals["follower_speed"].shape == (ROWS,)


def test_a_fitting_slice_keeps_the_rig_steps(tmp_path: Path) -> None:
    meas = load_measurement(_write(tmp_path, _csv_text()), "simple_gear")
    part = prepare_inputs(meas).slice(1, 3)
    assert part.rig_steps is not None
    assert part.rig_steps.steps_before.tolist() == [2, 3]
    assert part.rig_steps.before["base_speed"].tolist() == [1.0, 2.0]
    # keeping every other row loses what the rig applied between them
    assert meas.slice(0, ROWS, 2).time_base is None


def test_files_without_the_first_line_keep_their_reading(tmp_path: Path) -> None:
    """No marker: the extra columns are ignored and the model runs once per row."""
    meas = load_measurement(_write(tmp_path, _csv_text(marker="")), "simple_gear")
    assert meas.time_base is None and "inputs_since" not in meas.data
    assert prepare_inputs(meas, None).rig_steps is None
    # a commented header after the first line is still taken as the header
    text = _csv_text().replace(HEADER, "# " + HEADER)
    meas = load_measurement(_write(tmp_path, text, "commented.csv"), "simple_gear")
    assert meas.time_base.is_rig and any("comment line 2" in n for n in meas.notes)


# -- bad first lines -----------------------------------------------------------------
@pytest.mark.parametrize(
    "marker, says",
    [
        (MARKER.replace("rig_dt=0.001", "rig_dt=abc"), "rig_dt=abc"),
        (MARKER.replace("rig_dt=0.001", "rig_dt=-0.001"), "rig_dt=-0.001"),
        (MARKER.replace("rig_dt=0.001", "rig_dt=nan"), "rig_dt=nan"),
        (MARKER.replace(" rig_dt=0.001", ""), "rig_dt="),
        # 4 ms rows are 2.67 rig steps of 1.5 ms
        (MARKER.replace("rig_dt=0.001", "rig_dt=0.0015"), "rig_dt=0.0015"),
        (MARKER.replace("held=base_speed", "held=motor_speed"), "held=motor_speed"),
        (MARKER.replace("load_torque", "base_torque"), "'base_torque'"),
        (MARKER.replace("time_base=rig", "time_base=bus"), "time_base=bus"),
        (MARKER + " stray", "'stray'"),
    ],
)
def test_a_bad_first_line_is_refused_naming_the_line_and_key(
    tmp_path: Path, marker: str, says: str
) -> None:
    path = _write(tmp_path, _csv_text(marker=marker))
    with pytest.raises(MeasurementError) as err:
        load_measurement(path, "simple_gear")
    assert err.value.line == 1
    message = str(err.value)
    assert message.startswith(f"{path}, line 1: ") and says in message
    assert "\n" not in message


@pytest.mark.parametrize("dropped", ["inputs_since", "load_torque_before"])
def test_a_rig_time_csv_without_its_columns_is_refused(tmp_path: Path, dropped: str) -> None:
    names = HEADER.split(",")
    keep = [i for i, n in enumerate(names) if n != dropped]
    lines = _csv_text().splitlines()
    text = "\n".join([lines[0]] + [",".join(np.array(ln.split(","))[keep]) for ln in lines[1:]])
    with pytest.raises(MeasurementError) as err:
        load_measurement(_write(tmp_path, text + "\n"), "simple_gear")
    assert err.value.line == 2 and err.value.column == dropped
    assert "time_base=rig" in str(err.value)


def test_inputs_since_outside_its_row_is_refused(tmp_path: Path) -> None:
    rows = _rows()
    rows[4] = (*rows[4][:3], rows[4][0] + 0.002, *rows[4][4:])  # after the row itself
    with pytest.raises(MeasurementError) as err:
        load_measurement(_write(tmp_path, _csv_text(rows=rows)), "simple_gear")
    assert err.value.line == 2 + 1 + 4 and err.value.column == "inputs_since"


def test_a_bad_first_line_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    path = _write(tmp_path, _csv_text(marker=MARKER.replace("0.001", "0.0015")))
    model = tmp_path / "model.toml"
    base_model("simple_gear").save(model)
    capsys.readouterr()
    assert main(["compare", str(path), "--model", str(model)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{path}, line 1" in err[0] and "rig_dt=0.0015" in err[0]


# -- wall-clock CSVs -----------------------------------------------------------------
WALL = "# gearsim hil to-csv: time_base=wall"


def test_a_wall_clock_csv_is_read_with_one_warning(tmp_path: Path) -> None:
    path = _write(tmp_path, _csv_text(marker=WALL))
    heard: list[str] = []
    meas = load_measurement(path, "simple_gear", note=heard.append)
    warned = [h for h in heard if "warning" in h]
    assert len(warned) == 1 and "gearsim hil run --log" in warned[0]
    assert "step for step" in warned[0]
    assert meas.time_base is not None and not meas.time_base.is_rig
    assert rig_steps_of(meas) is None
    with pytest.warns(MeasurementWarning, match="wall-clock"):
        load_measurement(path, "simple_gear")


def test_a_wall_clock_csv_warns_once_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    path = _write(tmp_path, _csv_text(marker=WALL))
    model = tmp_path / "model.toml"
    base_model("simple_gear").save(model)
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["compare", str(path), "--model", str(model)]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(err) == 1 and "gearsim hil run --log" in err[0]

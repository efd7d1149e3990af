"""gearsim.columns is the one definition of the measurement columns: it agrees
with the contract (docs/measurement-format.md section 1) and with the rig's
signal names, and the analysis and the HIL recording derive from it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import gearsim
from gearsim import columns
from gearsim.columns import OPTIONAL, RIGS, TIME

ROOT = Path(__file__).resolve().parents[2]

_SECTIONS = {"simple_gear": "### 1.1 ", "rack_pinion": "### 1.2 "}
_ROW = re.compile(r"^\|\s*`(?P<name>[a-z_]+)`\s*\|\s*(?P<kind>[a-z ]+?)\s*\|\s*(?P<unit>\S+)\s*\|")


def _contract_table(block: str) -> list[tuple[str, str, str]]:
    """(name, used as, unit) of each row of the block's column table."""
    text = (ROOT / "docs" / "measurement-format.md").read_text()
    section = text[text.index(_SECTIONS[block]) :]
    section = section[: section.index("\n### ", 1)]
    rows = [_ROW.match(line) for line in section.splitlines()]
    kinds = {"time axis": "time"}
    return [(m["name"], kinds.get(m["kind"], m["kind"]), m["unit"]) for m in rows if m]


@pytest.mark.parametrize("block", sorted(RIGS))
def test_columns_are_the_contract(block):
    rig = RIGS[block]
    ours = [(c.name, c.kind, c.unit) for c in (*rig.required, *OPTIONAL)]
    assert ours == _contract_table(block)


@pytest.mark.parametrize("block", sorted(RIGS))
def test_columns_map_onto_rig_signals(block):
    rig = RIGS[block]
    assert TIME.rig_input is None and TIME.rig_output is None
    for col in (*rig.inputs, *OPTIONAL):
        assert col.rig_input in gearsim.INPUT_NAMES, col
    for col in rig.outputs:
        assert col.rig_input is None
        assert col.rig_output in gearsim.OUTPUT_NAMES, col
    for col in (*rig.inputs, *OPTIONAL):
        assert col.rig_output is None or col.rig_output in gearsim.OUTPUT_NAMES, col
    # one name for the driven shaft inside the rig, the contract's outside
    assert rig.speed_output.rig_output == "follower_speed"
    assert rig.column(rig.speed_output.name) is rig.speed_output
    assert rig.column("no_such_column") is None


def test_analysis_derives_from_the_table():
    from gearsim.analysis.measurement import OPTIONAL_INPUTS, RIG_SPECS

    assert set(RIG_SPECS) == set(RIGS)
    assert OPTIONAL_INPUTS == tuple(c.name for c in OPTIONAL)
    for block, spec in RIG_SPECS.items():
        rig = RIGS[block]
        assert spec.required == tuple(c.name for c in rig.required)
        assert spec.driven_name == rig.driven
        assert spec.driven_force_unit == rig.driven_force_unit
        for col in (*rig.required, *OPTIONAL):
            assert spec.unit(col.name) == col.unit
        assert spec.unit("no_such_column") == ""


def test_analysis_simulates_through_the_table_names():
    """The simulated outputs carry the contract names and equal the rig output
    each is mapped to."""
    import numpy as np

    from gearsim.analysis.measurement import Measurement
    from gearsim.analysis.simulate import simulate

    n = 200
    t = np.arange(n) * 1e-3
    meas = Measurement.from_arrays(
        "rack_pinion",
        t,
        pinion_speed=np.sin(t),
        load_force=np.zeros(n),
        pinion_torque=np.zeros(n),
        rack_velocity=np.zeros(n),
    )
    model = gearsim.Model.loads('[rig]\nblock = "rack_pinion"\n')
    sim = simulate(model, meas, signals=("base_torque", "follower_speed"))
    assert list(sim.outputs) == ["pinion_torque", "rack_velocity"]
    np.testing.assert_array_equal(sim.outputs["pinion_torque"], sim.signals["base_torque"])
    np.testing.assert_array_equal(sim.outputs["rack_velocity"], sim.signals["follower_speed"])


def test_hil_recording_derives_from_the_table():
    pytest.importorskip("can")
    pytest.importorskip("cantools")
    from gearsim.hil import COLUMNS, RigDbc

    assert COLUMNS == {block: rig.names for block, rig in RIGS.items()}
    for block, rig in RIGS.items():
        dbc = RigDbc(block=block)
        # every column has a feedback signal in the shipped DBC, and each input a command
        for col in (*rig.inputs, *rig.outputs, columns.TEMPERATURE):
            role = f"out.{col.rig_output}" if col.rig_output else f"in.{col.rig_input}"
            assert dbc.feedback_signals(role), (block, col.name, role)
        for col in rig.inputs:
            assert f"cmd.{col.rig_input}" in dbc.command_signals, (block, col.name)

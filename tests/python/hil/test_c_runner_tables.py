"""hil/dbc_tables.py, the build step that turns a DBC into the C runner's
frame tables: what it writes for the shipped DBC, and the DBCs it refuses
(exit 2, one line naming the frame and signal). Needs cantools, not the
built runner."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("cantools")

ROOT = Path(__file__).resolve().parents[3]
TABLES = ROOT / "hil" / "dbc_tables.py"
GEAR_DBC = ROOT / "hil" / "dbc" / "gear_rig.dbc"


def generate(dbc: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(TABLES), str(dbc), "gear_rig", str(out)],
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_shipped_dbc_tables(tmp_path: Path) -> None:
    out = tmp_path / "dbc_gear_rig.c"
    res = generate(GEAR_DBC, out)
    assert res.returncode == 0, res.stderr
    text = out.read_text()
    # BaseSpeedCmd: 0|24@1- (0.001,0) [-1000|1000], the driving command
    assert (
        '{"BaseSpeedCmd", 0u, 24u, 1, 0.001, 0.0, -1000.0, 1000.0, GS_HIL_ROLE_CMD_BASE_SPEED'
        in text
    )
    # FollowerAngle: 24|24@1+ (1E-006,0) [0|6.283186], the angle modulo 2*pi
    assert (
        '{"FollowerAngle", 24u, 24u, 0, 1e-06, 0.0, 0.0, 6.283186, GS_HIL_ROLE_OUT_FOLLOWER_ANGLE'
        in text
    )
    # DriveMode's value table: raw 0..3 -> Disabled, Speed, Torque, undefined
    assert "{GS_HIL_MODE_DISABLED, GS_HIL_MODE_SPEED, GS_HIL_MODE_TORQUE, -1}" in text
    # GearStatus (0x210), 100 ms, a status frame; GearCmd 0x100 a command frame
    assert '{"GearStatus", 0x210u, 0, 8u, GS_HIL_FRAME_FEEDBACK, 100u, signals_210, 12u, 1}' in text
    assert '{"GearCmd", 0x100u, 0, 8u, GS_HIL_FRAME_COMMAND, 10u, signals_100, 4u, 0}' in text


@pytest.mark.parametrize(
    "old, new, expected",
    [
        (
            "SG_ BaseTorque : 0|24@1-",
            "SG_ BaseTorque : 7|24@0-",
            "GearFbBase.BaseTorque: big-endian (Motorola) signals are not supported",
        ),
        (
            'BA_ "GenMsgCycleTime" BO_ 514 100;',
            "",
            "feedback frame GearFbThermal has no GenMsgCycleTime",
        ),
        (
            'SG_ 512 BaseSpeed "out.base_speed"',
            'SG_ 512 BaseSpeed "out.warp_speed"',
            "GearFbBase.BaseSpeed: unknown GsRole 'out.warp_speed'",
        ),
        (
            'SG_ 528 Overrun "status.flag.overrun"',
            'SG_ 528 Overrun "status.flag.overran"',
            "GearStatus.Overrun: unknown GsRole 'status.flag.overran'",
        ),
        (
            'SG_ 529 Timeouts "status.count.timeouts"',
            'SG_ 529 Timeouts "status.count.timeout"',
            "unknown GsRole 'status.count.timeout'",
        ),
        (
            "SG_ Temperature : 0|16@1+ (0.01,0) [0|655.35]",
            "SG_ Temperature : 0|16@1+ (0.01,0) [0|900]",
            "GearFbThermal.Temperature: range [0.0, 900.0] does not fit 16 unsigned bits",
        ),
    ],
)
def test_refused_dbc_is_one_line_and_exit_2(
    tmp_path: Path, old: str, new: str, expected: str
) -> None:
    text = GEAR_DBC.read_text()
    assert old in text
    bad = tmp_path / "bad.dbc"
    bad.write_text(text.replace(old, new))
    out = tmp_path / "out.c"
    res = generate(bad, out)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], res.stderr
    assert not out.exists()


def test_output_fields_come_from_the_c_core_table(tmp_path: Path) -> None:
    """The generator reads the rig's outputs from include/gearsim/fields.h; the
    compiled core exports the same X-macro list as gs_rig_output_info. Both
    readings must give the 15 fields of docs/c-api.md, in struct order."""
    rig = pytest.importorskip("gearsim.rig")
    spec = importlib.util.spec_from_file_location("dbc_tables_under_test", TABLES)
    tables = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tables)
    fields = tables.rig_output_fields()
    assert len(fields) == 15
    assert fields[0] == "base_torque" and fields[-1] == "follower_acceleration"
    assert fields == rig.OUTPUT_NAMES
    # an output the shipped DBC does not carry is accepted and indexed by name
    text = GEAR_DBC.read_text().replace(
        'SG_ 512 BaseSpeed "out.base_speed"', 'SG_ 512 BaseSpeed "out.contact_energy"'
    )
    dbc = tmp_path / "energy.dbc"
    dbc.write_text(text)
    out = tmp_path / "energy.c"
    res = generate(dbc, out)
    assert res.returncode == 0, res.stderr
    assert "GS_HIL_ROLE_OUT, GS_HIL_OUTPUT_INDEX(contact_energy)" in out.read_text()

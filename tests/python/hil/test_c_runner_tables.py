"""hil/dbc_tables.py, the build step that turns a DBC into the C library's
frame tables: what it writes for the shipped DBC (the DBC's facts as they
are, roles by the names of gearsim/hil.h), and the DBCs no table can hold
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
    # BaseSpeedCmd: 0|24@1- (0.001,0) [-1000|1000], the driving command: name,
    # start, length, signed, big-endian, float, scale, offset, minimum, maximum, role
    assert (
        '{"BaseSpeedCmd", 0u, 24u, 1, 0, 0, 0.001, 0.0, -1000.0, 1000.0, '
        "GS_HIL_ROLE_CMD_BASE_SPEED, 0, NULL, 0u}" in text
    )
    # FollowerAngle: 24|24@1+ (1E-006,0) [0|6.283186], the angle modulo 2*pi
    assert (
        '{"FollowerAngle", 24u, 24u, 0, 0, 0, 1e-06, 0.0, 0.0, 6.283186, '
        "GS_HIL_ROLE_OUT_FOLLOWER_ANGLE, 0" in text
    )
    assert "GS_HIL_ROLE_OUT, GS_HIL_OUTPUT_INDEX(base_torque)" in text
    assert "GS_HIL_ROLE_STATUS_FLAG, GS_HIL_FLAG_CMD_TIMEOUT" in text
    assert "GS_HIL_ROLE_STATUS_COUNT, GS_HIL_COUNT_RX_USED" in text
    # DriveMode's value table as the DBC has it (the library reads the names)
    assert '{{0, "Disabled"}, {1, "Speed"}, {2, "Torque"}}' in text
    # GearStatus (0x210), 8 bytes, 100 ms, not multiplexed, 16 signals
    assert '{"GearStatus", 0x210u, 0, 8u, 100u, 0, signals_210, 16u}' in text
    assert '{"GearCmd", 0x100u, 0, 8u, 10u, 0, signals_100, 4u}' in text
    assert 'gs_hil_dbc_gear_rig = {"gear_rig", GS_RIG_SIMPLE_GEAR, frames, 9u}' in text


def test_facts_are_written_as_the_dbc_gives_them(tmp_path: Path) -> None:
    """The generator knows no rules: a big-endian signal, a range wider than
    its bits are written as they are (gs_hil_dbc_check judges them when a
    bridge is set up; test_hil_codec.py checks its verdicts)."""
    text = GEAR_DBC.read_text()
    text = text.replace("SG_ BaseTorque : 0|24@1-", "SG_ BaseTorque : 7|24@0-")
    text = text.replace('[0|655.35] "K"', '[0|900] "K"')
    dbc = tmp_path / "facts.dbc"
    dbc.write_text(text)
    out = tmp_path / "facts.c"
    res = generate(dbc, out)
    assert res.returncode == 0, res.stderr
    assert '{"BaseTorque", 7u, 24u, 1, 1, 0, 0.0001' in out.read_text()
    assert '{"Temperature", 0u, 16u, 0, 0, 0, 0.01, 0.0, 0.0, 900.0,' in out.read_text()


@pytest.mark.parametrize(
    "old, new, expected",
    [
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
            'BA_ "GsBlock" "simple_gear";',
            'BA_ "GsBlock" "worm_gear";',
            "GsBlock 'worm_gear' is not one of simple_gear, rack_pinion",
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


def test_the_names_are_read_from_the_c_headers() -> None:
    """The generator's role, flag and counter names are the lists of
    gearsim/hil.h, which the compiled library (and so the Python package)
    names the same way."""
    from gearsim.hil import names

    tables = _load_tables()
    known = tables.Names()
    flags = [n for _, n in tables.x_list(str(tables.HIL_HEADER), "GS_HIL_FLAG_LIST")]
    counts = [n for _, n in tables.x_list(str(tables.HIL_HEADER), "GS_HIL_COUNT_LIST")]
    assert tuple(flags) == names.STATUS_FLAGS and tuple(counts) == names.STATUS_COUNTS
    for role in (*names.COMMAND_ROLES, *names.INPUT_ROLES, "status.counter"):
        assert known.role(role)[0] == "GS_HIL_ROLE_" + role.replace(".", "_").upper()
    assert known.role("out.follower_angle") == ("GS_HIL_ROLE_OUT_FOLLOWER_ANGLE", "0")
    assert known.blocks == {
        "simple_gear": "GS_RIG_SIMPLE_GEAR",
        "rack_pinion": "GS_RIG_RACK_PINION",
    }


def _load_tables():
    spec = importlib.util.spec_from_file_location("dbc_tables_under_test", TABLES)
    tables = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tables)
    return tables


def test_output_fields_come_from_the_c_core_table(tmp_path: Path) -> None:
    """The generator reads the rig's outputs from include/gearsim/fields.h; the
    compiled core exports the same X-macro list as gs_rig_output_info. Both
    readings must give the 15 fields of docs/c-api.md, in struct order."""
    rig = pytest.importorskip("gearsim.rig")
    fields = _load_tables().rig_output_fields()
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

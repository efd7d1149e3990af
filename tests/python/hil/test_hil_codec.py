"""The shipped DBCs and the range-checked codec."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hil_helpers import RigDbc, can, gearsim

from gearsim.hil import DbcError, Rejection, shipped_dbc
from gearsim.hil.codec import OUTPUT_FIELDS


def test_output_roles_match_the_bindings() -> None:
    assert set(OUTPUT_FIELDS) == set(gearsim.OUTPUT_NAMES)


@pytest.mark.parametrize(
    "rig, block, cmd_id, feedback_ids",
    [
        ("gear", "simple_gear", 0x100, {0x200: 10, 0x201: 10, 0x202: 100, 0x210: 100, 0x211: 100}),
        ("rack", "rack_pinion", 0x110, {0x300: 10, 0x301: 10, 0x302: 100, 0x310: 100, 0x311: 100}),
    ],
)
def test_shipped_dbc_layout(
    rig: str, block: str, cmd_id: int, feedback_ids: dict[int, int]
) -> None:
    dbc = RigDbc(block=rig)
    assert dbc.block == block
    assert shipped_dbc(rig).is_file()
    assert list(dbc.commands) == [(cmd_id, False)]
    assert {f.frame_id: round(f.cycle_time * 1000) for f in dbc.feedback} == feedback_ids
    assert set(dbc.command_signals) == {"cmd.base_speed", "cmd.base_torque", "cmd.load", "cmd.mode"}
    for role in (
        "out.base_torque",
        "out.base_speed",
        "out.follower_speed",
        "out.temperature",
        "out.loss_power",
        "out.backlash_position",
        "in.load",
        "status.counter",
        "status.flag.cmd_timeout",
        "status.count.rx_used",
        "status.count.rx_rejected",
        "status.count.rx_late",
        "status.count.rx_ignored",
    ):
        assert dbc.feedback_signals(role), role
    position = "out.follower_angle" if rig == "gear" else "out.follower_position"
    assert dbc.feedback_signals(position)
    # status frames are encoded after the data frames of the same period
    assert [f.is_status for f in dbc.feedback] == sorted(f.is_status for f in dbc.feedback)


def test_block_mismatch_is_an_error() -> None:
    with pytest.raises(DbcError, match="simple_gear"):
        RigDbc(shipped_dbc("gear"), block="rack")


def _cmd(dbc: RigDbc):
    return next(iter(dbc.commands.values()))


def test_decode_command_checks_length_choices_and_range(gear_dbc: RigDbc) -> None:
    frame = _cmd(gear_dbc)
    ok = gear_dbc.encode_command({"cmd.base_speed": 12.5, "cmd.load": -0.25, "cmd.mode": "speed"})[
        0
    ]
    values = gear_dbc.decode_command(frame, ok.data)
    assert values == {
        "cmd.base_speed": 12.5,
        "cmd.base_torque": 0.0,
        "cmd.load": -0.25,
        "cmd.mode": "speed",
    }
    short = gear_dbc.decode_command(frame, ok.data[:7])
    assert isinstance(short, Rejection) and short.reason == "bad_length"
    long = gear_dbc.decode_command(frame, bytes(ok.data) + b"\0")
    assert isinstance(long, Rejection) and long.reason == "bad_length"
    bad_mode = bytearray(ok.data)
    bad_mode[7] |= 0x03  # DriveMode = 3: no such value
    r = gear_dbc.decode_command(frame, bad_mode)
    assert isinstance(r, Rejection) and r.reason == "undecodable"
    raw = frame.message.encode(
        {"BaseSpeedCmd": 1500.0, "MotorTorqueCmd": 0, "LoadTorqueCmd": 0, "DriveMode": 1},
        strict=False,
    )
    r = gear_dbc.decode_command(frame, raw)
    assert isinstance(r, Rejection) and r.reason == "out_of_range"
    assert "BaseSpeedCmd" in r.detail


def test_encode_feedback_saturates_and_never_wraps(gear_dbc: RigDbc) -> None:
    frame = next(f for f in gear_dbc.feedback if f.name == "GearFbBase")
    data, saturated = gear_dbc.encode_feedback(
        frame, {"out.base_torque": 1e6, "out.base_speed": -1e9, "in.load": math.nan}
    )
    assert sorted(saturated) == ["BaseSpeed", "BaseTorque", "LoadTorque"]
    back = gear_dbc.decode_feedback(frame, data)
    assert back["out.base_torque"] == pytest.approx(838.8607)
    assert back["out.base_speed"] == pytest.approx(-8388.608)
    assert back["in.load"] == 0.0
    data, saturated = gear_dbc.encode_feedback(
        frame, {"out.base_torque": 1.23456, "out.base_speed": -7.5, "in.load": 0.5}
    )
    assert saturated == []
    back = gear_dbc.decode_feedback(frame, data)
    assert back["out.base_torque"] == pytest.approx(1.2346, abs=0.5e-4)
    assert back["out.base_speed"] == -7.5


def test_counters_roll_over_by_design(gear_dbc: RigDbc) -> None:
    frame = next(f for f in gear_dbc.feedback if f.name == "GearStatus")
    values = {s.role: 0 for s in frame.signals}
    values.update({"status.counter": 17, "status.count.rx_used": 65536 + 5})
    data, saturated = gear_dbc.encode_feedback(frame, values)
    back = gear_dbc.decode_feedback(frame, data)
    assert back["status.counter"] == 1 and back["status.count.rx_used"] == 5
    assert saturated == []


_HEADER = """VERSION ""
NS_ :
BS_:
BU_: H R
"""
_ATTRS = """BA_DEF_ BO_  "GenMsgCycleTime" INT 0 65535;
BA_DEF_ SG_  "GsRole" STRING ;
BA_DEF_DEF_  "GenMsgCycleTime" 0;
BA_DEF_DEF_  "GsRole" "";
"""


@pytest.mark.parametrize(
    "body, match",
    [
        (
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-500|500] "N*m" H\n\n'
            + _ATTRS
            + 'BA_ "GenMsgCycleTime" BO_ 512 10;\nBA_ "GsRole" SG_ 512 T "out.base_torque";\n',
            "does not fit",
        ),
        (
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-300|300] "N*m" H\n\n'
            + _ATTRS
            + 'BA_ "GsRole" SG_ 512 T "out.base_torque";\n',
            "no GenMsgCycleTime",
        ),
        (
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-300|300] "N*m" H\n\n'
            + _ATTRS
            + 'BA_ "GenMsgCycleTime" BO_ 512 10;\nBA_ "GsRole" SG_ 512 T "out.base_torqeu";\n',
            "unknown GsRole",
        ),
    ],
)
def test_bad_dbc_is_refused(tmp_path: Path, body: str, match: str) -> None:
    p = tmp_path / "bad.dbc"
    p.write_text(_HEADER + "\n" + body)
    with pytest.raises(DbcError, match=match):
        RigDbc(p, block="gear")


def test_unreadable_dbc(tmp_path: Path) -> None:
    with pytest.raises(DbcError, match="no such file"):
        RigDbc(tmp_path / "missing.dbc")
    p = tmp_path / "junk.dbc"
    p.write_text("this is not a DBC")
    with pytest.raises(DbcError):
        RigDbc(p, block="gear")


def test_encode_command_is_strict(gear_dbc: RigDbc) -> None:
    with pytest.raises(Exception, match="BaseSpeedCmd"):
        gear_dbc.encode_command({"cmd.base_speed": 5000.0})
    msgs = gear_dbc.encode_command({"cmd.base_speed": 1.0})
    assert isinstance(msgs[0], can.Message) and msgs[0].arbitration_id == 0x100


def test_docs_name_every_frame_and_role() -> None:
    doc = Path(__file__).resolve().parents[3] / "docs" / "hil.md"
    if not doc.is_file():
        pytest.skip("docs/hil.md is not next to the tests")
    text = doc.read_text()
    for rig in ("gear", "rack"):
        dbc = RigDbc(block=rig)
        for f in dbc.frames:
            assert f"`{f.name}`" in text and f"0x{f.frame_id:03X}" in text, f.name
    for flag in (
        "CmdTimeout",
        "SafeState",
        "DriveDisabled",
        "CmdRejected",
        "CmdLate",
        "FbSaturated",
        "Overrun",
        "TxError",
    ):
        assert flag in text

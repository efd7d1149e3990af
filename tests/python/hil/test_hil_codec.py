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
        (
            "gear",
            "simple_gear",
            0x100,
            {0x200: 10, 0x201: 10, 0x202: 100, 0x210: 100, 0x211: 100, 0x212: 100},
        ),
        (
            "rack",
            "rack_pinion",
            0x110,
            {0x300: 10, 0x301: 10, 0x302: 100, 0x310: 100, 0x311: 100, 0x312: 100},
        ),
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


def _fb(body: str, roles: dict[str, str], cycle: bool = True, frame_id: int = 512) -> str:
    """A DBC text: _HEADER, body (BO_/SG_ lines), the attribute definitions,
    the cycle time of frame_id and a GsRole per signal name."""
    text = _HEADER + "\n" + body + "\n" + _ATTRS
    if cycle:
        text += f'BA_ "GenMsgCycleTime" BO_ {frame_id} 10;\n'
    for name, role in roles.items():
        ident, _, sig = name.partition(".")
        text += f'BA_ "GsRole" SG_ {ident} {sig} "{role}";\n'
    return text


# Each DBC breaks one rule of gs_hil_dbc_check (the C library's), which
# RigDbc and the bridges apply; the message names frame and signal.
_BAD = [
    (
        _fb(
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-500|500] "N*m" H\n',
            {"512.T": "out.base_torque"},
        ),
        "Fb.T: range [-500, 500] does not fit 16 signed bits at scale 0.01 ([-327.68, 327.67])",
    ),
    (
        _fb(
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-300|300] "N*m" H\n',
            {"512.T": "out.base_torque"},
            cycle=False,
        ),
        "feedback frame Fb has no GenMsgCycleTime",
    ),
    (
        _fb(
            'BO_ 512 Fb: 2 R\n SG_ T : 0|16@1- (0.01,0) [-300|300] "N*m" H\n',
            {"512.T": "out.base_torqeu"},
        ),
        "Fb.T: unknown GsRole 'out.base_torqeu'",
    ),
    (
        _fb(
            'BO_ 512 St: 2 R\n SG_ C : 0|16@1- (1,0) [0|100] "" H\n',
            {"512.C": "status.count.rx_used"},
        ),
        "St.C: a counter must be an unsigned integer signal (scale 1, offset 0)",
    ),
    (
        _fb(
            'BO_ 512 St: 1 R\n SG_ F : 0|1@1+ (1,2) [2|3] "" H\n', {"512.F": "status.flag.overrun"}
        ),
        "St.F: a flag must hold 0 and 1",
    ),
    (
        _fb(
            'BO_ 512 Mix: 4 H\n SG_ L : 0|16@1- (0.001,0) [-30|30] "N*m" R\n'
            ' SG_ T : 16|16@1- (0.001,0) [-30|30] "N*m" R\n',
            {"512.L": "cmd.load", "512.T": "out.base_torque"},
        ),
        "Mix mixes command and feedback roles",
    ),
    (
        _fb(
            'BO_ 256 A: 2 H\n SG_ L : 0|16@1- (0.001,0) [-30|30] "N*m" R\n\n'
            'BO_ 257 B: 2 H\n SG_ K : 0|16@1- (0.001,0) [-30|30] "N*m" R\n',
            {"256.L": "cmd.load", "257.K": "cmd.load"},
            cycle=False,
        ),
        "command role 'cmd.load' is on A.L and on B.K",
    ),
    (
        _fb(
            'BO_ 256 Cmd: 1 H\n SG_ M : 0|2@1+ (1,0) [0|2] "" R\n',
            {"256.M": "cmd.mode"},
            cycle=False,
        )
        + 'VAL_ 256 M 0 "Off" 1 "Fast" 2 "Torque" ;\n',
        "Cmd.M: mode value 1 is named 'Fast'; expected one of Disabled, Speed, Torque",
    ),
    (
        _fb(
            'BO_ 512 Fd: 16 R\n SG_ T : 0|16@1- (0.01,0) [-300|300] "N*m" H\n',
            {"512.T": "out.base_torque"},
        ),
        "Fd: 16 data bytes; command and feedback frames are classic CAN frames of at most 8",
    ),
]


@pytest.mark.parametrize("text, match", _BAD)
def test_bad_dbc_is_refused(tmp_path: Path, text: str, match: str) -> None:
    p = tmp_path / "bad.dbc"
    p.write_text(text)
    with pytest.raises(DbcError) as info:
        RigDbc(p, block="gear")
    assert match in str(info.value) and str(p) in str(info.value)


_ENDIAN_DBC = (
    _fb(
        'BO_ 512 Fb: 8 R\n SG_ T : 7|24@0- (0.0001,0) [-800|800] "N*m" H\n'
        ' SG_ F : 24|32@1- (1,0.5) [-1000|1000] "" H\n'
        ' SG_ S : 63|8@0+ (0.5,0) [0|100] "" H\n\n'
        'BO_ 256 Cmd: 8 H\n SG_ W : 7|24@0- (0.001,0) [-1000|1000] "rad/s" R\n'
        ' SG_ L : 24|32@1- (1,0) [-30|30] "N*m" R\n SG_ M : 56|2@1+ (1,0) [0|2] "" R\n',
        {
            "512.T": "out.base_torque",
            "512.F": "out.follower_speed",
            "512.S": "out.temperature",
            "256.W": "cmd.base_speed",
            "256.L": "cmd.load",
            "256.M": "cmd.mode",
        },
    )
    + "SIG_VALTYPE_ 512 F : 1;\nSIG_VALTYPE_ 256 L : 1;\n"
)


def test_big_endian_and_float_signals_agree_with_cantools(tmp_path: Path) -> None:
    """Motorola integer and IEEE float signals (which the C codec encodes and
    decodes itself): seeded random values, clamped by the C codec, give the
    bytes cantools' strict encoding gives for the clamped values; commands
    cantools encodes decode to its values."""
    import random

    path = tmp_path / "endian.dbc"
    path.write_text(_ENDIAN_DBC)
    dbc = RigDbc(path, block="gear")
    fb = next(iter(dbc.feedback))
    cmd = next(iter(dbc.commands.values()))
    rng = random.Random(23)
    for _ in range(400):
        values = {
            "out.base_torque": rng.choice([rng.uniform(-900, 900), rng.uniform(-1, 1)]),
            "out.follower_speed": rng.uniform(-1200, 1200),
            "out.temperature": rng.uniform(-10, 120),
        }
        data, saturated = dbc.encode_feedback(fb, values)
        clamped = {s.name: min(max(values[s.role], s.minimum), s.maximum) for s in fb.signals}
        assert data == fb.message.encode(clamped, scaling=True, strict=True)
        assert sorted(saturated) == sorted(
            s.name for s in fb.signals if clamped[s.name] != values[s.role]
        )
        back = dbc.decode_feedback(fb, data)
        ref = fb.message.decode(data, decode_choices=False)
        assert back == {s.role: float(ref[s.name]) for s in fb.signals}
        w, load = round(rng.uniform(-1000, 1000), 3), rng.uniform(-30, 30)
        payload = cmd.message.encode({"W": w, "L": load, "M": 1}, strict=True)
        decoded = dbc.decode_command(cmd, payload)
        ref = cmd.message.decode(payload, decode_choices=False)
        assert decoded == {
            "cmd.base_speed": float(ref["W"]),
            "cmd.load": float(ref["L"]),
            "cmd.mode": "speed",
        }


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

"""Build step of the C HIL runner: a DBC file -> the C tables of its frames.

    python dbc_tables.py DBC NAME OUT.c

cantools reads the DBC (the one source of IDs, lengths, scaling, ranges, cycle
times and signal roles, docs/hil.md); this script writes a C file defining
``const gs_hil_dbc gs_hil_dbc_<NAME>`` (gearsim/hil.h) for the runner's
hand-written codec. It runs at build time (hil/CMakeLists.txt); the output
lives in the build directory and is never checked in.

The checks are those of the Python bridge's loader (unknown roles, a command
role on two signals, frames mixing command and feedback roles, feedback
without a cycle time, feedback ranges wider than their raw bits, counters
that are not unsigned integers), plus what the C codec does not do: signals
must be little-endian (Intel) integers in classic frames of at most 8 bytes.
Any failure prints one line naming the file, frame and signal, exit status 2.
"""

from __future__ import annotations

import math
import os
import sys

ROLE_ATTRIBUTE = "GsRole"
BLOCK_ATTRIBUTE = "GsBlock"
COMMAND_ROLES = {
    "cmd.base_speed": "GS_HIL_ROLE_CMD_BASE_SPEED",
    "cmd.base_torque": "GS_HIL_ROLE_CMD_BASE_TORQUE",
    "cmd.load": "GS_HIL_ROLE_CMD_LOAD",
    "cmd.mode": "GS_HIL_ROLE_CMD_MODE",
}
INPUT_ROLES = {
    "in.base_speed": "GS_HIL_ROLE_IN_BASE_SPEED",
    "in.base_torque": "GS_HIL_ROLE_IN_BASE_TORQUE",
    "in.load": "GS_HIL_ROLE_IN_LOAD",
}
OUTPUT_FIELDS = (
    "base_torque",
    "base_speed",
    "base_angle",
    "follower_speed",
    "follower_position",
    "base_port_torque",
    "follower_port_torque",
    "mesh_loss_power",
    "loss_power",
    "port_power",
    "contact_energy",
    "temperature",
    "backlash_position",
    "contact_force",
    "follower_acceleration",
)
STATUS_FLAGS = (
    "cmd_timeout",
    "safe_state",
    "drive_disabled",
    "cmd_rejected",
    "cmd_late",
    "fb_saturated",
    "overrun",
    "tx_error",
)
STATUS_COUNTS = (
    "rx_total",
    "rx_used",
    "rx_rejected",
    "rx_late",
    "rx_ignored",
    "tx_frames",
    "tx_errors",
    "timeouts",
    "recoveries",
    "overruns",
    "resyncs",
    "saturations",
    "periods",
)
MODE_NAMES = {
    "disabled": "GS_HIL_MODE_DISABLED",
    "disable": "GS_HIL_MODE_DISABLED",
    "off": "GS_HIL_MODE_DISABLED",
    "safe": "GS_HIL_MODE_DISABLED",
    "speed": "GS_HIL_MODE_SPEED",
    "torque": "GS_HIL_MODE_TORQUE",
}
DEFAULT_MODE_VALUES = {0: "disabled", 1: "speed", 2: "torque"}
BLOCKS = {"simple_gear": "GS_RIG_SIMPLE_GEAR", "rack_pinion": "GS_RIG_RACK_PINION"}
MAX_MODE_BITS = 8


class TableError(Exception):
    pass


def c_double(x: float) -> str:
    """A C double literal that reads back as exactly x (repr is the shortest
    round-trip form; C's strtod rounds it to the same double)."""
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "-HUGE_VAL"
    text = repr(float(x))
    return text if ("e" in text or "." in text) else text + ".0"


def c_string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def role_of(sig) -> str | None:
    if sig.dbc is not None and ROLE_ATTRIBUTE in sig.dbc.attributes:
        return str(sig.dbc.attributes[ROLE_ATTRIBUTE].value).strip() or None
    return None


def role_code(role: str) -> tuple[str, str]:
    """(gs_hil_role, aux) of a role; TableError if unknown."""
    if role in COMMAND_ROLES:
        return COMMAND_ROLES[role], "0"
    if role in INPUT_ROLES:
        return INPUT_ROLES[role], "0"
    if role == "out.follower_angle":
        return "GS_HIL_ROLE_OUT_FOLLOWER_ANGLE", "0"
    if role.startswith("out.") and role[4:] in OUTPUT_FIELDS:
        return "GS_HIL_ROLE_OUT", f"GS_HIL_OUTPUT_INDEX({role[4:]})"
    if role == "status.counter":
        return "GS_HIL_ROLE_STATUS_COUNTER", "0"
    if role.startswith("status.flag.") and role[12:] in STATUS_FLAGS:
        return "GS_HIL_ROLE_STATUS_FLAG", f"GS_HIL_FLAG_{role[12:].upper()}"
    if role.startswith("status.count.") and role[13:] in STATUS_COUNTS:
        return "GS_HIL_ROLE_STATUS_COUNT", f"GS_HIL_COUNT_{role[13:].upper()}"
    raise TableError(f"unknown GsRole {role!r}")


def raw_limits(length: int, signed: bool) -> tuple[int, int]:
    if signed:
        return -(1 << (length - 1)), (1 << (length - 1)) - 1
    return 0, (1 << length) - 1


def signal_entry(msg, sig, role: str | None, out: list[str]) -> str:
    where = f"{msg.name}.{sig.name}"
    if sig.byte_order != "little_endian":
        raise TableError(
            f"{where}: big-endian (Motorola) signals are not supported by the C runner"
        )
    if sig.is_float:
        raise TableError(f"{where}: float signals are not supported by the C runner")
    if sig.start + sig.length > 64:
        raise TableError(f"{where}: does not fit 64 bits")
    scale, offset = float(sig.scale), float(sig.offset)
    lo_raw, hi_raw = raw_limits(sig.length, sig.is_signed)
    a, b = lo_raw * scale + offset, hi_raw * scale + offset
    lo_phys, hi_phys = min(a, b), max(a, b)
    minimum = lo_phys if sig.minimum is None else float(sig.minimum)
    maximum = hi_phys if sig.maximum is None else float(sig.maximum)
    if minimum > maximum:
        raise TableError(f"{where}: minimum {minimum} > maximum {maximum}")
    tol = abs(scale) * 1e-6
    if (
        role is not None
        and not role.startswith("cmd.")
        and (minimum < lo_phys - tol or maximum > hi_phys + tol)
    ):
        raise TableError(f"{where}: range [{minimum}, {maximum}] does not fit its raw bits")
    if role and (role.startswith("status.count.") or role == "status.counter"):
        if sig.is_signed or scale != 1.0 or offset != 0.0:
            raise TableError(f"{where}: a counter must be an unsigned integer signal")
    if role and role.startswith("status.flag.") and (minimum > 0 or maximum < 1):
        raise TableError(f"{where}: a flag must hold 0 and 1")
    code, aux = ("GS_HIL_ROLE_NONE", "0") if role is None else role_code(role)
    modes = "NULL"
    mode_choices = 0
    if role == "cmd.mode":
        if sig.length > MAX_MODE_BITS:
            raise TableError(f"{where}: a mode signal has at most {MAX_MODE_BITS} bits")
        names = {int(k): str(v) for k, v in sig.choices.items()} if sig.choices else None
        mode_choices = 1 if names else 0
        table = []
        for raw in range(lo_raw, hi_raw + 1):
            # the Python bridge looks the mode up by int(physical value)
            value = int(raw * scale + offset)
            name = (names or DEFAULT_MODE_VALUES).get(value)
            if name is not None and name.strip().lower() not in MODE_NAMES:
                raise TableError(f"{where}: mode value {value} is named {name!r}")
            table.append(MODE_NAMES[name.strip().lower()] if name is not None else "-1")
        array = f"modes_{msg.frame_id:x}_{sig.name}"
        out.append(f"static const signed char {array}[{len(table)}] = {{{', '.join(table)}}};")
        modes = array
    return (
        f"    {{{c_string(sig.name)}, {sig.start}u, {sig.length}u, {int(sig.is_signed)}, "
        f"{c_double(scale)}, {c_double(offset)}, {c_double(minimum)}, {c_double(maximum)}, "
        f"{code}, {aux}, {modes}, {mode_choices}}},"
    )


def frame_kind(msg, roles: list[str]) -> str:
    is_cmd = any(r.startswith("cmd.") for r in roles)
    is_fb = any(not r.startswith("cmd.") for r in roles)
    if is_cmd and is_fb:
        raise TableError(f"{msg.name} mixes command and feedback roles")
    if (is_cmd or is_fb) and msg.is_multiplexed():
        raise TableError(
            f"{msg.name}: multiplexed frames are not supported for commands or feedback"
        )
    return (
        "GS_HIL_FRAME_COMMAND"
        if is_cmd
        else "GS_HIL_FRAME_FEEDBACK"
        if is_fb
        else "GS_HIL_FRAME_OTHER"
    )


def generate(path: str, name: str) -> str:
    import cantools

    db = cantools.database.load_file(path, database_format="dbc", strict=True)
    attrs = db.dbc.attributes if db.dbc is not None else {}
    block = attrs[BLOCK_ATTRIBUTE].value if BLOCK_ATTRIBUTE in attrs else ""
    if block not in BLOCKS:
        raise TableError(f"GsBlock {block!r} is neither 'simple_gear' nor 'rack_pinion'")
    head: list[str] = []
    frames: list[str] = []
    seen_roles: dict[str, str] = {}
    for msg in db.messages:
        if msg.length > 8 or msg.is_fd:
            raise TableError(f"{msg.name}: the C runner handles classic CAN frames of <= 8 bytes")
        roles = [r for r in (role_of(s) for s in msg.signals) if r]
        kind = frame_kind(msg, roles)
        cycle_ms = int(msg.cycle_time or 0)
        if kind == "GS_HIL_FRAME_FEEDBACK" and not cycle_ms:
            raise TableError(f"feedback frame {msg.name} has no GenMsgCycleTime")
        rows = []
        for sig in msg.signals:
            role = role_of(sig)
            if role and role.startswith("cmd."):
                if role in seen_roles:
                    raise TableError(
                        f"command role {role!r} is on {seen_roles[role]} "
                        f"and on {msg.name}.{sig.name}"
                    )
                seen_roles[role] = f"{msg.name}.{sig.name}"
            try:
                rows.append(signal_entry(msg, sig, role, head))
            except TableError as exc:
                detail = str(exc)
                raise TableError(
                    detail if detail.startswith(msg.name) else f"{msg.name}.{sig.name}: {detail}"
                ) from None
        array = f"signals_{msg.frame_id:x}"
        head.append(
            f"static const gs_hil_signal {array}[{len(rows)}] = {{\n" + "\n".join(rows) + "\n};"
        )
        is_status = int(any(r.startswith("status.") for r in roles))
        frames.append(
            f"    {{{c_string(msg.name)}, 0x{msg.frame_id:X}u, {int(bool(msg.is_extended_frame))}, "
            f"{msg.length}u, {kind}, {cycle_ms}u, {array}, {len(rows)}u, {is_status}}},"
        )
    if len(frames) > 32:
        raise TableError("more than GS_HIL_MAX_FRAMES (32) frames")
    lines = [
        f"/* Generated from {os.path.basename(path)} by hil/dbc_tables.py at build time. */",
        "#include <math.h>",
        "#include <stddef.h>",
        '#include "gearsim/hil.h"',
        "",
        *head,
        "",
        f"static const gs_hil_frame_spec frames[{len(frames)}] = {{",
        *frames,
        "};",
        "",
        f"const gs_hil_dbc gs_hil_dbc_{name} = "
        f"{{{c_string(name)}, {BLOCKS[block]}, frames, {len(frames)}u}};",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    if len(argv) != 4:
        print("usage: dbc_tables.py DBC NAME OUT.c", file=sys.stderr)
        return 2
    path, name, out = argv[1:]
    try:
        text = generate(path, name)
    except TableError as exc:
        print(f"{path}: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # cantools raises many kinds on a bad file
        print(f"{path}: not a usable DBC file: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    tmp = out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

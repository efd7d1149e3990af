"""Build step of the C HIL runner: a DBC file -> the C tables of its frames.

    python dbc_tables.py DBC NAME OUT.c

cantools reads the DBC (the one source of IDs, lengths, scaling, ranges, cycle
times and signal roles, docs/hil.md); this script writes a C file defining
``const gs_hil_dbc gs_hil_dbc_<NAME>`` (gearsim/hil.h) for the runner's
hand-written codec. It runs at build time (hil/CMakeLists.txt); the output
lives in the build directory and is never checked in. The names it accepts
are not listed here: roles, status flags, counters and modes come from
bindings/python/gearsim/hil/dbc_rules.py (read by path; the Python codec
imports it), the rig's output fields from include/gearsim/fields.h.

The checks are those of the Python bridge's loader: the signal and frame
rules of dbc_rules.py (ranges wider than their raw bits, counters that are not
unsigned integers, flags, frames mixing command and feedback roles, feedback
without a cycle time), unknown roles and a command role on two signals; plus
what the C codec does not do: signals must be little-endian (Intel) integers
in classic frames of at most 8 bytes.
Any failure prints one line naming the file, frame and signal, exit status 2.
"""

from __future__ import annotations

import importlib.util
import math
import os
import re
import sys

SOURCE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The role, flag, counter and mode names and the signal and frame rules: the
# same module the Python codec imports, loaded by path (it has no imports), so
# that building the runner needs neither an installed gearsim nor its compiled
# extension.
DBC_RULES_PATH = os.path.join(SOURCE_ROOT, "bindings", "python", "gearsim", "hil", "dbc_rules.py")
# The rig's output fields: the C core's one table of names.
FIELDS_HEADER_PATH = os.path.join(SOURCE_ROOT, "include", "gearsim", "fields.h")


def load_dbc_rules(path: str = DBC_RULES_PATH):
    spec = importlib.util.spec_from_file_location("gearsim_hil_dbc_rules", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rig_output_fields(path: str = FIELDS_HEADER_PATH) -> tuple[str, ...]:
    """Field names of GS_RIG_OUTPUT_LIST in fields.h, in order: every entry
    there is one line ``X(type, name, unit, unit, "description")``."""
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    match = re.search(r"#define GS_RIG_OUTPUT_LIST\(X\)(.*?)\n\s*\n", text, re.S)
    if match is None:
        raise RuntimeError(f"{path}: no GS_RIG_OUTPUT_LIST")
    names = tuple(re.findall(r"\bX\(\s*\w+\s*,\s*(\w+)\s*,", match.group(1)))
    if not names:
        raise RuntimeError(f"{path}: GS_RIG_OUTPUT_LIST has no fields")
    return names


RULES = load_dbc_rules()
OUTPUT_FIELDS = rig_output_fields()
STATUS_FLAGS = RULES.STATUS_FLAGS
STATUS_COUNTS = RULES.STATUS_COUNTS
DEFAULT_MODE_VALUES = RULES.DEFAULT_MODE_VALUES
# Each command or input role is the C enum GS_HIL_ROLE_<ROLE>, e.g.
# cmd.base_speed -> GS_HIL_ROLE_CMD_BASE_SPEED.
COMMAND_ROLES = {r: "GS_HIL_ROLE_" + r.replace(".", "_").upper() for r in RULES.COMMAND_ROLES}
INPUT_ROLES = {r: "GS_HIL_ROLE_" + r.replace(".", "_").upper() for r in RULES.INPUT_ROLES}
# A mode name (any alias) -> its gs_hil_mode enum.
MODE_NAMES = {alias: "GS_HIL_MODE_" + mode.upper() for alias, mode in RULES.MODE_ALIASES.items()}
BLOCKS = {block: "GS_RIG_" + block.upper() for block in RULES.BLOCKS}
ROLE_ATTRIBUTE = "GsRole"
BLOCK_ATTRIBUTE = "GsBlock"
MAX_MODE_BITS = 8


# The shared rules and the generator's own checks fail the same way: one line
# naming frame and signal, exit status 2.
TableError = RULES.RuleError


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


def signal_entry(msg, sig, role: str | None, out: list[str]) -> str:
    where = f"{msg.name}.{sig.name}"
    code, aux = ("GS_HIL_ROLE_NONE", "0") if role is None else role_code(role)
    # what the hand-written C codec does not handle
    if sig.byte_order != "little_endian":
        raise TableError(
            f"{where}: big-endian (Motorola) signals are not supported by the C runner"
        )
    if sig.is_float:
        raise TableError(f"{where}: float signals are not supported by the C runner")
    if sig.start + sig.length > 64:
        raise TableError(f"{where}: does not fit 64 bits")
    scale, offset = float(sig.scale), float(sig.offset)
    minimum, maximum = RULES.signal_range(
        where,
        role,
        length=sig.length,
        is_signed=bool(sig.is_signed),
        is_float=False,
        scale=scale,
        offset=offset,
        minimum=sig.minimum,
        maximum=sig.maximum,
    )
    modes = "NULL"
    mode_choices = 0
    if role == "cmd.mode":
        if sig.length > MAX_MODE_BITS:
            raise TableError(f"{where}: a mode signal has at most {MAX_MODE_BITS} bits")
        names = {int(k): str(v) for k, v in sig.choices.items()} if sig.choices else None
        mode_choices = 1 if names else 0
        table = []
        lo_raw, hi_raw = RULES.raw_limits(sig.length, sig.is_signed)
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


FRAME_KINDS = {
    "command": "GS_HIL_FRAME_COMMAND",
    "feedback": "GS_HIL_FRAME_FEEDBACK",
    "other": "GS_HIL_FRAME_OTHER",
}


def names_agree_checks() -> list[str]:
    """Compile-time checks that the C enums of gearsim/hil.h list exactly the
    flags and counters of dbc_rules.py, in the same order: a file-scope
    array type whose size is -1 (an error) when they differ."""
    checks = []
    for kind, names in (("FLAG", STATUS_FLAGS), ("COUNT", STATUS_COUNTS)):
        terms = [f"GS_HIL_{kind}_{n.upper()} == {i}" for i, n in enumerate(names)]
        terms.append(f"GS_HIL_{kind}S == {len(names)}")
        condition = " && ".join(terms)
        checks.append(
            f"typedef char gs_hil_{kind.lower()}_names_agree_with_dbc_rules_py"
            f"[({condition}) ? 1 : -1];"
        )
    return checks


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
        kind = FRAME_KINDS[
            RULES.frame_kind(
                msg.name,
                roles,
                has_cycle_time=bool(msg.cycle_time),
                is_multiplexed=msg.is_multiplexed(),
            )
        ]
        cycle_ms = int(msg.cycle_time or 0)
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
        *names_agree_checks(),
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

"""Build step of the C HIL library: a DBC file -> the C table of its frames.

    python dbc_tables.py DBC NAME OUT.c

cantools reads the DBC (the one source of IDs, lengths, scaling, ranges, cycle
times, value tables and signal roles, docs/hil.md); this script writes a C
file defining ``const gs_hil_dbc gs_hil_dbc_<NAME>`` (gearsim/hil.h) with
those facts as they are. It runs at build time (hil/CMakeLists.txt); the
output lives in the build directory and is never checked in.

It knows no names and no rules of its own. A signal's GsRole text becomes its
gs_hil_role enumerator and aux by the lists of gearsim/hil.h (roles, flags,
counters) and include/gearsim/fields.h (the rig's outputs), read here as
text; GsBlock becomes a gs_rig_block of include/gearsim/rig.h. What a table
must satisfy (ranges that fit their bits, frame kinds, counters, flags, mode
names, ...) is checked by the library itself, gs_hil_dbc_check, when a
bridge is set up, and by a CTest on the built tables. Refused here is only
what a table cannot hold: an unknown role or block, and more frames than
gearsim/hil.h allows. Any failure prints one line naming the file, frame and
signal, exit status 2.
"""

from __future__ import annotations

import math
import os
import re
import sys

SOURCE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HIL_HEADER = os.path.join(SOURCE_ROOT, "hil", "include", "gearsim", "hil.h")
FIELDS_HEADER = os.path.join(SOURCE_ROOT, "include", "gearsim", "fields.h")
RIG_HEADER = os.path.join(SOURCE_ROOT, "include", "gearsim", "rig.h")
ROLE_ATTRIBUTE = "GsRole"
BLOCK_ATTRIBUTE = "GsBlock"


class TableError(Exception):
    """A DBC that no frame table can hold; the message names frame and signal."""


def _list_body(text: str, macro: str, path: str) -> str:
    match = re.search(rf"#define {macro}\(X\)((?:[^\n]*\\\n)*[^\n]*)", text)
    if match is None:
        raise RuntimeError(f"{path}: no {macro}")
    return match.group(1)


def x_list(path: str, macro: str) -> list[tuple[str, str]]:
    """The entries of an X-macro list ``X(SUFFIX, "name")`` of a header, in order."""
    with open(path, encoding="utf-8") as fh:
        body = _list_body(fh.read(), macro, path)
    entries = re.findall(r'\bX\(\s*(\w+)\s*,\s*"([^"]*)"\s*\)', body)
    if not entries:
        raise RuntimeError(f"{path}: {macro} has no entries")
    return entries


def rig_output_fields(path: str = FIELDS_HEADER) -> tuple[str, ...]:
    """Field names of GS_RIG_OUTPUT_LIST in fields.h, in order (each entry is
    ``X(type, name, unit, unit, "description")``)."""
    with open(path, encoding="utf-8") as fh:
        body = _list_body(fh.read(), "GS_RIG_OUTPUT_LIST", path)
    names = tuple(re.findall(r"\bX\(\s*\w+\s*,\s*(\w+)\s*,", body))
    if not names:
        raise RuntimeError(f"{path}: GS_RIG_OUTPUT_LIST has no fields")
    return names


def rig_blocks(path: str = RIG_HEADER) -> dict[str, str]:
    """GsBlock value -> gs_rig_block enumerator ("simple_gear" -> GS_RIG_SIMPLE_GEAR)."""
    with open(path, encoding="utf-8") as fh:
        match = re.search(r"typedef enum\s*\{([^}]*)\}\s*gs_rig_block;", fh.read())
    if match is None:
        raise RuntimeError(f"{path}: no gs_rig_block")
    return {e[len("GS_RIG_") :].lower(): e for e in re.findall(r"\b(GS_RIG_\w+)", match.group(1))}


class Names:
    """The names gearsim/hil.h and fields.h give roles, flags and counters."""

    def __init__(self) -> None:
        self.roles = x_list(HIL_HEADER, "GS_HIL_ROLE_LIST")
        self.families = {
            "OUT": {f: f"GS_HIL_OUTPUT_INDEX({f})" for f in rig_output_fields()},
            "STATUS_FLAG": {
                n: f"GS_HIL_FLAG_{s}" for s, n in x_list(HIL_HEADER, "GS_HIL_FLAG_LIST")
            },
            "STATUS_COUNT": {
                n: f"GS_HIL_COUNT_{s}" for s, n in x_list(HIL_HEADER, "GS_HIL_COUNT_LIST")
            },
        }
        self.blocks = rig_blocks()

    def role(self, text: str) -> tuple[str, str]:
        """(gs_hil_role enumerator, aux) of a GsRole text; TableError if unknown.
        Whole names before families, as gs_hil_role_parse."""
        for suffix, name in self.roles:
            if name and not name.endswith(".") and name == text:
                return f"GS_HIL_ROLE_{suffix}", "0"
        for suffix, name in self.roles:
            if name.endswith(".") and text.startswith(name):
                aux = self.families.get(suffix, {}).get(text[len(name) :])
                if aux is not None:
                    return f"GS_HIL_ROLE_{suffix}", aux
        raise TableError(f"unknown GsRole {text!r}")


def c_double(x: float | None, missing: str = "0.0") -> str:
    """A C double literal that reads back as exactly x (repr is the shortest
    round-trip form; C's strtod rounds it to the same double)."""
    if x is None:
        return missing
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


def signal_entry(names: Names, msg, sig, out: list[str]) -> str:
    role = role_of(sig)
    code, aux = ("GS_HIL_ROLE_NONE", "0") if role is None else names.role(role)
    choices, count = "NULL", 0
    if sig.choices:
        array = f"choices_{msg.frame_id:x}_{sig.name}"
        items = [f"{{{int(k)}, {c_string(str(v))}}}" for k, v in sig.choices.items()]
        out.append(f"static const gs_hil_choice {array}[{len(items)}] = {{{', '.join(items)}}};")
        choices, count = array, len(items)
    return (
        f"    {{{c_string(sig.name)}, {sig.start}u, {sig.length}u, {int(bool(sig.is_signed))}, "
        f"{int(sig.byte_order == 'big_endian')}, {int(bool(sig.is_float))}, "
        f"{c_double(float(sig.scale))}, {c_double(float(sig.offset))}, "
        f"{c_double(sig.minimum, '-HUGE_VAL')}, {c_double(sig.maximum, 'HUGE_VAL')}, "
        f"{code}, {aux}, {choices}, {count}u}},"
    )


def generate(path: str, name: str) -> str:
    import cantools

    names = Names()
    db = cantools.database.load_file(path, database_format="dbc", strict=True)
    attrs = db.dbc.attributes if db.dbc is not None else {}
    block = attrs[BLOCK_ATTRIBUTE].value if BLOCK_ATTRIBUTE in attrs else ""
    if block not in names.blocks:
        raise TableError(f"GsBlock {block!r} is not one of {', '.join(names.blocks)}")
    if len(db.messages) > 32:
        raise TableError("more than GS_HIL_MAX_FRAMES (32) frames")
    head: list[str] = []
    frames: list[str] = []
    for msg in db.messages:
        rows = []
        for sig in msg.signals:
            try:
                rows.append(signal_entry(names, msg, sig, head))
            except TableError as exc:
                raise TableError(f"{msg.name}.{sig.name}: {exc}") from None
        array = f"signals_{msg.frame_id:x}"
        head.append(
            f"static const gs_hil_signal {array}[{len(rows)}] = {{\n" + "\n".join(rows) + "\n};"
        )
        frames.append(
            f"    {{{c_string(msg.name)}, 0x{msg.frame_id:X}u, {int(bool(msg.is_extended_frame))}, "
            f"{msg.length}u, {int(msg.cycle_time or 0)}u, {int(bool(msg.is_multiplexed()))}, "
            f"{array}, {len(rows)}u}},"
        )
    lines = [
        f"/* Generated from {os.path.basename(path)} by hil/dbc_tables.py at build time. */",
        "#include <math.h>",
        "#include <stddef.h>",
        '#include "gearsim/hil_dbc.h"',
        "",
        *head,
        "",
        f"static const gs_hil_frame_spec frames[{len(frames)}] = {{",
        *frames,
        "};",
        "",
        f"const gs_hil_dbc gs_hil_dbc_{name} = "
        f"{{{c_string(name)}, {names.blocks[block]}, frames, {len(frames)}u}};",
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

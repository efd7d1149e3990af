#!/usr/bin/env python3
"""Flash and RAM taken by the gearsim library in a linked program, from the
GNU ld map file: sums the input sections that come from libgearsim.a (code
and constants -> flash; .data -> flash + RAM; .bss -> RAM), and separately
those from the C library (memcpy/memset) and the rest (startup, probe).

usage: map_sizes.py PROG.map [PROG.map ...]  -> one line per map:
  name gearsim_text gearsim_rodata gearsim_data gearsim_bss libc_text
  other_text other_data other_bss
"""

import os
import re
import sys

SECTION = re.compile(
    r"^ (\.[A-Za-z_.$0-9-]+|COMMON)\s*(?:\n\s+|\s+)(0x[0-9a-f]+)\s+(0x[0-9a-f]+)\s+(\S.*)$", re.M
)


def kind(section):
    if section.startswith(
        (
            ".text",
            ".init",
            ".fini",
            ".ARM.exidx",
            ".ARM.extab",
            ".vectors",
            ".glue",
            ".vfp11",
            ".v4_bx",
            ".iplt",
        )
    ):
        return "text"
    if section.startswith(".rodata"):
        return "rodata"
    if section.startswith(".data"):
        return "data"
    if section.startswith((".bss", "COMMON")):
        return "bss"
    return None


def sizes(path):
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    text = text[text.find("Linker script and memory map") :]
    out = {}
    for m in SECTION.finditer(text):
        section, _addr, size, origin = m.groups()
        k = kind(section)
        size = int(size, 16)
        if k is None or size == 0:
            continue
        if "libgearsim.a" in origin:
            owner = "gearsim"
        elif re.search(r"lib(c|c_nano|g|g_nano|m|nosys|rdimon|gcc)\.a", origin):
            owner = "libc"
        else:
            owner = "other"
        out[(owner, k)] = out.get((owner, k), 0) + size
    return out


def main():
    for path in sys.argv[1:]:
        s = sizes(path)

        def g(owner: str, section_kind: str, s: dict = s) -> int:  # this map's sizes, bound
            return s.get((owner, section_kind), 0)

        name = os.path.basename(path).rsplit(".", 1)[0]
        print(
            name,
            g("gearsim", "text"),
            g("gearsim", "rodata"),
            g("gearsim", "data"),
            g("gearsim", "bss"),
            g("libc", "text") + g("libc", "rodata"),
            g("other", "text") + g("other", "rodata"),
            g("other", "data"),
            g("other", "bss"),
        )


if __name__ == "__main__":
    main()

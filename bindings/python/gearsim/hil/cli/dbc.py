"""``gearsim hil dbc gear|rack [-o FILE]``: the path of a shipped DBC, or a copy."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..._outputs import atomic_write_bytes, check_output
from .common import show

NAME = "dbc"


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        NAME,
        help="print the path of a shipped DBC, or copy it",
        description="The DBC shipped for a rig: its path, or a copy with -o.",
    )
    p.add_argument("rig", choices=("gear", "rack"))
    p.add_argument("-o", "--out", metavar="FILE", help="copy it here")


def execute(args: argparse.Namespace) -> int:
    from ..codec import shipped_dbc

    path = shipped_dbc(args.rig)
    if args.out is None:
        print(show(path))
        return 0
    out = check_output(args.out, [path], option="--out")
    data = path.read_bytes()
    if out == "-":
        sys.stdout.write(data.decode("utf-8"))
        return 0
    atomic_write_bytes(out, data)
    print(show(out))
    return 0

"""The parameters the docs list are those of the C parameter tables
(include/gearsim/parameters.h): the generated tables of docs/python.md are
current, and the key tables and lists of docs/measurement-format.md and
docs/python-api.md name every model-file key, with its units, and no other."""

from __future__ import annotations

import re
from pathlib import Path

from gearsim import params as P

ROOT = Path(__file__).resolve().parents[2]


def test_python_md_tables_are_current():
    text = (ROOT / "docs" / "python.md").read_text()
    for table in P.doc_tables().split("\n\n"):
        assert table in text, "docs/python.md: paste gearsim.params.doc_tables() again"


def _section(text: str, start: str, end: str) -> str:
    return text[text.index(start) : text.index(end, text.index(start))]


def test_measurement_format_rig_keys_and_units():
    """docs/measurement-format.md 2.1: one row per rig key, with the gear
    rig's and the rack rig's unit."""
    text = (ROOT / "docs" / "measurement-format.md").read_text()
    table = _section(text, "### 2.1 `[rig]` keys", "### 2.2")
    rows = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].startswith("`"):
            rows[cells[0].strip("`")] = (cells[1], cells[2])
    gear = {p.name: p for p in P.GEAR_RIG_PARAMS}
    rack = {p.name: p for p in P.RACK_RIG_PARAMS}
    assert set(rows) == {"block"} | set(gear) | set(rack)
    for name, (gear_cell, rack_cell) in rows.items():
        for spec, cell in ((gear.get(name), gear_cell), (rack.get(name), rack_cell)):
            if spec is None or spec.kind in (P.OPTION, P.BOOL, P.INT):
                continue
            # pint's ** is written ^ in this table
            assert spec.unit.replace("**", "^") in cell, (name, spec.unit, cell)


def test_measurement_format_and_python_api_block_keys():
    """The key lists of measurement-format.md 2.2 name every block key, and
    python-api.md every rig key (its block keys: the tables of python.md)."""
    keys_22 = set(
        re.findall(
            r"`([a-z_]+)`",
            _section(
                (ROOT / "docs" / "measurement-format.md").read_text(),
                "### 2.2 `[block]` keys",
                "### 2.3",
            ),
        )
    )
    api = _section(
        (ROOT / "docs" / "python-api.md").read_text(),
        "## Parameters and model files",
        "```python",
    )
    keys_api = set(re.findall(r"`([a-z_]+)`", api))
    for specs in (P.SIMPLE_GEAR_PARAMS, P.RACK_PINION_PARAMS):
        for p in specs:
            assert p.name in keys_22, f"measurement-format.md 2.2 misses {p.name}"
    for p in (*P.GEAR_RIG_PARAMS, *P.RACK_RIG_PARAMS):
        assert p.name in keys_api, f"python-api.md misses {p.name}"

"""load_measurement: the stages of reading a measurement file, in order."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import replace

from ..._outputs import printable
from . import rig_time, sniff, table, units
from .record import Measurement, Notes, rig_spec
from .source import STDIN, read_text
from .validate import validate_table


def load_measurement(
    path: str | os.PathLike[str],
    block: str,
    *,
    columns: Mapping[str, str] | None = None,
    resample: bool = False,
    max_gap: int | None = None,
    note: Callable[[str], None] | None = None,
) -> Measurement:
    """Read and check a measurement CSV for the rig of `block`
    ("simple_gear" or "rack_pinion"); `path` "-" reads standard input. See
    :mod:`gearsim.analysis.measurement`. `note(message)` receives one-line notes on how the file
    was read (separator, units, ...) and warnings (prefixed "warning:").
    `max_gap`: with `resample`, the longest run of missing samples that may be
    interpolated (None or 0: any; a longer gap is refused); every gap filled is
    noted."""
    spec = rig_spec(block)
    path_s = os.fspath(path)
    label = "<stdin>" if path_s == STDIN else path_s
    shown = printable(label, 160)
    notes = Notes(shown, note)
    columns = sniff.check_column_map(columns, spec, shown)

    text = read_text(path_s, shown, notes)
    marker = rig_time.read_marker(text.data, spec, shown)
    layout = sniff.find_layout(text, shown)
    wanted = sniff.find_columns(layout, spec, columns, shown)
    wanted += rig_time.rig_time_columns(marker, layout, spec, shown)
    layout = sniff.number_format(layout, wanted, notes)
    units.convert_units(wanted, spec, shown, layout.header.line, notes)

    values, line_of = table.read_table(text, layout, wanted, shown)
    units.to_si(values, wanted)
    units.check_time_scale(values, wanted, notes)
    meas = validate_table(
        values,
        [c.canonical for c in wanted],
        spec,
        label,
        resample=resample,
        max_gap=max_gap,
        line_of=line_of,
        source_names={c.canonical: c.shown for c in wanted},
        shown=shown,
    )
    for n in meas.notes:
        notes.info(n)
    time_base = rig_time.check_time_base(meas, marker, notes, shown, line_of)
    return replace(meas, notes=tuple(notes.items), time_base=time_base)

"""Measurement files (docs/measurement-format.md section 1): load, check, hold.

A measurement is loaded and checked once, at the edge; everything behind
:func:`load_measurement` works on validated, finite, uniformly sampled arrays.

What is read (gearsim reads whatever a logger wrote):

- plain or compressed files: gzip, bzip2, xz and zstd (``.gz``, ``.bz2``,
  ``.xz``, ``.zst``), recognised by their magic bytes whatever the file is
  called (the extension alone is not trusted); ``"-"`` reads standard input;
- UTF-8 (with or without BOM) or Latin-1 text; anything else (binary data, NUL
  bytes, UTF-16/32 text, ZIP/Excel/MATLAB/HDF5 files) is refused with one line
  saying what the file is;
- the separator is sniffed (``,`` ``;`` or tab; an Excel ``sep=;`` first line
  is honoured) and, with ``;`` or tab, a decimal comma (``1,5``); leading
  ``#`` comment lines are skipped (a commented header, as ``np.savetxt``
  writes it, is used);
- a unit in the header (``time [ms]``, ``base_speed (rpm)``,
  ``base_torque [mN*m]``) is converted with pint to the SI unit of the
  canonical column; a unit that cannot be converted is an error naming the
  column, the unit and how to map it.

Checks, each reported as a :class:`MeasurementError` naming file, line (1-based,
the header is line 1 unless blank lines precede it) and column:
missing or unreadable file, not a text CSV, no header, no data rows, a required
column missing, a cell that is not a number, NaN or infinity, time not strictly
increasing, sampling that is not uniform (a sample more than half a step away
from the uniform grid; pass ``resample=True`` to interpolate onto a uniform grid
instead), fewer than 20 samples. Extra columns are ignored and never parsed,
except those a rig-time CSV of ``gearsim hil to-csv`` needs (below).

A first line ``# gearsim hil to-csv: time_base=rig rig_dt=H held=COLUMNS``
(what ``gearsim hil to-csv`` writes for a log in rig time) is kept as
:attr:`Measurement.time_base`, with its ``inputs_since`` and
``<input>_before`` columns in :attr:`Measurement.data`, so that the
simulation steps the model as the rig was stepped (:mod:`.simulate`); a bad
value in that line, a row step that is not a whole number of rig steps, or a
missing column is an error naming the line. ``time_base=wall`` is warned
about: such a CSV cannot reproduce the run step for step.
User text echoed in a message goes through :func:`gearsim._outputs.printable`.

Column mapping: ``columns={"pinion_speed": "omega_rad_s"}`` reads a canonical
column from another header; the header text is taken as it is (any characters:
``"torque [N*m]"``, spaces, unicode). ``"header*factor"`` also scales it into
SI (``{"pinion_speed": "omega*0.10471975512"}``); an explicit factor replaces
the unit of that header.

Notes (separator, decimal comma, units converted, resampling) are kept in
:attr:`Measurement.notes` and passed to the ``note`` callback if one is given.
A time column that looks like milliseconds or microseconds (no unit in the
header, median step of 0.5 or more) is warned about through ``note``, or, without
a callback, as a :class:`MeasurementWarning`.

The stages, one module each, in the order :func:`load_measurement` runs them:
:mod:`.source` (the bytes, decompressed, checked to be text), :mod:`.rig_time`
(the to-csv first line, its columns, and the rows checked against it),
:mod:`.sniff` (header, separator, decimal mark, which header column is which),
:mod:`.units` (header units to SI), :mod:`.table` (the numbers, with the line
of each row) and :mod:`.validate` (the checks that make a
:class:`Measurement`). :mod:`.record` holds what they produce.
"""

from __future__ import annotations

from ...columns import BEFORE_SUFFIX, INPUTS_SINCE
from .load import load_measurement
from .record import (
    OPTIONAL_INPUTS,
    RIG_SPECS,
    Measurement,
    MeasurementWarning,
    RecordedTimeBase,
    RigSpec,
    write_measurement,
)
from .rig_time import MARKER
from .sniff import parse_column_map

# not in __all__, but read by name (the CLI checks model values against MAX_MAGNITUDE)
from .source import STDIN as STDIN
from .validate import MAX_MAGNITUDE as MAX_MAGNITUDE
from .validate import MIN_SAMPLES as MIN_SAMPLES

__all__ = [
    "RigSpec",
    "RIG_SPECS",
    "RecordedTimeBase",
    "MARKER",
    "INPUTS_SINCE",
    "BEFORE_SUFFIX",
    "OPTIONAL_INPUTS",
    "Measurement",
    "MeasurementWarning",
    "load_measurement",
    "write_measurement",
    "parse_column_map",
]

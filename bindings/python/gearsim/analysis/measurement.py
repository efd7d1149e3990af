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
"""

from __future__ import annotations

import bz2
import csv
import gzip
import io
import lzma
import math
import os
import re
import sys
import unicodedata
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .._outputs import atomic_writer, printable
from ..columns import (
    BEFORE_SUFFIX,
    INPUTS_SINCE,
    OPTIONAL,
    RIG_TIME_MARKER,
    RIGS,
    RigColumns,
)
from ..errors import caller_stacklevel
from .errors import MeasurementError
from .signals import describe_gap, sampling_gaps

#: Largest magnitude of any value (SI units) the analysis accepts: far beyond
#: any rig (1e12 rad/s, N*m, K, s), and far below what overflows the
#: simulation and the fits (a logging or unit error, not a measurement).
MAX_MAGNITUDE = 1e12

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

MIN_SAMPLES = 20
STDIN = "-"

MARKER = RIG_TIME_MARKER
#: How far (relative) the row step may be from a whole number of rig steps.
_SUBSTEP_TOLERANCE = 1e-6


class MeasurementWarning(UserWarning):
    """A measurement was read but something in it looks wrong (e.g. a time
    column that looks like milliseconds)."""


@dataclass(frozen=True)
class RigSpec:
    """The canonical columns of one rig (contract section 1), by role.

    Derived from :data:`gearsim.columns.RIGS`, the one definition of the
    columns, which the HIL recording uses too. driven_*: the driven side
    (follower shaft or rack), as texts name it."""

    block: str
    speed_input: str
    load_input: str
    torque_output: str
    speed_output: str
    speed_unit: str
    load_unit: str
    torque_unit: str
    driven_speed_unit: str
    driven_force_unit: str
    driven_name: str

    @classmethod
    def from_columns(cls, rig: RigColumns) -> RigSpec:
        return cls(
            block=rig.block,
            speed_input=rig.speed_input.name,
            load_input=rig.load_input.name,
            torque_output=rig.torque_output.name,
            speed_output=rig.speed_output.name,
            speed_unit=rig.speed_input.unit,
            load_unit=rig.load_input.unit,
            torque_unit=rig.torque_output.unit,
            driven_speed_unit=rig.speed_output.unit,
            driven_force_unit=rig.driven_force_unit,
            driven_name=rig.driven,
        )

    @property
    def columns(self) -> RigColumns:
        """The columns of this rig, with the rig signal each maps to."""
        return RIGS[self.block]

    @property
    def inputs(self) -> tuple[str, str]:
        return (self.speed_input, self.load_input)

    @property
    def outputs(self) -> tuple[str, str]:
        return (self.torque_output, self.speed_output)

    @property
    def required(self) -> tuple[str, ...]:
        return ("time", self.speed_input, self.load_input, self.torque_output, self.speed_output)

    def unit(self, column: str) -> str:
        """The SI unit of ``column`` ("" for a column this rig does not have)."""
        col = self.columns.column(column)
        return col.unit if col is not None else ""


RIG_SPECS: dict[str, RigSpec] = {block: RigSpec.from_columns(rig) for block, rig in RIGS.items()}


@dataclass(frozen=True)
class RecordedTimeBase:
    """What the first line of a ``gearsim hil to-csv`` CSV says about its rows.

    kind: "rig" (the rows are the instants at which a rig stepped every
    ``rig_dt`` seconds sent its outputs; the ``held`` input columns were held
    constant over each rig step, changing at the row's ``inputs_since``) or
    "wall" (resampled from a wall-clock log). steps_per_row: rig steps per row
    interval (the row step divided by rig_dt; 0 for "wall")."""

    kind: str
    rig_dt: float | None = None
    held: tuple[str, ...] = ()
    steps_per_row: int = 0

    @property
    def is_rig(self) -> bool:
        return self.kind == "rig"


OPTIONAL_INPUTS: tuple[str, ...] = tuple(col.name for col in OPTIONAL)


@dataclass(frozen=True)
class Measurement:
    """A validated measurement: uniform time axis and finite columns.

    time: s, strictly increasing; dt: the uniform step (s); data: canonical
    column name -> float64 array (SI units); path: where it came from (for
    messages)."""

    spec: RigSpec
    time: np.ndarray
    dt: float
    data: Mapping[str, np.ndarray]
    path: str = "<memory>"
    notes: tuple[str, ...] = field(default=())
    time_base: RecordedTimeBase | None = None
    """the to-csv first line's facts (None: a file without it)"""

    @property
    def n(self) -> int:
        return int(self.time.size)

    @property
    def block(self) -> str:
        return self.spec.block

    @property
    def has_temperature(self) -> bool:
        return "temperature" in self.data

    @property
    def has_ambient(self) -> bool:
        return "ambient_temperature" in self.data

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[name]

    def slice(self, start: int, stop: int, step: int = 1) -> Measurement:
        """Sub-measurement of samples [start:stop:step] (dt scales with step).

        Keeping every step-th row of a rig-time CSV loses what the rig applied
        between the kept rows: such a slice forgets its time base."""
        sl = slice(start, stop, step)
        return replace(
            self,
            time=self.time[sl],
            dt=self.dt * step,
            data={k: v[sl] for k, v in self.data.items()},
            time_base=self.time_base if step == 1 else None,
        )

    def with_data(self, **columns: np.ndarray) -> Measurement:
        data = dict(self.data)
        data.update({k: np.asarray(v, dtype=float) for k, v in columns.items()})
        return replace(self, data=data)

    @classmethod
    def from_arrays(
        cls, block: str, time: np.ndarray, path: str = "<memory>", **columns: np.ndarray
    ) -> Measurement:
        """Build and validate a measurement from arrays (canonical names)."""
        spec = _spec(block)
        arrays = {"time": np.asarray(time, dtype=float)}
        arrays.update({k: np.asarray(v, dtype=float) for k, v in columns.items()})
        names = [c for c in spec.required + OPTIONAL_INPUTS if c in arrays]
        for c in spec.required:
            if c not in arrays:
                raise MeasurementError(
                    f"missing column (the {block} rig needs {', '.join(spec.required)})",
                    file=path,
                    column=c,
                )
        n = arrays["time"].size
        for c in names:
            if arrays[c].shape != (n,):
                raise MeasurementError(
                    f"has {arrays[c].size} values, time has {n}", file=path, column=c
                )
        table = np.column_stack([arrays[c] for c in names])
        return _validate(table, names, spec, path, resample=False, line_of=lambda i: None)


def _spec(block: str) -> RigSpec:
    try:
        return RIG_SPECS[block]
    except KeyError:
        raise MeasurementError(
            f"unknown rig block '{block}' (expected one of {', '.join(RIG_SPECS)})"
        ) from None


def parse_column_map(items: list[str] | None) -> dict[str, str]:
    """['canonical=source[*factor]', ...] -> {canonical: 'source[*factor]'}.

    Everything after the first '=' is the source header, taken as it is (it may
    hold '=', '*', '[', spaces, unicode); surrounding quotes are removed."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        value = _unquote(value.strip())
        if not sep or not key.strip() or not value:
            raise MeasurementError(
                f"column mapping '{printable(item)}' is not CANONICAL=SOURCE[*FACTOR]"
            )
        out[key.strip()] = value
    return out


def _unquote(text: str) -> str:
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
        return text[1:-1].strip()
    return text


# ------------------------------------------------------------------ reading bytes

_COMPRESSIONS = {  # name -> extensions
    "gzip": (".gz", ".gzip", ".tgz"),
    "bzip2": (".bz2", ".bzip2"),
    "xz": (".xz", ".txz"),
    "zstd": (".zst", ".zstd"),
}
_ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"

# Files that are surely not a CSV: (signature, what it is, what to do)
_NOT_CSV = (
    (b"PK\x03\x04", "a ZIP archive (or an .xlsx workbook)", "extract or export the CSV first"),
    (b"PK\x05\x06", "an empty ZIP archive", "extract or export the CSV first"),
    (
        b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1",
        "an OLE document (an old .xls workbook?)",
        "export the sheet as CSV",
    ),
    (b"%PDF-", "a PDF document", "export the data as CSV"),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file (MATLAB v7.3 .mat?)", "export the signals as CSV"),
    (b"MATLAB 5.0 MAT-file", "a MATLAB .mat file", "export the signals as CSV"),
    (b"SQLite format 3\x00", "an SQLite database", "export the table as CSV"),
    (b"PAR1", "a Parquet file", "export it as CSV"),
    (b"\x89PNG\r\n\x1a\n", "a PNG image", "give the measurement CSV"),
    (b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive", "extract the CSV first"),
    (b"\x7fELF", "an executable (ELF)", "give the measurement CSV"),
)
_CONTROL = re.compile(rb"[\x01-\x08\x0b\x0c\x0e-\x1f\x7f]")
_NOT_CONTROL = bytes(sorted(set(range(256)) - {*range(1, 9), 11, 12, *range(14, 32), 127}))
_EOL = re.compile(rb"\r\n|\r|\n")
_EOL_TEXT = re.compile(r"\r\n|\r|\n")


def _read_source(path: str, shown: str) -> bytes:
    """All bytes of the file, or of standard input for "-"."""
    if path == STDIN:
        if sys.stdin is None:
            raise MeasurementError("there is no standard input to read", file=shown)
        stream = getattr(sys.stdin, "buffer", None) or sys.stdin
        try:
            tty = bool(sys.stdin.isatty())
        except (AttributeError, OSError, ValueError):
            tty = False
        if tty:
            raise MeasurementError(
                "standard input is a terminal; pipe or redirect the CSV into it "
                "(e.g. gearsim compare - --model M.toml < data.csv)",
                file=shown,
            )
        try:
            data = stream.read()
        except (OSError, ValueError) as exc:
            raise MeasurementError(
                f"cannot read standard input ({printable(getattr(exc, 'strerror', None) or exc)})",
                file=shown,
            ) from None
        return data.encode("utf-8") if isinstance(data, str) else bytes(data)
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        raise MeasurementError("no such file", file=shown) from None
    except IsADirectoryError:
        raise MeasurementError("is a directory, not a CSV file", file=shown) from None
    except OSError as exc:
        raise MeasurementError(
            f"cannot read ({printable(exc.strerror or exc)})", file=shown
        ) from None


def _compression_of(data: bytes) -> str | None:
    if data[:3] == b"\x1f\x8b\x08":
        return "gzip"
    if re.match(rb"BZh[1-9]1AY&SY", data[:10]) or re.fullmatch(rb"BZh[1-9]\x17rE8P\x90", data[:10]):
        return "bzip2"
    if data[:6] == b"\xfd7zXZ\x00":
        return "xz"
    if data[:4] == _ZSTD_MAGIC:
        return "zstd"
    return None


def _decompress_one(data: bytes, kind: str, shown: str) -> bytes:
    try:
        if kind == "gzip":
            return gzip.decompress(data)
        if kind == "bzip2":
            return bz2.decompress(data)
        if kind == "xz":
            return lzma.decompress(data)
        return _zstd_decompress(data, shown)
    except MeasurementError:
        raise
    except MemoryError:
        raise MeasurementError(
            f"{kind} data too large to decompress in memory", file=shown
        ) from None
    except Exception as exc:  # EOFError, OSError, zlib.error, LZMAError, ZstdError, ...
        reason = printable(str(exc) or type(exc).__name__, 90)
        raise MeasurementError(
            f"corrupt or truncated {kind} file, cannot decompress it ({reason})", file=shown
        ) from None


def _zstd_decompress(data: bytes, shown: str) -> bytes:
    try:
        import zstandard
    except ImportError:
        raise MeasurementError(
            "is zstd-compressed; reading it needs the Python package 'zstandard' of the "
            "analysis extra (pip install 'gearsim[analysis]'), or decompress it first (zstd -d)",
            file=shown,
        ) from None
    dctx = zstandard.ZstdDecompressor()
    out: list[bytes] = []
    rest = data
    while rest:
        obj = dctx.decompressobj()
        out.append(obj.decompress(rest))
        if not obj.eof:
            raise EOFError("compressed data ended before the end of the zstd frame")
        rest = obj.unused_data
    return b"".join(out)


def _decompress(data: bytes, path: str, shown: str, notes: _Notes) -> tuple[bytes, list[str]]:
    """Decompressed content (by magic bytes, nested at most 3 deep) and the
    compressions found."""
    kinds: list[str] = []
    for _ in range(3):
        kind = _compression_of(data)
        if kind is None:
            break
        data = _decompress_one(data, kind, shown)
        kinds.append(kind)
    ext = os.path.splitext(path)[1].lower() if path != STDIN else ""
    named = next((k for k, exts in _COMPRESSIONS.items() if ext in exts), None)
    if named and not kinds:
        if not data or _looks_binary(data[:65536]):
            raise MeasurementError(
                f"corrupt {named} file: the name ends in {printable(ext)} but the content "
                f"does not start with the {named} signature",
                file=shown,
            )
        notes.info(f"named {printable(ext)} but not compressed; read as plain text")
    elif named and kinds and kinds[0] != named:
        notes.info(f"named {printable(ext)} but {kinds[0]}-compressed; read as {kinds[0]}")
    return data, kinds


def _looks_binary(head: bytes) -> bool:
    if b"\x00" in head:
        return True
    ctrl = len(head.translate(None, _NOT_CONTROL))  # the control bytes only
    return ctrl > max(4, len(head) // 100)


def _check_text(data: bytes, shown: str, kinds: list[str]) -> bytes:
    """Refuses what is not a text CSV (one line saying what it is); returns the
    text bytes (a trailing DOS end-of-file mark removed)."""
    inside = f" (after {' and '.join(kinds)} decompression)" if kinds else ""
    of = f" of the {'+'.join(kinds)}-decompressed content" if kinds else ""
    if data.startswith(b"\xef\xbb\xbf"):  # UTF-8 BOM
        data = data[3:]
    for magic, what, todo in _NOT_CSV:
        if data.startswith(magic):
            raise MeasurementError(f"not a text CSV: {what}{inside}; {todo}", file=shown)
    if data[257:262] == b"ustar":
        raise MeasurementError(
            f"not a text CSV: a tar archive{inside}; extract the CSV first", file=shown
        )
    if data.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
        raise MeasurementError(
            f"UTF-32 text{inside}: save the file as UTF-8 (or plain ASCII) CSV", file=shown
        )
    head = data[:4096]
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or _utf16_without_bom(head):
        raise MeasurementError(
            f"UTF-16 text{inside}: save the file as UTF-8 (or plain ASCII) CSV", file=shown
        )
    nul = data.find(b"\x00")
    if nul >= 0:
        raise MeasurementError(
            f"not a text CSV: NUL byte at offset {nul}{of} "
            f"(it starts with '{printable(data[:16], 48)}')",
            file=shown,
        )
    if data.endswith(b"\x1a"):  # DOS end-of-file mark
        data = data[:-1]
    head = data[:65536]
    m = _CONTROL.search(head)
    if m is not None and _looks_binary(head):
        raise MeasurementError(
            f"not a text CSV: binary data (control byte 0x{m.group()[0]:02x} at offset "
            f"{m.start()}{of}) (it starts with '{printable(data[:16], 48)}')",
            file=shown,
        )
    high = len(head) - len(head.translate(None, bytes(range(128, 256))))
    if high > 0.3 * len(head):
        try:
            head.decode("utf-8")
        except UnicodeDecodeError as exc:
            if exc.start < len(head) - 4:
                raise MeasurementError(
                    f"not a text CSV: binary data (byte 0x{head[exc.start]:02x} at offset "
                    f"{exc.start}{of}) (it starts with '{printable(data[:16], 48)}')",
                    file=shown,
                ) from None
    return data


def _utf16_without_bom(head: bytes) -> bool:
    if len(head) < 8:
        return False
    head = head[: len(head) // 2 * 2]
    even, odd = head[0::2], head[1::2]
    return (odd.count(0) >= 0.9 * len(odd) and even.count(0) == 0) or (
        even.count(0) >= 0.9 * len(even) and odd.count(0) == 0
    )


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _iter_lines(data: bytes, pos: int = 0, lineno: int = 0):
    """(line number, start offset, line bytes without EOL, offset of the next line)."""
    n = len(data)
    while pos < n:
        m = _EOL.search(data, pos)
        end, nxt = (m.start(), m.end()) if m else (n, n)
        lineno += 1
        yield lineno, pos, data[pos:end], nxt
        pos = nxt


# ------------------------------------------------------------------ notes


class _Notes:
    """Notes on how a file was read: kept for Measurement.notes and passed on."""

    def __init__(self, shown: str, note: Callable[[str], None] | None) -> None:
        self.shown = shown
        self.note = note
        self.items: list[str] = []

    def info(self, msg: str) -> None:
        self.items.append(msg)
        if self.note is not None:
            self.note(f"{self.shown}: {msg}")

    def warn(self, msg: str) -> None:
        self.items.append(f"warning: {msg}")
        if self.note is not None:
            self.note(f"{self.shown}: warning: {msg}")
        else:
            warnings.warn(
                f"{self.shown}: {msg}", MeasurementWarning, stacklevel=caller_stacklevel()
            )


# ------------------------------------------------------------------ header and dialect

_SEPARATORS = (",", ";", "\t")
_SEP_NAMES = {",": "','", ";": "';'", "\t": "tab", "|": "'|'"}
_NUM_START = re.compile(r"^\s*\"?[-+]?(?:\d|\.\d)")
_SEP_LINE = re.compile(r"^\s*\"?sep=(.)\"?[ ,;]*$", re.IGNORECASE)
_COMMA_NUMBER = re.compile(r"^\s*[-+]?\d*,\d+(?:[eE][-+]?\d+)?\s*$")
_DOT_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.\d*|\.\d+)(?:[eE][-+]?\d+)?\s*$")
_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_FACTOR = re.compile(rf"^(?P<name>.*?)\s*\*\s*(?P<factor>{_FLOAT})$")
_UNIT = re.compile(r"^(?P<name>.*?\S)\s*(?:\[(?P<a>[^\[\]]*)\]|\((?P<b>[^()]*)\))$")


def _split(line: str, sep: str) -> list[str]:
    if '"' not in line:
        return line.split(sep)
    try:
        return next(csv.reader([line], delimiter=sep))
    except (csv.Error, StopIteration):
        return line.split(sep)


def _clean_header(h: str) -> str:
    h = h.replace("\ufeff", "").strip().strip('"').strip("'").strip()
    return unicodedata.normalize("NFC", h)


def _name_unit(h: str) -> tuple[str, str | None]:
    """'time [ms]' -> ('time', 'ms'); 'time' -> ('time', None)."""
    m = _UNIT.match(h)
    if not m:
        return h, None
    unit = (m.group("a") if m.group("a") is not None else m.group("b")).strip()
    if unit in ("", "-"):
        return m.group("name").strip(), None
    return m.group("name").strip(), unit


@dataclass
class _Header:
    line: int  # 1-based line number of the header
    text: str
    body_start: int  # byte offset of the first line after the header
    body_line: int  # line number of that line
    sep: str | None  # from an Excel "sep=" line
    commented: bool


def _find_header(data: bytes, shown: str, inside: str) -> _Header:
    sep_hint: str | None = None
    comments: list[tuple[int, str, int]] = []
    for lineno, _start, raw, nxt in _iter_lines(data):
        text = _decode(raw)
        s = text.strip().lstrip("\ufeff")
        if not s:
            continue
        m = _SEP_LINE.match(text.lstrip("\ufeff"))
        if m and sep_hint is None and not comments:
            sep_hint = m.group(1)
            continue
        if s.startswith(MARKER):
            continue  # facts about the rows (see _read_marker), never a header
        if s.startswith("#"):
            comments.append((lineno, s, nxt))
            continue
        if comments and _NUM_START.match(s):
            # numbers right after comment lines: the last comment is the header
            c_line, c_text, c_next = comments[-1]
            return _Header(c_line, c_text.lstrip("#").strip(), c_next, c_line + 1, sep_hint, True)
        return _Header(lineno, text, nxt, lineno + 1, sep_hint, False)
    if comments:
        raise MeasurementError(f"has only comment lines, no header row{inside}", file=shown)
    raise MeasurementError(f"is empty, no header row{inside}", file=shown)


def _sample_lines(data: bytes, start: int, first_line: int, count: int = 50) -> list[str]:
    out: list[str] = []
    for _ln, _s, raw, _n in _iter_lines(data, start, first_line - 1):
        text = _decode(raw)
        if text.strip():
            out.append(text)
            if len(out) >= count:
                break
    return out


def _sniff_separator(header: str, sample: list[str]) -> str:
    best, best_key = ",", None
    for sep in _SEPARATORS:
        nh = len(_split(header, sep))
        counts = [len(_split(s, sep)) for s in sample]
        consistent = bool(counts) and all(c == nh for c in counts)
        key = (nh >= 2, consistent, nh)
        if best_key is None or key > best_key:
            best, best_key = sep, key
    return best


def _sniff_decimal(sample: list[str], sep: str, indices: list[int]) -> str:
    if sep == ",":
        return "."
    comma = dot = 0
    for s in sample:
        row = _split(s, sep)
        for i in indices:
            if i < len(row):
                if _COMMA_NUMBER.match(row[i]):
                    comma += 1
                elif _DOT_NUMBER.match(row[i]):
                    dot += 1
    return "," if comma and not dot else "."


# ------------------------------------------------------------------ columns and units


@dataclass
class _Column:
    canonical: str
    index: int
    header: str  # the header text as written (cleaned)
    factor: float = 1.0
    offset: float = 0.0
    unit: str | None = None  # the unit found in the header
    explicit_factor: bool = False
    unit_of: str | None = None  # the canonical column whose SI unit this one has

    @property
    def si_column(self) -> str:
        return self.unit_of or self.canonical

    @property
    def shown(self) -> str:
        return printable(self.header, 60)


def _resolve(
    canonical: str,
    mapped: str | None,
    fields: list[str],
    *,
    block: str,
    spec: RigSpec,
    shown: str,
    line: int,
    how: str,
) -> _Column | None:
    """Finds the header column of `canonical` (mapped or not); None when an
    optional column is absent. Raises on missing, ambiguous or duplicated."""
    source = unicodedata.normalize("NFC", mapped) if mapped is not None else canonical
    parsed = [_name_unit(h) for h in fields]

    def exact(text: str) -> list[int]:
        return [i for i, h in enumerate(fields) if h == text]

    def bare(text: str, fold: bool = False) -> list[int]:
        if fold:
            return [i for i, (n, _u) in enumerate(parsed) if n.casefold() == text.casefold()]
        return [i for i, (n, _u) in enumerate(parsed) if n == text]

    fm = _FACTOR.match(source) if mapped is not None else None
    attempts: list[tuple[list[int], float | None]] = [(exact(source), None)]
    if fm:
        attempts.append((exact(fm.group("name")), float(fm.group("factor"))))
    attempts.append((bare(source), None))
    if fm:
        attempts.append((bare(fm.group("name")), float(fm.group("factor"))))
    attempts.append((bare(source, fold=True), None))
    for hits, factor in attempts:
        if not hits:
            continue
        if len(hits) > 1:
            listed = ", ".join(f"'{printable(fields[i], 40)}' (column {i + 1})" for i in hits[:4])
            if len({fields[i] for i in hits}) == 1:
                raise MeasurementError(
                    f"header names column '{printable(fields[hits[0]], 60)}' twice "
                    f"(columns {hits[0] + 1} and {hits[1] + 1})",
                    file=shown,
                    line=line,
                    column=printable(fields[hits[0]], 60),
                )
            raise MeasurementError(
                f"several header columns could be '{canonical}': {listed}; choose one with "
                f"--column {canonical}=HEADER",
                file=shown,
                line=line,
                column=canonical,
            )
        i = hits[0]
        col = _Column(canonical, i, fields[i], unit=parsed[i][1])
        if factor is not None:
            if not np.isfinite(factor) or factor == 0.0:
                raise MeasurementError(
                    f"scale factor '{printable(fm.group('factor'))}' of the mapping for "
                    f"'{canonical}' must be finite and non-zero",
                    file=shown,
                    column=canonical,
                )
            col.factor, col.explicit_factor = factor, True
        return col

    if mapped is not None:
        name, star, factor_text = source.rpartition("*")
        if star and (exact(name.strip()) or bare(name.strip())):
            raise MeasurementError(
                f"scale factor '{printable(factor_text.strip(), 30)}' of the mapping for "
                f"'{canonical}' is not a number",
                file=shown,
                column=canonical,
            )
    if canonical not in spec.required and mapped is None:
        return None
    have = ", ".join(f"'{printable(h, 40)}'" for h in fields[:12] if h) or "none"
    if len(fields) > 12:
        have += f", ... ({len(fields) - 12} more)"
    hint = ""
    if fields and all(_NUM_START.match(h) for h in fields if h):
        hint = " (that line holds numbers: the file has no header row?)"
    elif len(fields) == 1:
        hint = " (one field only: is the separator something else than ',', ';' or tab?)"
    elif how:
        hint = f" (read{how})"
    if canonical not in spec.required:
        raise MeasurementError(
            f"mapped column '{printable(source, 60)}' is not in the header; "
            f"the header has {have}{hint}",
            file=shown,
            line=line,
            column=printable(source, 60),
        )
    what = f" (mapped from '{printable(source, 60)}')" if mapped is not None else ""
    raise MeasurementError(
        f"missing column{what}; the {block} rig needs {', '.join(spec.required)}; "
        f"the header has {have}{hint}",
        file=shown,
        line=line,
        column=printable(source, 60),
    )


_UNIT_SPELLINGS = (
    (re.compile(r"[·⋅×]"), "*"),
    (re.compile(r"[µμ]"), "u"),
    (re.compile(r"°\s*C\b"), "degC"),
    (re.compile(r"°\s*F\b"), "degF"),
    (re.compile(r"°"), "degree"),
    (re.compile(r"²"), "**2"),
    (re.compile(r"(?<![A-Za-z])([mkMu]?)N\s*\.?\s*m(?![A-Za-z])"), r"\1N*m"),
    (re.compile(r"(?<![A-Za-z])U\s*/\s*min(?![A-Za-z])"), "rpm"),
    (re.compile(r"(?<![A-Za-z])rpm(?![A-Za-z])", re.IGNORECASE), "rpm"),
    (re.compile(r"(?<![A-Za-z])revs?(?![A-Za-z])"), "revolution"),
    (re.compile(r"(?<![A-Za-z])sec(?![A-Za-z])"), "s"),
)


def _normalize_unit(unit: str) -> str:
    u = unicodedata.normalize("NFC", unit).strip()
    for pattern, repl in _UNIT_SPELLINGS:
        u = pattern.sub(repl, u)
    return u


def _unit_conversion(col: _Column, spec: RigSpec, shown: str, line: int) -> tuple[float, float]:
    """(factor, offset) taking the header unit of `col` to the SI unit of its
    canonical column; raises naming the column, the unit and the way out."""
    from ..units import registry

    target = spec.unit(col.si_column)
    unit = col.unit or ""
    shown_unit = printable(unit, 30)
    way_out = (
        f"write a unit pint reads in the header (e.g. [{target}], [ms], [rpm], [mN*m], [degC]) "
        f"or map the column with its factor to {target}: "
        f"--column {col.canonical}='{printable(col.header, 60)}*FACTOR'"
    )
    ureg = registry()
    try:
        src = ureg.parse_units(_normalize_unit(unit))
        tgt = ureg.parse_units(target)
    except Exception:
        raise MeasurementError(
            f"unknown unit '{shown_unit}' in the header ({col.canonical} is in {target}); "
            + way_out,
            file=shown,
            line=line,
            column=col.shown,
        ) from None

    def radians(u) -> float:
        return dict(ureg.get_root_units(u)[1]._units).get("radian", 0)

    if radians(src) != radians(tgt):
        raise MeasurementError(
            f"unit '{shown_unit}' cannot be converted to {target}: "
            + (
                "it has no angle (revolutions or radians?); "
                if radians(tgt)
                else "it has an angle that the column does not; "
            )
            + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    if target == "K" and any(str(n).startswith("delta") for n in src._units):
        raise MeasurementError(
            f"unit '{shown_unit}' is a temperature difference; an absolute temperature is "
            "expected; " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    try:
        y = ureg.Quantity(np.array([0.0, 1.0]), src).to(tgt).magnitude
    except Exception:
        raise MeasurementError(
            f"unit '{shown_unit}' cannot be converted to {target} ({col.canonical}); " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        ) from None
    offset, factor = float(y[0]), float(y[1] - y[0])
    if not (np.isfinite(factor) and np.isfinite(offset)) or factor == 0.0:
        raise MeasurementError(
            f"unit '{shown_unit}' gives no usable conversion to {target}; " + way_out,
            file=shown,
            line=line,
            column=col.shown,
        )
    return factor, offset


# ------------------------------------------------------------------ loading


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
    ("simple_gear" or "rack_pinion"); `path` "-" reads standard input. See the
    module docstring. `note(message)` receives one-line notes on how the file
    was read (separator, units, ...) and warnings (prefixed "warning:").
    `max_gap`: with `resample`, the longest run of missing samples that may be
    interpolated (None or 0: any; a longer gap is refused); every gap filled is
    noted."""
    spec = _spec(block)
    path_s = os.fspath(path)
    label = "<stdin>" if path_s == STDIN else path_s
    shown = printable(label, 160)
    notes = _Notes(shown, note)
    columns = dict(columns or {})
    for key in columns:
        if key not in spec.required + OPTIONAL_INPUTS:
            raise MeasurementError(
                f"column mapping names '{printable(key, 40)}', which is not a column of the "
                f"{block} rig ({', '.join(spec.required + OPTIONAL_INPUTS)})",
                file=shown,
            )

    data, kinds = _decompress(_read_source(path_s, shown), path_s, shown, notes)
    inside = f" (after {' and '.join(kinds)} decompression)" if kinds else ""
    data = _check_text(data, shown, kinds)
    marker = _read_marker(data, spec, shown)
    hdr = _find_header(data, shown, inside)
    sample = _sample_lines(data, hdr.body_start, hdr.body_line)
    sep = hdr.sep or _sniff_separator(hdr.text, sample)
    fields = [_clean_header(h) for h in _split(hdr.text.rstrip("\r\n"), sep)]

    how = "" if sep == "," else f" with separator {_SEP_NAMES.get(sep, repr(sep))}"
    wanted: list[_Column] = []
    for canonical in spec.required + OPTIONAL_INPUTS:
        col = _resolve(
            canonical,
            columns.get(canonical),
            fields,
            block=block,
            spec=spec,
            shown=shown,
            line=hdr.line,
            how=how,
        )
        if col is not None:
            wanted.append(col)
    if marker is not None and marker.time_base.is_rig:
        wanted += _rig_time_columns(marker, fields, spec, shown, hdr.line, how)
    dec = _sniff_decimal(sample, sep, [c.index for c in wanted])
    if dec == ",":
        how += " and decimal comma" if how else " with decimal comma"
    if how:
        notes.info("read" + how)
    if hdr.commented:
        notes.info(f"header taken from the comment line {hdr.line}")

    converted: list[str] = []
    for col in wanted:
        if col.unit is None:
            continue
        if col.explicit_factor:
            notes.info(
                f"column '{col.shown}': the mapping's factor {col.factor:g} is used, "
                f"not the header unit '{printable(col.unit, 30)}'"
            )
            continue
        col.factor, col.offset = _unit_conversion(col, spec, shown, hdr.line)
        if col.factor != 1.0 or col.offset != 0.0:
            target = spec.unit(col.si_column)
            converted.append(f"'{col.shown}' {printable(col.unit, 30)} -> {target}")
    if converted:
        notes.info("converted to SI: " + ", ".join(converted))

    how_msg = f" (read{how})" if how else ""
    names = [c.canonical for c in wanted]
    table = _parse_fast(data, hdr.body_start, [c.index for c in wanted], sep, dec)
    lines: list[int] | None = None
    if table is None or not np.isfinite(table).all():
        table, lines = _parse_slow(
            data[hdr.body_start :], hdr.body_line, wanted, sep, dec, len(fields), shown, how_msg
        )
    if table.shape[0] == 0:
        raise MeasurementError(
            f"has a header (line {hdr.line}) but no data rows{inside}", file=shown
        )
    for j, col in enumerate(wanted):
        if col.factor != 1.0 or col.offset != 0.0:
            table[:, j] = table[:, j] * col.factor + col.offset

    tcol = wanted[names.index("time")]
    if tcol.unit is None and not tcol.explicit_factor:
        _check_time_scale(table[:, names.index("time")], tcol, notes)

    line_cache: list[list[int]] = [lines] if lines is not None else []

    def line_of(row: int) -> int:
        if not line_cache:
            line_cache.append(
                [
                    ln
                    for ln, _s, raw, _n in _iter_lines(data, hdr.body_start, hdr.body_line - 1)
                    if raw.strip()
                ]
            )
        found = line_cache[0]
        return found[row] if 0 <= row < len(found) else hdr.body_line + row

    meas = _validate(
        table,
        names,
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
    time_base = None
    if marker is not None:
        time_base = _check_time_base(meas, marker, notes, shown, line_of)
    return replace(meas, notes=tuple(notes.items), time_base=time_base)


# ------------------------------------------------------------------ the to-csv first line


@dataclass(frozen=True)
class _Marker:
    line: int  # 1-based line of the marker
    time_base: RecordedTimeBase


def _read_marker(data: bytes, spec: RigSpec, shown: str) -> _Marker | None:
    """The facts of a leading ``# gearsim hil to-csv: key=value ...`` line
    (docs/measurement-format.md section 1.7), or None when the first line is
    anything else. Unknown keys are ignored (a newer to-csv may add some)."""
    for lineno, _start, raw, _next in _iter_lines(data):
        text = _decode(raw).strip().lstrip("\ufeff")
        if not text:
            continue
        if not text.startswith(MARKER):
            return None
        facts: dict[str, str] = {}
        for item in text[len(MARKER) :].split():
            key, sep, value = item.partition("=")
            if not sep or not key:
                raise MeasurementError(
                    f"'{printable(item, 40)}' in the gearsim hil to-csv line is not KEY=VALUE",
                    file=shown,
                    line=lineno,
                )
            facts[key] = value
        return _Marker(lineno, _time_base_of(facts, spec, shown, lineno))
    return None


def _time_base_of(facts: dict[str, str], spec: RigSpec, shown: str, line: int) -> RecordedTimeBase:
    def bad(key: str, why: str) -> MeasurementError:
        value = printable(facts.get(key, ""), 40)
        return MeasurementError(
            f"{key}={value} in the gearsim hil to-csv line {why}", file=shown, line=line
        )

    kind = facts.get("time_base")
    if kind == "wall":
        return RecordedTimeBase("wall")
    if kind != "rig":
        raise bad("time_base", "is not 'rig' or 'wall'")
    try:
        rig_dt = float(facts.get("rig_dt", ""))
    except ValueError:
        rig_dt = math.nan
    if not (math.isfinite(rig_dt) and rig_dt > 0.0):
        raise bad("rig_dt", "is not a positive number of seconds (the rig step)")
    held: list[str] = []
    for name in filter(None, (h.strip() for h in facts.get("held", "").split(","))):
        if name not in spec.inputs:
            raise bad(
                "held",
                f"names '{printable(name, 40)}', which is not an input column of the "
                f"{spec.block} rig ({', '.join(spec.inputs)})",
            )
        if name not in held:
            held.append(name)
    return RecordedTimeBase("rig", rig_dt, tuple(held))


def _rig_time_columns(
    marker: _Marker, fields: list[str], spec: RigSpec, shown: str, line: int, how: str
) -> list[_Column]:
    """The ``inputs_since`` and ``<input>_before`` columns a rig-time CSV must have."""
    needed = {INPUTS_SINCE: "time"}
    needed.update({name + BEFORE_SUFFIX: name for name in marker.time_base.held})
    found: list[_Column] = []
    for name, unit_of in needed.items():
        col = _resolve(
            name, None, fields, block=spec.block, spec=spec, shown=shown, line=line, how=how
        )
        if col is None:
            raise MeasurementError(
                f"missing column: the first line (line {marker.line}) says time_base=rig, "
                f"which needs the columns {', '.join(needed)} (as gearsim hil to-csv writes them)",
                file=shown,
                line=line,
                column=name,
            )
        col.unit_of = unit_of
        found.append(col)
    return found


def _check_time_base(
    meas: Measurement, marker: _Marker, notes: _Notes, shown: str, line_of: Callable[[int], int]
) -> RecordedTimeBase | None:
    """The time base to keep on the measurement, once its rows are checked
    against it: a warning for a wall-clock CSV, the rig steps per row for a
    rig-time one."""
    base = marker.time_base
    if not base.is_rig:
        notes.warn(
            "the first line says time_base=wall: this CSV was resampled from a wall-clock "
            "log and cannot reproduce the run step for step; record with 'gearsim hil run "
            "--log' (rig time) instead"
        )
        return base
    if any(n.startswith("resampled") for n in meas.notes):
        notes.warn(
            "the rig-time rows were resampled: the model is stepped once per row, not per "
            "rig step as the first line says"
        )
        return None
    ratio = meas.dt / base.rig_dt
    steps = round(ratio)
    if steps < 1 or abs(ratio - steps) > _SUBSTEP_TOLERANCE * steps:
        raise MeasurementError(
            f"rig_dt={base.rig_dt!r} in the gearsim hil to-csv line does not divide the row "
            f"step {meas.dt:.9g} s into whole rig steps (ratio {ratio:.9g})",
            file=shown,
            line=marker.line,
        )
    _check_inputs_since(meas, base.rig_dt, shown, line_of)
    notes.info(
        f"rig time (line {marker.line}): the model is stepped every {base.rig_dt:g} s, "
        f"{steps} steps per row"
        + (f", with {', '.join(base.held)} held as the rig applied them" if base.held else "")
    )
    return replace(base, steps_per_row=steps)


def _check_inputs_since(
    meas: Measurement, rig_dt: float, shown: str, line_of: Callable[[int], int]
) -> None:
    """Each row's inputs_since lies in the interval that ends at the row (half
    a rig step of slack for the rounding of the text)."""
    since = meas[INPUTS_SINCE]
    outside = (since < meas.time - meas.dt - 0.5 * rig_dt) | (since > meas.time + 0.5 * rig_dt)
    if outside.any():
        r = int(np.nonzero(outside)[0][0])
        raise MeasurementError(
            f"inputs_since {float(since[r])!r} s is outside the row's interval "
            f"({float(meas.time[r] - meas.dt)!r} s to {float(meas.time[r])!r} s)",
            file=shown,
            line=line_of(r),
            column=INPUTS_SINCE,
        )


def _hz(f: float) -> str:
    for scale, unit in ((1e6, "MHz"), (1e3, "kHz"), (1.0, "Hz")):
        if f >= scale:
            return f"{f / scale:.3g} {unit}"
    return f"{f:.3g} Hz"


def _check_time_scale(t: np.ndarray, tcol: _Column, notes: _Notes) -> None:
    """Warns when a time column without unit steps like milliseconds or
    microseconds (a median step of 0.5 or more: 2 Hz or slower if seconds)."""
    if t.size < 2:
        return
    d = np.diff(t)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return
    med = float(np.median(d))
    if not (np.isfinite(med) and med >= 0.5):
        return
    name = _name_unit(tcol.header)[0]
    notes.warn(
        f"time column '{tcol.shown}' has no unit and steps by {med:g} (median): "
        f"{_hz(1.0 / med)} sampling if in seconds, {_hz(1e3 / med)} if milliseconds, "
        f"{_hz(1e6 / med)} if microseconds; if it is not in seconds, write the unit in the "
        f"header ('{printable(name, 40)} [ms]' or '{printable(name, 40)} [us]')"
    )


def _parse_fast(
    data: bytes, start: int, usecols: list[int], sep: str, dec: str
) -> np.ndarray | None:
    """The numeric table by pandas' C parser (about 3x faster than a Python loop
    on a million rows), or None when pandas is missing or the text is not
    plain numbers (empty cells, text, nan/inf, short rows): the slow path then
    parses it and locates any bad cell."""
    if sep == dec:
        return None
    try:
        import pandas as pd
    except ImportError:
        return None
    buf = io.BytesIO(data)  # shares the bytes; reading starts at the body
    buf.seek(start)
    try:
        frame = pd.read_csv(
            buf,
            header=None,
            sep=sep,
            decimal=dec,
            usecols=sorted(set(usecols)),
            dtype=float,
            na_filter=False,
            engine="c",
            encoding="latin-1",
        )
    except (ValueError, TypeError, IndexError, OverflowError, pd.errors.ParserError):
        return None
    # pandas orders usecols by position; the callers expect the given order
    order = sorted(set(usecols))
    table = frame[order].to_numpy(dtype=float)
    return np.ascontiguousarray(table[:, [order.index(c) for c in usecols]])


def _parse_slow(
    body: bytes,
    first_line: int,
    wanted: list[_Column],
    sep: str,
    dec: str,
    ncols: int,
    shown: str,
    how: str,
) -> tuple[np.ndarray, list[int]]:
    """Parses row by row; raises at the first short row or bad cell.
    Returns the table and the file line of each row."""
    need = max(c.index for c in wanted)
    rows: list[list[float]] = []
    lines: list[int] = []
    text = _decode(body)
    for k, line in enumerate(_EOL_TEXT.split(text)):
        if not line.strip():
            continue
        lineno = first_line + k
        row = _split(line, sep)
        if len(row) <= need:
            missing = [c for c in wanted if c.index >= len(row)]
            raise MeasurementError(
                f"row has {len(row)} field{'s' if len(row) != 1 else ''}, the header has "
                f"{ncols}; no value for this column{how}",
                file=shown,
                line=lineno,
                column=missing[0].shown,
            )
        values: list[float] = []
        for c in wanted:
            cell = row[c.index].strip()
            try:
                values.append(float(cell.replace(",", ".") if dec == "," else cell))
            except ValueError:
                what = "is empty" if not cell else f"'{printable(cell, 30)}' is not a number"
                raise MeasurementError(
                    what + how, file=shown, line=lineno, column=c.shown
                ) from None
        rows.append(values)
        lines.append(lineno)
    table = np.array(rows, dtype=float).reshape(len(rows), len(wanted))
    return table, lines


def _validate(
    table: np.ndarray,
    names: list[str],
    spec: RigSpec,
    path: str,
    *,
    resample: bool,
    max_gap: int | None = None,
    line_of,
    source_names: Mapping[str, str] | None = None,
    shown: str | None = None,
) -> Measurement:
    """Checks the table; `path` goes into the Measurement, `shown` (the
    printable file name, default `path`) into messages."""
    source_names = source_names or {}
    where = shown if shown is not None else path
    n = table.shape[0]

    def refuse_first(bad: np.ndarray, message: Callable[[float], str]) -> None:
        """Raise naming the first cell (in row order) where bad is set."""
        if bad.any():
            bad_rows, bad_cols = np.nonzero(bad)
            r, c = int(bad_rows[0]), int(bad_cols[0])
            raise MeasurementError(
                message(float(table[r, c])),
                file=where,
                line=line_of(r),
                column=source_names.get(names[c], names[c]),
            )

    refuse_first(~np.isfinite(table), lambda v: f"value {v!r} is not finite")
    refuse_first(
        np.abs(table) > MAX_MAGNITUDE,
        lambda v: (
            f"value {v:.6g} is beyond the supported magnitude "
            f"{MAX_MAGNITUDE:g} (SI units): a logging or unit error?"
        ),
    )
    t = table[:, names.index("time")]
    tname = source_names.get("time", "time")
    if n < MIN_SAMPLES:
        raise MeasurementError(f"has {n} samples; at least {MIN_SAMPLES} are needed", file=where)
    d = np.diff(t)
    bad = np.nonzero(d <= 0.0)[0]
    if bad.size:
        r = int(bad[0]) + 1
        raise MeasurementError(
            f"time {float(t[r])!r} s is not after the previous sample ({float(t[r - 1])!r} "
            "s); time must increase strictly",
            file=where,
            line=line_of(r),
            column=tname,
        )
    # uniform grid by least squares: t_i ~ t0 + i*dt
    i = np.arange(n, dtype=float)
    dt = float((t[-1] - t[0]) / (n - 1))
    dev = t - (t[0] + i * dt)
    notes: list[str] = []
    worst = int(np.argmax(np.abs(dev)))
    data = {name: table[:, j].copy() for j, name in enumerate(names)}
    med = float(np.median(d))
    if abs(dev[worst]) > 0.5 * dt or np.any(np.abs(d - med) > 0.5 * med):
        if not resample:
            # name the first interval that breaks the grid
            far = np.nonzero(np.abs(d - med) > 0.5 * med)[0]
            r = int(far[0]) + 1 if far.size else worst
            raise MeasurementError(
                f"sampling is not uniform: the step before this sample is {d[r - 1]:.6g} s, "
                "the median step "
                f"is {med:.6g} s (gearsim runs at a fixed step; resample the file or pass "
                "--resample)",
                file=where,
                line=line_of(r),
                column=tname,
            )
        dt = med
        gaps = sampling_gaps(t, med)
        too_long = [g for g in gaps if max_gap and g.missing > max_gap]
        if too_long:
            g = too_long[0]
            raise MeasurementError(
                f"--resample would interpolate across {describe_gap(g)}, more than "
                f"--max-gap {max_gap} samples; cut the record there, or raise --max-gap "
                "(0: no limit)",
                file=where,
                line=line_of(g.index + 1),
                column=tname,
            )
        if gaps:
            more = f" and {len(gaps) - 1} more" if len(gaps) > 1 else ""
            notes.append(f"interpolated across {describe_gap(gaps[0])}{more}")
        m = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
        grid = t[0] + np.arange(m) * dt
        data = {
            name: (grid if name == "time" else np.interp(grid, t, col))
            for name, col in data.items()
        }
        notes.append(
            f"resampled {n} samples onto a uniform {dt:.6g} s grid ({m} samples, linear "
            "interpolation)"
        )
        t = grid
    time = data.pop("time")
    return Measurement(spec=spec, time=time, dt=dt, data=data, path=path, notes=tuple(notes))


def write_measurement(path: str | os.PathLike[str], meas: Measurement, *, digits: int = 9) -> None:
    """Write a measurement as a canonical CSV (header row, %.{digits}g values)."""
    names = [*meas.spec.required, *(c for c in OPTIONAL_INPUTS if c in meas.data)]
    cols = [meas.time] + [meas.data[c] for c in names[1:]]
    arr = np.column_stack(cols)
    fmt = f"%.{digits}g"
    with atomic_writer(path, "w", newline="\n") as fh:
        fh.write(",".join(names) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt=fmt)

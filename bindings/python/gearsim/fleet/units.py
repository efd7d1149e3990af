"""Which logs make the fleet: a directory, a glob or a manifest CSV.

Every log becomes a :class:`Unit`: its id, its path and the optional
metadata a manifest gives (line, station, timestamp). Everything here runs
on the client and checks the fleet as a whole before any work starts: a
missing directory, a glob that matches nothing, a manifest row without a
unit id or with a timestamp that cannot be read end the command with exit
status 2 and one line naming the file, row and column
(:class:`FleetInputError`). A log that a manifest names but that does not
exist is not a fleet-level problem: that unit gets an error row, the others
run (docs/fleet.md, "When a unit fails").
"""

from __future__ import annotations

import csv
import glob as globmod
import hashlib
import io
import os
from dataclasses import dataclass
from datetime import UTC, datetime

from .._outputs import printable
from ..errors import InputError

__all__ = [
    "Unit",
    "FleetInputError",
    "LOG_SUFFIXES",
    "MANIFEST_COLUMNS",
    "find_units",
    "content_hash",
    "unit_id_of",
]

#: What a log file in a directory or a glob is called: a measurement CSV
#: (docs/measurement-format.md), plain or compressed.
LOG_SUFFIXES = (".csv", ".tsv", ".txt")
COMPRESSED_SUFFIXES = (".gz", ".bz2", ".xz", ".zst")
#: The manifest's columns: `unit` and `path` are required, the rest optional.
#: Other columns are ignored.
MANIFEST_COLUMNS = ("unit", "path", "line", "station", "timestamp")
_HASH_CHUNK = 1 << 20


class FleetInputError(InputError):
    """The fleet as a whole cannot be read: exit status 2 with this one line."""


@dataclass(frozen=True)
class Unit:
    """One log of the fleet. index: its place in the input order (the
    Parquet file's row order); timestamp: UTC, naive when the manifest gave
    naive times (they are then taken as they are)."""

    index: int
    unit: str
    path: str
    line: str | None = None
    station: str | None = None
    timestamp: datetime | None = None


def unit_id_of(path: str) -> str:
    """The file name without its log suffixes: unit-0007.csv.gz -> unit-0007."""
    name = os.path.basename(path)
    low = name.lower()
    for comp in COMPRESSED_SUFFIXES:
        if low.endswith(comp):
            name, low = name[: -len(comp)], low[: -len(comp)]
            break
    for suffix in LOG_SUFFIXES:
        if low.endswith(suffix):
            return name[: -len(suffix)]
    return name


def _is_log(name: str) -> bool:
    if name.startswith("."):
        return False
    low = name.lower()
    for comp in ("", *COMPRESSED_SUFFIXES):
        for suffix in LOG_SUFFIXES:
            if low.endswith(suffix + comp):
                return True
    return False


def _check_unique(units: list[Unit], where: str) -> None:
    seen: dict[str, Unit] = {}
    for u in units:
        if u.unit in seen:
            raise FleetInputError(
                f"{where}: unit id '{printable(u.unit)}' twice ({printable(seen[u.unit].path)} "
                f"and {printable(u.path)}); every unit needs its own id (a manifest gives them)"
            )
        seen[u.unit] = u


def _from_paths(paths: list[str], where: str) -> list[Unit]:
    units = [Unit(i, unit_id_of(p), p) for i, p in enumerate(paths)]
    _check_unique(units, where)
    return units


def _from_directory(directory: str) -> list[Unit]:
    try:
        names = sorted(os.listdir(directory))
    except OSError as exc:
        raise FleetInputError(
            f"{printable(directory)}: cannot list the directory ({exc.strerror or exc})"
        ) from None
    paths = [
        os.path.join(directory, n)
        for n in names
        if _is_log(n) and os.path.isfile(os.path.join(directory, n))
    ]
    if not paths:
        raise FleetInputError(
            f"{printable(directory)}: no log in the directory (files ending in "
            f"{', '.join(LOG_SUFFIXES)}, optionally compressed)"
        )
    return _from_paths(paths, printable(directory))


def _from_glob(pattern: str) -> list[Unit]:
    paths = sorted(p for p in globmod.glob(pattern, recursive=True) if os.path.isfile(p))
    if not paths:
        raise FleetInputError(f"{printable(pattern)}: no file matches the pattern")
    return _from_paths(paths, printable(pattern))


def _parse_time(text: str, where: str) -> datetime:
    """ISO 8601 (a trailing Z is UTC) or seconds since 1970-01-01 UTC."""
    s = text.strip()
    try:
        return datetime.fromtimestamp(float(s), tz=UTC)
    except (ValueError, OverflowError, OSError):
        pass
    try:
        t = datetime.fromisoformat(s)
    except ValueError:
        raise FleetInputError(
            f"{where}: timestamp '{printable(s, 60)}' is neither ISO 8601 "
            "(2026-11-26T08:15:00Z) nor seconds since 1970"
        ) from None
    return t.astimezone(UTC) if t.tzinfo is not None else t


def _read_manifest(path: str) -> list[Unit]:
    shown = printable(path)
    try:
        raw = open(path, "rb").read()
    except OSError as exc:
        raise FleetInputError(
            f"{shown}: cannot read the manifest ({exc.strerror or exc})"
        ) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FleetInputError(
            f"{shown}: the manifest is not UTF-8 text (byte {exc.start})"
        ) from None
    if "\x00" in text:
        raise FleetInputError(f"{shown}: the manifest is not text (NUL bytes)")
    rows = csv.reader(io.StringIO(text, newline=""))
    header = next(rows, None)
    if not header or not any(h.strip() for h in header):
        raise FleetInputError(f"{shown}: the manifest is empty; its first line names the columns")
    names = [h.strip().lower() for h in header]
    for need in ("unit", "path"):
        if need not in names:
            raise FleetInputError(
                f"{shown}, line 1: the manifest has no column '{need}' (columns: unit, path, "
                "and optionally line, station, timestamp)"
            )
    col = {n: names.index(n) for n in MANIFEST_COLUMNS if n in names}
    base = os.path.dirname(os.path.abspath(path))
    units: list[Unit] = []
    seen: dict[str, int] = {}
    aware: tuple[bool, int] | None = None
    for lineno, row in enumerate(rows, start=2):
        if not row or all(not c.strip() for c in row):
            continue  # blank line
        if len(row) < len(names):
            raise FleetInputError(
                f"{shown}, line {lineno}: {len(row)} cells, the header has {len(names)}"
            )

        def cell(name: str, row: list[str] = row) -> str | None:
            v = row[col[name]].strip() if name in col else ""
            return v or None

        unit, rel = cell("unit"), cell("path")
        for name, value in (("unit", unit), ("path", rel)):
            if value is None:
                raise FleetInputError(f"{shown}, line {lineno}, column '{name}': empty")
        if unit in seen:
            raise FleetInputError(
                f"{shown}, line {lineno}, column 'unit': '{printable(unit)}' already on line "
                f"{seen[unit]}"
            )
        seen[unit] = lineno
        stamp = None
        if cell("timestamp") is not None:
            stamp = _parse_time(cell("timestamp"), f"{shown}, line {lineno}, column 'timestamp'")
            if aware is None:
                aware = (stamp.tzinfo is not None, lineno)
            elif aware[0] != (stamp.tzinfo is not None):
                raise FleetInputError(
                    f"{shown}, line {lineno}, column 'timestamp': "
                    f"{'with' if stamp.tzinfo else 'without'} a time zone, line {aware[1]} "
                    f"{'with' if aware[0] else 'without'}; give all with one or all without"
                )
        log = rel if os.path.isabs(rel) else os.path.join(base, rel)
        units.append(Unit(len(units), unit, log, cell("line"), cell("station"), stamp))
    if not units:
        raise FleetInputError(f"{shown}: the manifest lists no unit (only its header)")
    return units


def find_units(source: str | None = None, *, manifest: str | None = None) -> list[Unit]:
    """The units of a fleet: `source` a directory (its logs, not recursive,
    sorted by name) or a glob pattern (``**`` recurses), or `manifest` a CSV
    with the columns of MANIFEST_COLUMNS (paths relative to the manifest's
    directory). Raises FleetInputError."""
    if (source is None) == (manifest is None):
        raise FleetInputError("give either a directory or glob, or a manifest")
    if manifest is not None:
        if not os.path.isfile(manifest):
            raise FleetInputError(f"{printable(manifest)}: no such manifest file")
        return _read_manifest(manifest)
    if os.path.isdir(source):
        return _from_directory(source)
    if any(ch in source for ch in "*?["):
        return _from_glob(source)
    if os.path.isfile(source):
        return _from_paths([source], printable(source))
    raise FleetInputError(f"{printable(source)}: no such directory or file, and not a glob pattern")


def content_hash(path: str) -> str | None:
    """sha256 of the file's bytes (hex); None when it cannot be read (the
    unit's own analysis then reports why)."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(_HASH_CHUNK):
                h.update(chunk)
    except OSError:
        return None
    return h.hexdigest()

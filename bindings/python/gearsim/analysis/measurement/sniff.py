"""The sniff stage: where the header is, how the rows are split (separator,
decimal mark), and which header column holds each canonical column (by name,
by unit-stripped name, case-folded, or as the user mapped it, with a factor)."""

from __future__ import annotations

import csv
import re
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..._outputs import printable
from ...columns import RIG_TIME_MARKER
from ..errors import MeasurementError
from .record import OPTIONAL_INPUTS, Notes, RigSpec
from .source import Text, decode, iter_lines

_SEPARATORS = (",", ";", "\t")
_SEP_NAMES = {",": "','", ";": "';'", "\t": "tab", "|": "'|'"}
_NUM_START = re.compile(r"^\s*\"?[-+]?(?:\d|\.\d)")
_SEP_LINE = re.compile(r"^\s*\"?sep=(.)\"?[ ,;]*$", re.IGNORECASE)
_COMMA_NUMBER = re.compile(r"^\s*[-+]?\d*,\d+(?:[eE][-+]?\d+)?\s*$")
_DOT_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.\d*|\.\d+)(?:[eE][-+]?\d+)?\s*$")
_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_FACTOR = re.compile(rf"^(?P<name>.*?)\s*\*\s*(?P<factor>{_FLOAT})$")
_UNIT = re.compile(r"^(?P<name>.*?\S)\s*(?:\[(?P<a>[^\[\]]*)\]|\((?P<b>[^()]*)\))$")


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


def check_column_map(
    columns: Mapping[str, str] | None, spec: RigSpec, shown: str
) -> dict[str, str]:
    """The mapping as a dict; a key that is not a column of the rig is an error."""
    columns = dict(columns or {})
    for key in columns:
        if key not in spec.required + OPTIONAL_INPUTS:
            raise MeasurementError(
                f"column mapping names '{printable(key, 40)}', which is not a column of the "
                f"{spec.block} rig ({', '.join(spec.required + OPTIONAL_INPUTS)})",
                file=shown,
            )
    return columns


def split(line: str, sep: str) -> list[str]:
    if '"' not in line:
        return line.split(sep)
    try:
        return next(csv.reader([line], delimiter=sep))
    except (csv.Error, StopIteration):
        return line.split(sep)


def _clean_header(h: str) -> str:
    h = h.replace("\ufeff", "").strip().strip('"').strip("'").strip()
    return unicodedata.normalize("NFC", h)


def name_unit(h: str) -> tuple[str, str | None]:
    """'time [ms]' -> ('time', 'ms'); 'time' -> ('time', None)."""
    m = _UNIT.match(h)
    if not m:
        return h, None
    unit = (m.group("a") if m.group("a") is not None else m.group("b")).strip()
    if unit in ("", "-"):
        return m.group("name").strip(), None
    return m.group("name").strip(), unit


@dataclass
class Header:
    line: int  # 1-based line number of the header
    text: str
    body_start: int  # byte offset of the first line after the header
    body_line: int  # line number of that line
    sep: str | None  # from an Excel "sep=" line
    commented: bool


def find_header(data: bytes, shown: str, inside: str) -> Header:
    sep_hint: str | None = None
    comments: list[tuple[int, str, int]] = []
    for lineno, _start, raw, nxt in iter_lines(data):
        text = decode(raw)
        s = text.strip().lstrip("\ufeff")
        if not s:
            continue
        m = _SEP_LINE.match(text.lstrip("\ufeff"))
        if m and sep_hint is None and not comments:
            sep_hint = m.group(1)
            continue
        if s.startswith(RIG_TIME_MARKER):
            continue  # facts about the rows (see rig_time.read_marker), never a header
        if s.startswith("#"):
            comments.append((lineno, s, nxt))
            continue
        if comments and _NUM_START.match(s):
            # numbers right after comment lines: the last comment is the header
            c_line, c_text, c_next = comments[-1]
            return Header(c_line, c_text.lstrip("#").strip(), c_next, c_line + 1, sep_hint, True)
        return Header(lineno, text, nxt, lineno + 1, sep_hint, False)
    if comments:
        raise MeasurementError(f"has only comment lines, no header row{inside}", file=shown)
    raise MeasurementError(f"is empty, no header row{inside}", file=shown)


def _sample_lines(data: bytes, start: int, first_line: int, count: int = 50) -> list[str]:
    out: list[str] = []
    for _ln, _s, raw, _n in iter_lines(data, start, first_line - 1):
        text = decode(raw)
        if text.strip():
            out.append(text)
            if len(out) >= count:
                break
    return out


def _sniff_separator(header: str, sample: list[str]) -> str:
    best, best_key = ",", None
    for sep in _SEPARATORS:
        nh = len(split(header, sep))
        counts = [len(split(s, sep)) for s in sample]
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
        row = split(s, sep)
        for i in indices:
            if i < len(row):
                if _COMMA_NUMBER.match(row[i]):
                    comma += 1
                elif _DOT_NUMBER.match(row[i]):
                    dot += 1
    return "," if comma and not dot else "."


# ------------------------------------------------------------------ columns and units


@dataclass(frozen=True)
class Layout:
    """Where the rows of a file are and how to split them."""

    header: Header
    fields: list[str]  # the header cells, cleaned
    sample: list[str]  # the first non-blank lines after the header
    sep: str
    dec: str = "."
    how: str = ""  # " with separator ';' and decimal comma" ("": the defaults), for messages


def find_layout(text: Text, shown: str) -> Layout:
    """The header line, its cells and the separator."""
    hdr = find_header(text.data, shown, text.inside)
    sample = _sample_lines(text.data, hdr.body_start, hdr.body_line)
    sep = hdr.sep or _sniff_separator(hdr.text, sample)
    fields = [_clean_header(h) for h in split(hdr.text.rstrip("\r\n"), sep)]
    how = "" if sep == "," else f" with separator {_SEP_NAMES.get(sep, repr(sep))}"
    return Layout(hdr, fields, sample, sep, how=how)


def find_columns(
    layout: Layout, spec: RigSpec, columns: Mapping[str, str], shown: str
) -> list[Column]:
    """The header column of every canonical column of the rig the file has
    (all the required ones, the optional ones present or mapped)."""
    wanted: list[Column] = []
    for canonical in spec.required + OPTIONAL_INPUTS:
        col = resolve(
            canonical,
            columns.get(canonical),
            layout.fields,
            spec=spec,
            shown=shown,
            line=layout.header.line,
            how=layout.how,
        )
        if col is not None:
            wanted.append(col)
    return wanted


def number_format(layout: Layout, wanted: list[Column], notes: Notes) -> Layout:
    """The layout with the decimal mark of the wanted columns; notes how the
    file is read when that is not the default."""
    dec = _sniff_decimal(layout.sample, layout.sep, [c.index for c in wanted])
    how = layout.how
    if dec == ",":
        how += " and decimal comma" if how else " with decimal comma"
    if how:
        notes.info("read" + how)
    if layout.header.commented:
        notes.info(f"header taken from the comment line {layout.header.line}")
    return replace(layout, dec=dec, how=how)


@dataclass
class Column:
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


def resolve(
    canonical: str,
    mapped: str | None,
    fields: list[str],
    *,
    spec: RigSpec,
    shown: str,
    line: int,
    how: str,
) -> Column | None:
    """Finds the header column of `canonical` (mapped or not); None when an
    optional column is absent. Raises on missing, ambiguous or duplicated."""
    source = unicodedata.normalize("NFC", mapped) if mapped is not None else canonical
    parsed = [name_unit(h) for h in fields]
    fm = _FACTOR.match(source) if mapped is not None else None
    for hits, factor in _attempts(source, fm, fields, parsed):
        if hits:
            return _column(canonical, hits, factor, fm, fields, parsed, shown, line)
    if mapped is not None:
        _check_factor_text(canonical, source, fields, parsed, shown)
    if canonical not in spec.required and mapped is None:
        return None
    raise _missing(canonical, mapped, source, fields, spec, shown, line, how)


def _exact(fields: list[str], text: str) -> list[int]:
    return [i for i, h in enumerate(fields) if h == text]


def _bare(parsed: list[tuple[str, str | None]], text: str, fold: bool = False) -> list[int]:
    if fold:
        return [i for i, (n, _u) in enumerate(parsed) if n.casefold() == text.casefold()]
    return [i for i, (n, _u) in enumerate(parsed) if n == text]


def _attempts(
    source: str,
    fm: re.Match[str] | None,
    fields: list[str],
    parsed: list[tuple[str, str | None]],
) -> list[tuple[list[int], float | None]]:
    """The header columns `source` may name, best first, each with the
    mapping's factor when it was read off `source`: the header text as it is,
    the name without its unit, the name case-folded."""
    attempts: list[tuple[list[int], float | None]] = [(_exact(fields, source), None)]
    if fm:
        attempts.append((_exact(fields, fm.group("name")), float(fm.group("factor"))))
    attempts.append((_bare(parsed, source), None))
    if fm:
        attempts.append((_bare(parsed, fm.group("name")), float(fm.group("factor"))))
    attempts.append((_bare(parsed, source, fold=True), None))
    return attempts


def _column(
    canonical: str,
    hits: list[int],
    factor: float | None,
    fm: re.Match[str] | None,
    fields: list[str],
    parsed: list[tuple[str, str | None]],
    shown: str,
    line: int,
) -> Column:
    """The one column of `hits`; several are an error (the same header twice,
    or names that all fit)."""
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
    col = Column(canonical, i, fields[i], unit=parsed[i][1])
    if factor is not None and fm is not None:  # a factor is only read off the mapping fm
        if not np.isfinite(factor) or factor == 0.0:
            raise MeasurementError(
                f"scale factor '{printable(fm.group('factor'))}' of the mapping for "
                f"'{canonical}' must be finite and non-zero",
                file=shown,
                column=canonical,
            )
        col.factor, col.explicit_factor = factor, True
    return col


def _check_factor_text(
    canonical: str,
    source: str,
    fields: list[str],
    parsed: list[tuple[str, str | None]],
    shown: str,
) -> None:
    """A mapping 'HEADER*TEXT' whose HEADER is in the header: TEXT is not a number."""
    name, star, factor_text = source.rpartition("*")
    if star and (_exact(fields, name.strip()) or _bare(parsed, name.strip())):
        raise MeasurementError(
            f"scale factor '{printable(factor_text.strip(), 30)}' of the mapping for "
            f"'{canonical}' is not a number",
            file=shown,
            column=canonical,
        )


def _missing(
    canonical: str,
    mapped: str | None,
    source: str,
    fields: list[str],
    spec: RigSpec,
    shown: str,
    line: int,
    how: str,
) -> MeasurementError:
    """The error for a column the header lacks: what the header has, and a
    hint when the header row looks wrong."""
    have = ", ".join(f"'{printable(h, 40)}'" for h in fields[:12] if h) or "none"
    if len(fields) > 12:
        have += f", ... ({len(fields) - 12} more)"
    hint = _header_hint(fields, how)
    if canonical not in spec.required:
        return MeasurementError(
            f"mapped column '{printable(source, 60)}' is not in the header; "
            f"the header has {have}{hint}",
            file=shown,
            line=line,
            column=printable(source, 60),
        )
    what = f" (mapped from '{printable(source, 60)}')" if mapped is not None else ""
    return MeasurementError(
        f"missing column{what}; the {spec.block} rig needs {', '.join(spec.required)}; "
        f"the header has {have}{hint}",
        file=shown,
        line=line,
        column=printable(source, 60),
    )


def _header_hint(fields: list[str], how: str) -> str:
    if fields and all(_NUM_START.match(h) for h in fields if h):
        return " (that line holds numbers: the file has no header row?)"
    if len(fields) == 1:
        return " (one field only: is the separator something else than ',', ';' or tab?)"
    if how:
        return f" (read{how})"
    return ""
